"""The step kernel (cosim/engine/kernel/kernel.c) against the Python oracle (tests/oracle.py) it
must equal: the same numbers bit for bit for every algorithm, order and step control, on the
oscillator and on the whole platform system, and the same failure handling."""

from __future__ import annotations


import numpy as np
import pytest

import oracle
from cosim.engine import (Algorithm, EnergyControl, FixedStep, FmuError, RecordFull, RunFailed,
                          StepDoubling, SystemStructure)
from cosim.engine.execution import Execution
from cosim.engine.artifacts import ROOT
from cosim.platform.run.compile import scene_record, scene_structure
from cosim.platform.scene import load_scene
from cosim.platform.scene.parameter_sets import mechanics_start_values
from cosim.platform.scene.signals import scene_trajectory
from cosim.platform.ports import platform_algorithm
from cosim.platform.run.system import platform_structure
from test_coupling import oscillator


def both(structure: SystemStructure, settings: Algorithm, control, stop: float, record, names, clock: str):
    """(oracle run, kernel result, kernel execution, kernel failure)."""
    reference = oracle.run(structure, settings, control, stop, record, clock)
    execution = Execution(structure, settings, control, record, names, clock=clock)
    failure = None
    try:
        result = execution.run(stop)
    except RunFailed as failed:
        result, failure = failed.result, failed.error
    finally:
        execution.free()
    return reference, result, execution, failure


def assert_equal(reference, result, execution, names) -> None:
    assert np.array_equal(reference.rows[:, 0], result["time"])
    for k, name in enumerate(names, start=1):
        assert np.array_equal(reference.rows[:, k], result[name]), name
    assert reference.residuals == execution.energy_residuals.tolist()
    assert reference.steps == execution.steps.tolist()
    assert reference.rejected == execution.rejected


@pytest.mark.parametrize("control", [FixedStep(1e-2), StepDoubling(1e-2, rtol=1e-2, atol=1e-3),
                                     EnergyControl(1e-2, rtol=1e-2, atol=1e-4, h_min=1e-4)], ids=["fixed", "doubling", "energy"])
@pytest.mark.parametrize("kind,order", [("jacobi", 0), ("jacobi", 1), ("jacobi", 2), ("gauss-seidel", 0),
                                        ("gauss-seidel", 1), ("gauss-seidel", 2)])
def test_kernel_equals_the_oracle_on_the_oscillator(kind, order, control):
    settings = Algorithm(kind, order, ("coupling", "mass") if kind == "gauss-seidel" else None)
    record, names = [("mass", "position"), ("coupling", "force")], ["x1", "force"]
    reference, result, execution, failure = both(oscillator(), settings, control, 1.0, record, names, "mass")
    assert failure is None and reference.failure is None
    assert_equal(reference, result, execution, names)
    if not isinstance(control, FixedStep):
        assert len(execution.steps) > 5


def test_the_energy_law_s_safety_and_change_limits_reach_the_kernel():
    """ECCO with libcosim's safety factor and change limits (0.99, [0.2, 1.5]) instead of ours
    (1, [0.2, 2]): the kernel equals the oracle under them, and takes other steps than under ours
    (the parameters are the law's, not decoration; the OSP export writes the same ones)."""
    settings, record, names = Algorithm("jacobi", 1), [("mass", "position")], ["x1"]
    theirs = EnergyControl(1e-2, rtol=1e-2, atol=1e-4, h_min=1e-4, safety=0.99, change_max=1.5)
    reference, result, execution, failure = both(oscillator(), settings, theirs, 1.0, record, names, "mass")
    assert failure is None and reference.failure is None
    assert_equal(reference, result, execution, names)
    _, _, ours, _ = both(oscillator(), settings, EnergyControl(1e-2, rtol=1e-2, atol=1e-4, h_min=1e-4), 1.0,
                         record, names, "mass")
    assert max(np.diff(np.log(execution.steps))) <= np.log(1.5) + 1e-12 < max(np.diff(np.log(ours.steps)))


@pytest.mark.parametrize("control", [StepDoubling(1e-2, rtol=1e-9, atol=1e-12, h_min=1e-7),
                                     EnergyControl(1e-2, rtol=1e-9, atol=1e-12, h_min=1e-7)], ids=["doubling", "energy"])
