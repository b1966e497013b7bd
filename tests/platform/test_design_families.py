"""Design studies beyond Halder's plane (cosim.platform.design): Meng's and Sumnu's layouts as
families, a scene's or a recorded table's motion as the specification, the actuator's peak force
and speed as limits. Each against an independent fact: Meng's defining property of l_0, the
parameter set's own mechanics at the unscaled design, Eq 35's sines differentiated by hand, the
leg speed against differences of the leg lengths."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT
from cosim.platform.design import FAMILIES, design_map, load_study, platform_values
from cosim.platform.design.spec.motion import basic_motions, shortest_time
from cosim.platform.design.answer.report import map_rows
from cosim.platform.scene.parameter_sets import read_parameter_set, sumnu_mechanics
from cosim.platform.core import Core
from cosim.platform.scene import load_scene
from cosim.platform.scene.signals import sine_motion

MENG = ROOT / "studies" / "meng_eq35_platform.toml"


@pytest.fixture(scope="module")
def meng():
    return load_study(MENG)


def grid(study, rows, columns):
    (row_key, _), (column_key, _) = list(study.axes.items())
    return study.with_axes({row_key: np.asarray(rows, float), column_key: np.asarray(columns, float)})


def test_meng_family_every_leg_is_l0_long_at_the_neutral(meng):
    """Meng's Table 1 defines the neutral height by the middle leg length l_0: at each design's
    neutral pose every leg is l_0 long, whatever r_b."""
    part = grid(meng, [0.8, 1.1, 1.3], [1.7, 1.86, 2.1])
    for r_b in part.axes["lower_joint_radius"]:
        for l_0 in part.axes["middle_leg_length"]:
            core = Core().use_start_values(platform_values(part, {"lower_joint_radius": r_b, "middle_leg_length": l_0}))
            assert np.allclose(core.leg_lengths(core.neutral_pose), l_0, atol=1e-9)
    design = design_map(part, dynamic=False)
    assert np.allclose(design.neutral_length, np.broadcast_to(part.axes["middle_leg_length"], (3, 3)), atol=1e-9)


def test_sumnu_family_unscaled_is_the_thesis_platform(tmp_path):
    """Sumnu's family at base_scale = platform_scale = 1 and the thesis' home height is the
    parameter set's own platform (its joints and neutral); a base scaled by 1.2 moves every base
    joint 1.2 times as far from the base frame's z axis."""
    study = tmp_path / "sumnu.toml"
    study.write_text('[study]\nparameter_set = "sumnu2015"\n[axes]\nbase_scale = {from = 0.9, to = 1.2, step = 0.1}\n'
                     'home_height = {from = 0.9, to = 1.1, step = 0.1}\n[motion]\nheave = 0.1\nvelocity = 0.1\n'
                     'acceleration = 1.0\nangular_velocity_deg = 10\nangular_acceleration_deg = 100\n'
                     '[[actuator]]\nname = "any"\nstroke = 1.0\nrunning_length_min = 0.5\ncontinuous_force = 1e4\n')
    loaded = load_study(study)
    values = platform_values(loaded, {"base_scale": 1.0, "home_height": 1.0})
    own = sumnu_mechanics(read_parameter_set("sumnu2015"))
    for key, value in own.items():
        if key.startswith("geometry."):
            assert values[key] == pytest.approx(value, abs=1e-12), key
    scaled = platform_values(loaded, {"base_scale": 1.2, "home_height": 1.0})
    for i in range(1, 7):
        radius = [math.hypot(v[f"geometry.base_joint[{i}].x"], v[f"geometry.base_joint[{i}].y"]) for v in (values, scaled)]
        assert radius[1] == pytest.approx(1.2 * radius[0], rel=1e-12)
    design = design_map(loaded)
    assert design.actuated_length_max.shape == (4, 3, 1) and np.all(design.actuated_length_max > design.actuated_length_min)


