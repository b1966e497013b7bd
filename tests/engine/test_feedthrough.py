"""Feed-through resolved at each communication point (Algorithm.feedthrough, issue 29): after
each macro step the outputs that depend on inputs at the same communication point (their FMUs'
declared dependencies) are read again, in dependency order, with those inputs at their sources'
new values, as OMSimulator's master does. The kernel equals the Python oracle bit for bit with it;
an algebraic loop of such outputs is refused with its members named; and what it changes is
measured: on the Meng scene at order 0 the leg references no longer reach the drives one step late."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import oracle
from cosim.engine import Algorithm, Component, Connection, EnergyControl, FixedStep, StepDoubling
from cosim.engine.execution import Execution
from cosim.engine.coupling import FeedthroughLoop
from cosim.engine.structure import SystemStructure
from cosim.engine.artifacts import ROOT, fmu_path
from cosim.platform.run.compile import scene_record, scene_structure
from cosim.platform.scene import load_scene
from cosim.platform.ports import platform_algorithm
from test_coupling import oscillator
from test_kernel import assert_equal, both


@pytest.mark.parametrize("control", [FixedStep(1e-2), StepDoubling(1e-2, rtol=1e-2, atol=1e-3),
                                     EnergyControl(1e-2, rtol=1e-2, atol=1e-4, h_min=1e-4)], ids=["fixed", "doubling", "energy"])
@pytest.mark.parametrize("kind,order", [("jacobi", 0), ("jacobi", 1), ("jacobi", 2), ("gauss-seidel", 0),
                                        ("gauss-seidel", 1)])
def test_kernel_equals_the_oracle_with_feedthrough_on_the_oscillator(kind, order, control):
    """The coupling FMU's force feeds through from the mass's position and velocity."""
    settings = Algorithm(kind, order, ("coupling", "mass") if kind == "gauss-seidel" else None, feedthrough=True)
    record, names = [("mass", "position"), ("coupling", "force")], ["x1", "force"]
    reference, result, execution, failure = both(oscillator(), settings, control, 1.0, record, names, "mass")
    assert failure is None and reference.failure is None
    assert_equal(reference, result, execution, names)


@pytest.mark.parametrize("algorithm,order", [("jacobi", 0), ("gauss-seidel", 1), ("jacobi", 2)])
def test_kernel_equals_the_oracle_with_feedthrough_on_the_meng_scene(algorithm, order):
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"coupling.algorithm": algorithm, "coupling.order": order,
                                                            "outputs.mechanics": ["leg[1].angle_ref"],
                                                            "outputs.drive": ["speed"]})
    record, names = scene_record(scene)
    settings = dataclasses.replace(platform_algorithm("pmsm", algorithm, order), feedthrough=True)
    reference, result, execution, failure = both(scene_structure(scene), settings, FixedStep(scene.step), 0.4,
                                                 record, names, "mechanics")
    assert failure is None
    assert_equal(reference, result, execution, names)


def run(structure, settings, control, stop, record):
    with Execution(structure, settings, control, record) as execution:
        return execution.run(stop)


def test_at_order_0_the_references_arrive_at_the_same_communication_point():
    """Order-0 Jacobi on the Meng scene: without the resolution the mechanics' leg[1].angle_ref
    recorded at t is the inverse kinematics of pose_ref at t - h (the mechanics stepped with the
    input held at t - h); with it, of pose_ref at t. Checked against the trajectory's own output."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    structure = scene_structure(scene)
    record = [("trajectory", "pose_ref.z"), ("mechanics", "leg[1].angle_ref"), ("mechanics", "leg[1].length_ref")]
    plain = platform_algorithm("pmsm", "jacobi", 0)
    late = run(structure, plain, FixedStep(1e-3), 0.3, record)
    resolved = run(structure, dataclasses.replace(plain, feedthrough=True), FixedStep(1e-3), 0.3, record)
    from cosim.platform.core import Core
    from cosim.platform.run.compile import scene_values
    from cosim.platform.scene.signals import sine_motion
    core = Core().use_start_values(scene_values(scene)[0])
    t = resolved["time"][1:]
    pose_now = sine_motion(scene.trajectory, t)[0]
    pose_before = sine_motion(scene.trajectory, t - 1e-3)[0]
    now = np.array([core.leg_lengths(p)[0] for p in pose_now])
    before = np.array([core.leg_lengths(p)[0] for p in pose_before])
    np.testing.assert_allclose(resolved["mechanics.leg[1].length_ref"][1:], now, atol=1e-12)
    np.testing.assert_allclose(late["mechanics.leg[1].length_ref"][1:], before, atol=1e-12)
    assert np.max(np.abs(now - before)) > 1e-5  # the step's delay is visible at this motion


def test_an_algebraic_loop_is_refused_with_its_members():
    """Two spring-damper FMUs whose forces feed each other's positions: each force depends on the
    other's at the same communication point."""
    coupling = fmu_path("oscillator_coupling", test=True)
    loop = SystemStructure("loop", [Component("a", coupling), Component("b", coupling)],
                           [Connection(("a", "force"), ("b", "position_1")), Connection(("b", "force"), ("a", "position_1"))])
    with pytest.raises(FeedthroughLoop, match=r"an algebraic loop: the outputs a\.force, b\.force depend on each other"):
        Execution(loop, Algorithm("jacobi", 0, feedthrough=True), FixedStep(1e-3), [("a", "force")])
    with Execution(loop, Algorithm("jacobi", 0), FixedStep(1e-3), [("a", "force")]) as execution:  # off: it runs
        assert len(execution.run(0.01)) == 11


def test_the_setting_travels_in_the_ssp_annotation_and_the_scene():
    from cosim.engine.settings import from_strings, to_strings
    algorithm = Algorithm("jacobi", 0, feedthrough=True)
    assert from_strings(to_strings(algorithm, FixedStep(1e-3)), 1e-3)[0] == algorithm
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"coupling.feedthrough": True})
    assert scene.algorithm.feedthrough