def test_an_adaptive_run_stops_at_its_record_budget_and_keeps_the_rows(control):
    """An adaptive step driven to its minimum could record without bound (a fixed-step run is
    refused up front by its size): past the record budget the run stops, says when, how big and what
    to try, and keeps every row up to there, equal to an unbounded run's."""
    settings, record, names = Algorithm("jacobi", 1), [("mass", "position")], ["x1"]
    with Execution(oscillator(), settings, control, record, names, clock="mass") as free:
        full = free.run(1.0)
    budget_rows = len(full) // 3
    with Execution(oscillator(), settings, control, record, names, clock="mass") as bounded:
        bounded.record_budget = 8.0 * budget_rows * 2  # two columns: time and x1
        with pytest.raises(RunFailed) as failed:
            bounded.run(1.0)
    error, kept = failed.value.error, failed.value.result
    assert isinstance(error, RecordFull) and str(error).startswith(f"the run stopped at t = {error.time:.6g} s:")
    assert "raise the minimum step" in str(error) and error.time < 1.0
    assert budget_rows < len(kept) <= budget_rows + 500  # stopped within the batch that crossed the budget
    assert kept["time"][-1] == error.time
    assert np.array_equal(kept["x1"], full["x1"][:len(kept)]) and np.array_equal(kept["time"], full["time"][:len(kept)])


@pytest.mark.parametrize("kind,order", [("jacobi", 0), ("jacobi", 1), ("gauss-seidel", 1), ("gauss-seidel", 2)])
def test_kernel_equals_the_oracle_with_an_interface_jacobian(kind, order):
    """The oscillator with the coupling FMU's slopes wired to the mass (an output fed back into its
    own FMU's input) and the bond's slope in the energy residual: the same numbers bit for bit."""
    settings = Algorithm(kind, order, ("coupling", "mass") if kind == "gauss-seidel" else None)
    record, names = [("mass", "position"), ("coupling", "force")], ["x1", "force"]
    reference, result, execution, failure = both(oscillator(interface_jacobian=True), settings, FixedStep(1e-2), 1.0,
                                                 record, names, "mass")
    assert failure is None and reference.failure is None
    assert_equal(reference, result, execution, names)


@pytest.mark.parametrize("algorithm,order,interface_jacobian",
                         [("gauss-seidel", 0, False), ("gauss-seidel", 1, False), ("gauss-seidel", 2, False),
                          ("jacobi", 1, False), ("jacobi", 2, False), ("gauss-seidel", 1, True)])
def test_kernel_equals_the_oracle_on_the_meng_scene(algorithm, order, interface_jacobian):
    """The Meng scene (trajectory FMU with exact derivatives, six PMSM drives, mechanics) for 0.6 s,
    across batch boundaries: every recorded value, every energy residual and the final time."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {
        "coupling.algorithm": algorithm, "coupling.order": order, "outputs.mechanics": ["leg[1].length"],
        "outputs.drive": ["speed"], "coupling.interface_jacobian": interface_jacobian})
    record, names = scene_record(scene)
    reference, result, execution, failure = both(scene_structure(scene), platform_algorithm("pmsm", algorithm, order),
                                                 FixedStep(scene.step), 0.6, record, names, "mechanics")
    assert failure is None
    assert_equal(reference, result, execution, names)


def test_kernel_failure_names_the_instance_and_keeps_the_rows():
    """Six linear motors cannot hold the Meng platform: the mechanics fails mid-run; the error names
    it and the call, and the rows kept equal the oracle's up to there."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"drive.kind": "linear", "drive.parameters": {},
                                                            "outputs.drive": ["velocity"]})
    record, names = scene_record(scene)
    # built directly: the scene compiler refuses it up front (the motors cannot hold the legs)
    structure = platform_structure("linear", mechanics_start_values("meng2010"), {}, scene_trajectory(scene))
    reference, result, execution, failure = both(structure, platform_algorithm("linear"), FixedStep(scene.step), 3.0,
                                                 record, names, "mechanics")
    assert isinstance(failure, FmuError) and isinstance(reference.failure, FmuError)
    assert str(failure).startswith("mechanics: fmi2DoStep failed at t = ")
    assert str(failure) == str(reference.failure)
    assert_equal(reference, result, execution, names)
    assert 0.1 < result["time"][-1] < 3.0


@pytest.mark.parametrize("name", ["meng_eq35", "sumnu_case_1"])
def test_kernel_step_doubling_equals_the_oracle_on_the_platform(name):
    """Step doubling on the scene for 0.5 s, rejections included (87 on the Meng scene): the same
    rows, accepted steps, rejections and energy residuals."""
    scene = load_scene(ROOT / "scenes" / f"{name}.toml", {"scene.duration": 0.5, "coupling.step_control": "doubling",
                                                          "coupling.rtol": 1e-3, "coupling.atol": 1e-3})
    record, names = scene_record(scene)
    settings, control = scene.algorithm, scene.control
    reference, result, execution, failure = both(scene_structure(scene), settings, control, 0.5, record, names,
                                                 "mechanics")
    assert failure is None
    assert_equal(reference, result, execution, names)
    assert execution.rejected > 0