def test_a_scenes_motion_is_its_reference_about_the_neutral_with_exact_rates(meng):
    """[motion] scene = "meng_eq35": the displacements are Eq 35's sines about the neutral, and the
    rates and accelerations from the samples' differences are the sines' derivatives to the
    differences' second-order error ((w h)^2 / 6 of each amplitude's scale, w = 2 pi 0.2 Hz, h = 10 ms;
    the ends' one-sided differences 4x that)."""
    recorded = meng.recorded
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    pose, rate, acceleration = sine_motion(scene.trajectory, recorded.times)
    neutral = Core().use_start_values(platform_values(meng, {})).neutral_pose
    assert np.allclose(recorded.displacement, pose - np.r_[0, 0, neutral[2], 0, 0, 0], atol=1e-12)
    h = recorded.times[1] - recorded.times[0]
    w = np.array([2 * math.pi * max((s.frequency for s in scene.trajectory[dof].sines), default=0.0)
                  for dof in ("x", "y", "z", "roll", "pitch", "yaw")])
    amplitude = np.array([sum(abs(s.amplitude) for s in scene.trajectory[dof].sines)
                          for dof in ("x", "y", "z", "roll", "pitch", "yaw")])
    for got, exact, order in ((recorded.rates, rate, 1), (recorded.accelerations, acceleration, 2)):
        bound = 4 * order * (w * h) ** 2 / 6 * w ** order * amplitude + 1e-12
        assert np.all(np.abs(got - exact) <= bound), np.abs(got - exact).max(axis=0) / bound


def test_a_recorded_table_gives_the_limits_of_the_same_basic_motion(meng, tmp_path):
    """A table holding Halder's surge move (shortest-time, 0.6 m) gives the map the same leg-length
    extremes as the basic motion itself (the cubic table between 400 samples per phase: 1e-9 m)."""
    halder = load_study(ROOT / "studies" / "halder_section5.toml")
    t, s, _, _ = shortest_time(0.6, 0.05, 0.05, 400)
    keep = np.r_[True, np.diff(t) > 0]
    (tmp_path / "surge.csv").write_text("time,x\n" + "\n".join(f"{float(a)!r},{float(b) - 0.3!r}" for a, b in zip(t[keep], s[keep])))
    text = (ROOT / "studies" / "halder_section5.toml").read_text()
    motion = text[text.index("[motion]"):text.index("[[actuator]]")]
    study = tmp_path / "table.toml"
    study.write_text(text.replace(motion, '[motion]\ntable = "surge.csv"\nsamples = 2001\n\n'))
    table = grid(load_study(study), [1.0, 1.1], [1.2, 1.4])
    basic = grid(dataclasses.replace(halder, motion=dataclasses.replace(halder.motion, ranges={"surge": 0.3})),
                 [1.0, 1.1], [1.2, 1.4])
    a, b = design_map(table, dynamic=False), design_map(basic, dynamic=False)
    assert a.motions == ["surge"] and b.motions == ["surge"]
    assert np.allclose(a.actuated_length_max, b.actuated_length_max, atol=1e-9) and np.allclose(a.actuated_length_min, b.actuated_length_min, atol=1e-9)


def test_the_leg_speed_is_the_rate_of_the_leg_lengths(meng):
    """The map's leg speed (the core's platform_leg_velocities_many) against central differences of
    the leg lengths along the motion's rates (1e-7 m/s)."""
    core = Core().use_start_values(platform_values(meng, {}))
    rng = np.random.default_rng(3)
    poses = core.neutral_pose + rng.normal(0, [0.1, 0.1, 0.1, 0.1, 0.1, 0.1], (50, 6))
    rates = rng.normal(0, 0.5, (50, 6))
    h = 1e-6
    differences = np.array([(core.leg_lengths(p + h * r) - core.leg_lengths(p - h * r)) / (2 * h)
                            for p, r in zip(poses, rates)])
    assert np.allclose(core.leg_velocities_many(poses, rates), differences, atol=1e-7)
    part = grid(meng, [1.1], [1.86])
    design = design_map(part)
    neutral = core.neutral_pose
    r = meng.recorded
    expected = np.abs(core.leg_velocities_many(neutral + r.displacement, r.rates)).max()
    assert design.leg_speed[0, 0, 0] == pytest.approx(expected, rel=1e-12)


