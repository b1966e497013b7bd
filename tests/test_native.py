"""The native inner loop (cosim/native/loop.c) against the Python coupling algorithms it mirrors:
the same numbers bit for bit, and the same failure handling."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.fmus import ROOT
from cosim.parameter_sets import mechanics_start_values
from cosim.scene import load_scene
from cosim.signals import scene_trajectory
from cosim.system import PlatformSystem, RunFailed


def run(scene, order: int, algorithm: str, native: bool, duration: float, drive_values=None):
    system = PlatformSystem(scene.drive, mechanics_start_values(scene.parameter_set, scene.mass_set),
                            drive_values if drive_values is not None else scene.drive_parameters, order, algorithm,
                            scene_trajectory(scene))
    system.record(["leg[1].length"], ["speed" if scene.drive == "pmsm" else "velocity"])
    try:
        rows = system.run(duration, scene.step, native=native, divergence_ratio=None)  # bit for bit, stable or not
        return rows, list(system.algorithm.energy_residuals), system.time
    finally:
        system.free()


@pytest.mark.parametrize("algorithm,order", [("gauss-seidel", 0), ("gauss-seidel", 1), ("gauss-seidel", 2),
                                             ("jacobi", 1), ("jacobi", 2)])
def test_native_loop_equals_the_python_loop_bit_for_bit(algorithm, order):
    """The Meng scene (trajectory FMU with exact derivatives, six PMSM drives, mechanics) for 0.6 s,
    across the 0.5 s batch boundary: every recorded value, every energy residual and the final time
    are identical."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    python = run(scene, order, algorithm, native=False, duration=0.6)
    native = run(scene, order, algorithm, native=True, duration=0.6)
    assert np.array_equal(python[0], native[0])
    assert python[1] == native[1]
    assert python[2] == native[2]


def test_native_failure_names_the_instance_and_keeps_the_rows():
    """Six linear motors cannot hold the Meng platform: the mechanics fails mid-run in the native
    loop; the error names it and the call, and the rows kept equal the Python loop's up to there."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    scene.drive = "linear"
    failures = {}
    for native in (False, True):
        with pytest.raises(RunFailed) as failed:
            run(scene, 1, "gauss-seidel", native, 3.0, drive_values={})
        failures[native] = failed.value
    assert str(failures[True].error).startswith("mechanics: fmi2DoStep failed at t = ")
    assert str(failures[True]) == str(failures[False])
    assert np.array_equal(failures[True].result, failures[False].result)
    assert 0.1 < failures[True].result[-1, 0] < 3.0


@pytest.mark.parametrize("name", ["meng_eq35", "sumnu_case_1"])
def test_native_step_doubling_equals_the_python_controller_bit_for_bit(name):
    """cosim.coupling.AdaptiveStep on the scene for 0.5 s, once in Python and once with its steps
    after the first in C (rejections included: 87 on the Meng scene): the same rows, accepted steps,
    rejections and energy residuals."""
    import dataclasses

    from cosim.runner import step_control

    scene = dataclasses.replace(load_scene(ROOT / "scenes" / f"{name}.toml"), duration=0.5, step_control="doubling",
                                rtol=1e-3, atol=1e-3)
    runs = []
    for native in (False, True):
        system = PlatformSystem(scene.drive, mechanics_start_values(scene.parameter_set, scene.mass_set),
                                scene.drive_parameters, scene.order, scene.algorithm, scene_trajectory(scene))
        control = step_control(scene, system)
        try:
            rows = system.run(scene.duration, scene.step, control, native=native)
            runs.append((rows, list(control.accepted), control.rejected, list(system.algorithm.energy_residuals)))
        finally:
            system.free()
    (rows_a, h_a, rejected_a, e_a), (rows_b, h_b, rejected_b, e_b) = runs
    assert np.array_equal(rows_a, rows_b) and h_a == h_b and rejected_a == rejected_b and e_a == e_b
    assert rejected_a > 0
