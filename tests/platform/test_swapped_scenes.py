"""Any drive on any platform: the shipped swapped scenes (Meng's platform on linear motors, Sumnu's
on PMSMs with ball screws) differ from their papers' scenes in the drive kind alone, run at the
default 1 ms step with drives sized and designed for their legs, and track; the user guide (docs/guide/scenes.md) quotes their
tracking errors and this test holds it to what the runs print. A platform's parameter set gives
every value the mechanics reads, so switching the motor systems on adds nothing of another paper."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT
from cosim.platform.scene.parameter_sets import mechanics_start_values
from cosim.platform.run.compile import scene_structure
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene

SWAPPED = {"meng_eq35_linear": ("meng_eq35", "SWAPPED_MENG", "Meng on linear motors"),
           "sumnu_case_1_pmsm": ("sumnu_case_1", "SWAPPED_SUMNU", "Sumnu case I on PMSMs")}


def quoted(errors: np.ndarray) -> str:
    mm = " / ".join(f"{1e3 * e:.3g}" for e in errors[:3])
    mrad = " / ".join(f"{1e3 * e:.3g}" for e in errors[3:])
    return f"{mm} mm in surge / sway / heave, {mrad} mrad in roll / pitch / yaw"


@pytest.fixture(scope="module")
def runs():
    return {name: run_scene(load_scene(ROOT / "scenes" / f"{name}.toml")) for name in SWAPPED}


@pytest.mark.parametrize("name", SWAPPED)
def test_a_swapped_scene_is_its_papers_scene_with_another_drive_kind(name):
    own = (ROOT / "scenes" / f"{SWAPPED[name][0]}.toml").read_text().splitlines()
    swapped = (ROOT / "scenes" / f"{name}.toml").read_text().splitlines()
    code = [(a, b) for a, b in zip([l for l in own if not l.startswith("#")], [l for l in swapped if not l.startswith("#")])
            if a != b]
    assert [b.split("#")[0].strip() for _, b in code if not b.startswith("name")] == \
           [{"meng_eq35_linear": 'kind = "linear"', "sumnu_case_1_pmsm": 'kind = "pmsm"'}[name]]


def test_the_swapped_drives_come_sized_for_their_legs():
    meng = scene_structure(load_scene(ROOT / "scenes" / "meng_eq35_linear.toml"))
    drives = [c for c in meng.components if c.name.startswith("linear")]
    assert all(c.parameters["motor.continuous_force"] == 3000.0 for c in drives)  # > 2066 N per leg
    assert next(c for c in meng.components if c.name == "mechanics").parameters["effects.motor_inertia"] is False
    sumnu = scene_structure(load_scene(ROOT / "scenes" / "sumnu_case_1_pmsm.toml"))
    mechanics = next(c for c in sumnu.components if c.name == "mechanics").parameters
    assert mechanics["effects.motor_inertia"] is True and mechanics["motor_system.rotor_inertia"] == 1.3e-4
    assert mechanics["transmission.screw_ratio"] == pytest.approx(2 * np.pi / 0.01)
    pmsm = [c for c in sumnu.components if c.name.startswith("pmsm")]
    assert all(c.parameters["motor.torque_constant"] == 0.3 for c in pmsm)
    # designed for the leg: J_eq = M_ii / (K_FT i_theta); the electromechanical time constant
    # J_eq R / K_m^2 is then well above the 1 ms step (the reason for this motor)
    kp_w = pmsm[0].parameters["control.speed_kp"]
    j_eq = kp_w * 0.3 / 500.0
    assert j_eq * 1.5 / 0.3 ** 2 > 2e-3


@pytest.mark.parametrize("name", SWAPPED)
def test_a_swapped_scene_tracks_at_the_default_step(name, runs):
    result, report = runs[name]
    scene = load_scene(ROOT / "scenes" / f"{name}.toml")
    assert report.failure is None and report.simulated == pytest.approx(scene.duration)
    bounds = {"meng_eq35_linear": [0.5e-3] * 6,    # the linear motors' PID with feedforward: < 0.5 mm, mrad
              "sumnu_case_1_pmsm": [8e-3] * 3 + [2e-3] * 3}[name]  # the PMSM's P position loop lags by mm
    assert np.all(report.largest_error < bounds), report.largest_error
    assert "drive loops designed for the plant" in report.text()


def test_the_readme_quotes_what_the_swapped_scenes_print(runs):
    text = (ROOT / "docs" / "guide" / "scenes.md").read_text().replace("\n", " ")
    for name, (_, _, label) in SWAPPED.items():
        assert f"{label} {quoted(runs[name][1].largest_error)}" in text, (name, quoted(runs[name][1].largest_error))


def test_sumnu_parameters_stand_alone_without_mengs_motor_systems():
    values = mechanics_start_values("sumnu2015")
    assert values["motor_system.mass"] == values["motor_system.rotor_inertia"] == 0.0
    assert values["transmission.screw_ratio"] == values["transmission.force_torque"] == 1.0
    scene = load_scene(ROOT / "scenes" / "sumnu_case_1.toml", {"scene.duration": 0.3})
    on = load_scene(ROOT / "scenes" / "sumnu_case_1.toml",
                    {"scene.duration": 0.3, 'mechanics.parameters."effects.motor_inertia"': True})
    a, _ = run_scene(scene)
    b, _ = run_scene(on)
    assert np.abs(a["pose.z"] - b["pose.z"]).max() < 1e-12  # the switch adds nothing: no motor on these legs


def test_the_fast_numerics_on_linear_motors_need_a_longer_finer_start():
    """The interface-Jacobian coupling at 2 ms (the start and the impact's edges at the finer step) on Meng's platform with linear motors, through the
    first 3 s, impact included, against the scene at 62.5 us: with the PMSM scene's 0.1 s finer start
    the pose and the forces are off by more than twice what the scene's 1 ms gives (measured 1.1e-5
    and 6.5 % of the force peak against 3.3e-6 and 1.9 %), both right after the finer start ends, where
    the linear drives' start-up transient is still running; with a 0.2 s finer start they keep 1e-5
    and 1 % (measured 1.0e-6 and 0.24 %, better than the scene's 1 ms). Why the paper's scene has not
    moved to these numerics yet: docs/guide/scenes.md, Step control."""
    from cosim.platform.run.accuracy import difference
    path, forces = ROOT / "scenes" / "meng_eq35_linear.toml", [f"force[{i}]" for i in range(1, 7)]
    poses = [f"pose.{a}" for a in ("x", "y", "z", "roll", "pitch", "yaw")]
    reference, _ = run_scene(load_scene(path, {"scene.duration": 3.0, "scene.step": 6.25e-5,
                                               "coupling.startup_time": 0.0, "coupling.edge_time": 0.0}))
    peak = max(np.abs(reference[n]).max() for n in forces)
    shipped, _ = run_scene(load_scene(path, {"scene.duration": 3.0}))
    fast = {"scene.duration": 3.0, "scene.step": 2e-3, "coupling.interface_jacobian": True, "coupling.edge_time": 0.02,
            'drive.parameters."solver.step"': 2e-4, 'mechanics.parameters."solver.step"': 2e-3,
            'mechanics.parameters."solver.method"': 1}  # RK4, as measured
    short, _ = run_scene(load_scene(path, fast))
    longer, _ = run_scene(load_scene(path, {**fast, "coupling.startup_time": 0.2}))
    assert difference(short, reference, poses) > 2 * difference(shipped, reference, poses)
    assert difference(short, reference, forces) / peak > 0.05 > 2 * difference(shipped, reference, forces) / peak
    assert difference(longer, reference, poses) < 1e-5 and difference(longer, reference, forces) / peak < 0.01


def test_meng_on_linear_motors_converges_at_second_order():
    """The linear motors' PID differentiates its reference. Taken as the rate of `position_ref`, the
    slope of the master's order-1 extrapolation (a secant, O(h) off), it made the scene first order;
    the mechanics' `leg[i].velocity_ref`, computed from pose_ref's exact rate and curvature (the
    trajectory's derivatives, all sent, from the first sample on), makes it second order: the pose
    error over 0.5-2 s against the scene at 62.5 us falls at least threefold from 1 ms to 0.5 ms
    (measured 4.5x), and at 1 ms it is under 1e-6 (measured 1.1e-7; it was 1.1e-5)."""
    from cosim.platform.run.accuracy import difference
    path, poses = ROOT / "scenes" / "meng_eq35_linear.toml", [f"pose.{a}" for a in ("x", "y", "z", "roll", "pitch", "yaw")]
    reference, _ = run_scene(load_scene(path, {"scene.duration": 2.0, "scene.step": 6.25e-5,
                                               "coupling.startup_time": 0.0, "coupling.edge_time": 0.0}))
    errors = {}
    for step in (1e-3, 5e-4):
        result, _ = run_scene(load_scene(path, {"scene.duration": 2.0, "scene.step": step}))
        errors[step] = difference(result[result["time"] >= 0.5], reference, poses)
    assert errors[1e-3] > 3 * errors[5e-4] and errors[1e-3] < 1e-6, errors