def test_the_actuators_peak_force_and_speed_limit_the_designs(meng):
    """An actuator whose speed (peak force) is just below (above) what the map asks turns every
    design out (keeps the kinematically admissible ones)."""
    part = grid(meng, [0.8, 0.85, 0.9], [1.93, 1.95])
    design = design_map(part)
    wide = dataclasses.replace(meng.actuators[1], peak_force=None, speed=None, continuous_force=1e9)
    assert design.admissible(wide).any()
    for field, demand in (("speed", design.leg_speed), ("peak_force", design.force_full)):
        below = dataclasses.replace(wide, **{field: 0.999 * float(demand.min())})
        above = dataclasses.replace(wide, **{field: 1.001 * float(demand.max())})
        assert not design.admissible(below, dynamic=True).any()
        assert np.array_equal(design.admissible(above, dynamic=True), design.admissible(wide))


def test_meng_eq35_needs_more_than_mengs_stroke_at_any_geometry(meng):
    """The shipped study's answer on a coarse grid: no design of Meng's layout carries Eq 35 within
    Table 4's 665 mm stroke (the main job leaves the stroke), the 0.85 m leg carries it at some, and
    the smallest stroke the rows report is the smallest needed over the grid's designs."""
    part = grid(meng, np.arange(0.6, 1.51, 0.1), np.sort(np.r_[np.arange(1.5, 2.41, 0.1), 1.95]))
    design = design_map(part)
    assert not design.admissible(meng.actuators[0]).any() and design.admissible(meng.actuators[1]).any()
    needed = design.actuated_length_max.max(axis=2) - design.actuated_length_min.min(axis=2)
    joints = np.maximum(design.top_angle, design.bottom_angle).max(axis=2) < meng.joint_angle_limit
    row = next(r for r in map_rows(design) if r.quantity.startswith("the smallest stroke"))
    assert row.ours == pytest.approx(needed[joints].min(), abs=0) and row.ours > 0.665
    assert set(FAMILIES) == {"halder2013", "meng2010", "sumnu2015"}
    assert basic_motions(meng, np.zeros(6)).keys() == {"meng_eq35"}


@pytest.mark.parametrize("drive", ["pmsm", "linear"])
def test_a_confirmation_through_our_drives_reports_their_currents(meng, drive):
    """Eq 35 at Meng's design through our drive FMUs (auto tuned, the platform's drive set): the
    legs' peak force within 1 % of the full inverse dynamics' along the reference (the tracking
    error's effect: millimetres on metres of leg), and the currents the drive's own torque or
    force constant away from those forces (the current loop's error and the motor's friction:
    1 %)."""
    from cosim.platform.design.search.confirm import confirm_motion, confirmation_rows, drive_parameters
    from cosim.platform.run.tuning import drive_defaults
    point = {"lower_joint_radius": 1.1, "middle_leg_length": 1.86}
    run = confirm_motion(meng, point, meng.actuators[1], "meng_eq35", drive=drive)
    assert run["peak_force"] == pytest.approx(run["predicted_peak"], rel=0.01)
    values, on_legs, _ = drive_parameters(meng, drive)
    given = {**drive_defaults(drive), **values}
    per_ampere = given["motor.torque_constant"] * 250.0 if drive == "pmsm" else given["motor.force_constant"]
    assert run["peak_current"] * per_ampere == pytest.approx(run["peak_force"], rel=0.01)
    assert run["rms_current"] * per_ampere == pytest.approx(run["rms_force"], rel=0.01)
    assert run["continuous_current"] * per_ampere == pytest.approx(meng.actuators[1].continuous_force, rel=1e-12)
    (row,) = confirmation_rows([run], "Meng's design")
    assert f"current peak {run['peak_current']:.1f} A" in row.note


def test_each_joint_may_have_its_own_limit(meng, tmp_path):
    """top_joint_angle_limit_deg / bottom_joint_angle_limit_deg: each joint's angle against its own
    limit; the same value for both is the shared limit's map."""
    text = MENG.read_text()
    for top, bottom in ((20, 20), (15, 30)):
        study = tmp_path / f"limits_{top}.toml"
        study.write_text(text.replace("joint_angle_limit_deg = 20.0",
                                      f"top_joint_angle_limit_deg = {top}\nbottom_joint_angle_limit_deg = {bottom}"))
        loaded = grid(load_study(study), [0.7, 1.0, 1.3], [1.6, 1.9, 2.2])
        design = design_map(loaded, dynamic=False)
        got = design.kinematic_admissible(meng.actuators[1])["joint angle"]
        expected = (design.top_angle < math.radians(top)) & (design.bottom_angle < math.radians(bottom))
        assert np.array_equal(got, expected)
        if top == bottom:
            shared = design_map(grid(meng, [0.7, 1.0, 1.3], [1.6, 1.9, 2.2]), dynamic=False)
            assert np.array_equal(got, shared.kinematic_admissible(meng.actuators[1])["joint angle"])
        else:
            assert not np.array_equal(got, np.maximum(design.top_angle, design.bottom_angle) < math.radians(20))


def test_a_rotary_actuator_is_given_by_its_motor(meng, tmp_path, capsys):
    """continuous_torque, peak_torque, motor_speed: the motor's side, through the family's screw
    (params/meng2010.toml: K_FT = 250 N/(N m), i_theta = 277.78 rad/m): the same limits as the leg
    forces and speed they stand for. A family without a screw (Sumnu's linear motors) refuses them,
    and a limit given both ways is refused, each in one line naming the file and line."""
    from cosim.cli import main
    transmission = read_parameter_set("meng2010")["transmission"]
    k_ft = transmission["force_torque_coefficient"]
    leg = meng.actuators[0]
    assert leg.continuous_force == pytest.approx(20.1 * k_ft, rel=1e-12)
    assert leg.peak_force == pytest.approx(63.0 * k_ft, rel=1e-12)
    screw = platform_values(meng, {})["transmission.screw_ratio"]
    assert leg.speed == pytest.approx(600.0 / screw, rel=1e-12)
    text = MENG.read_text()
    forces = text.replace("continuous_torque = 20.1", f"continuous_force = {20.1 * k_ft!r}").replace(
        "peak_torque = 63.0", f"peak_force = {63.0 * k_ft!r}").replace("motor_speed = 600.0", f"speed = {600.0 / screw!r}")
    (tmp_path / "forces.toml").write_text(forces)
    def limits(actuators):  # what the map judges by (the motor's side aside)
        return [(a.name, a.stroke, a.running_length_min, a.continuous_force, a.peak_force, a.speed) for a in actuators]
    assert limits(load_study(tmp_path / "forces.toml").actuators) == limits(meng.actuators)
    assert leg.motor is not None and leg.with_lead(leg.lead).continuous_force == pytest.approx(leg.continuous_force)
    assert "continuous_torque = 20.1  " in text
    for body, expected in ((text.replace("continuous_torque = 20.1  ", "continuous_force = 5025.0\ncontinuous_torque = 20.1  ", 1),
                            "'actuator[1].continuous_torque' and 'continuous_force' both given"),
                           (text.replace('parameter_set = "meng2010"', 'parameter_set = "sumnu2015"').replace(
                               "[axes]\nlower_joint_radius = {from = 0.60, to = 1.50, step = 0.01}",
                               "[axes]\nbase_scale = {from = 0.9, to = 1.1, step = 0.1}").replace(
                               "middle_leg_length = {from = 1.50, to = 2.40, step = 0.01}",
                               "home_height = {from = 0.9, to = 1.1, step = 0.1}"),
                            "'actuator[1].continuous_torque' needs a screw: sumnu2015's legs are driven by force")):
        path = tmp_path / "bad.toml"
        path.write_text(body)
        assert main(["design", str(path), "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and expected in err and "bad.toml:" in err, err
