"""The cueing FMU's model-predictive cueing (algorithm 2, fmu/cueing/mpc.c): its vestibular models
are the published ones (the same as cosim.platform.perception's, on a platform held at neutral),
its pose reference keeps every leg within the stroke less the margin, every joint within its tilt
and every leg within its speed on the shipped drive and on sustained motions far past what the
workspace holds, its roll and pitch turn within the threshold (beyond the vehicle's own turning), its derivatives are its own, and settings
it cannot run are refused with a reason."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT, fmu_path
from cosim.engine.fmi import FmuError, FmuInstance
from cosim.platform import perception
from cosim.platform.core import Core

INPUTS = ["specific_force.x", "specific_force.y", "specific_force.z", "angular_rate.x", "angular_rate.y",
          "angular_rate.z"]
POSE = ["pose_ref.x", "pose_ref.y", "pose_ref.z", "pose_ref.roll", "pose_ref.pitch", "pose_ref.yaw"]
PERCEIVED = [f"mpc.perceived_error.{name}" for name in INPUTS]
G = 9.81
# the FMU's defaults: Meng's platform (the mechanics' limits)
LENGTH_MIN, LENGTH_MAX, MARGIN, LEG_VELOCITY, JOINT_ANGLE = 1.535, 2.2, 0.01, 1.0, np.radians(20.0)
TILT_RATE = np.radians(3.0)
# what the linearisation about the pose at each solve may miss over the horizon's first interval,
# and the soft constraints' own give: 1 mm of a leg, 1 % of a speed or an angle
LENGTH_SLACK, RELATIVE_SLACK = 1e-3, 0.01


def run(values: dict, motion, duration: float, h: float = 1e-3, outputs=POSE):
    """The cueing FMU alone through `motion(t)` (n x 6), each step's input the chord to the next
    sample; the times, the outputs with their first derivatives, and the inputs."""
    instance = FmuInstance(fmu_path("cueing"), "mpc")
    try:
        n = int(round(duration / h))
        t = np.arange(n + 1) * h
        u = motion(t)
        inputs = instance.real_group(INPUTS)
        instance.initialize({"algorithm": 2, **values, **dict(zip(INPUTS, u[0].tolist()))})
        out = instance.real_group(list(outputs))
        rows, rates = [out.read().copy()], [out.read_derivatives(1)]
        for k in range(n):
            inputs.write(u[k])
            inputs.write_derivatives((u[k + 1] - u[k]) / h)
            instance.do_step(h)
            rows.append(out.read().copy())
            rates.append(out.read_derivatives(1))
        return t, np.array(rows), np.array(rates), u
    finally:
        instance.free()


def at_rest(t: np.ndarray) -> np.ndarray:
    u = np.zeros((len(t), 6))
    u[:, 2] = G
    return u


def sustained(t: np.ndarray) -> np.ndarray:
    """Far past any workspace: 8 m/s^2 forward and 6 m/s^2 to the left for 10 s, a 0.5 rad/s
    yaw and a 0.3 rad/s roll for as long, then braking at 9 m/s^2."""
    u = at_rest(t)
    on = (t >= 0.5) & (t < 10.5)
    u[on, 0], u[on, 1], u[on, 5], u[on, 3] = 8.0, 6.0, 0.5, 0.3
    u[t >= 10.5, 0] = np.where(t[t >= 10.5] < 13.0, -9.0, 0.0)
    return u


def drive_csv(t: np.ndarray) -> np.ndarray:
    """The shipped car drive (examples/vehicle/drive.csv), linear between its rows."""
    path = ROOT / "examples/vehicle/drive.csv"
    header = next(line for line in path.read_text().splitlines() if not line.startswith("#")).split(",")
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
    return np.column_stack([np.interp(t, data[:, 0], data[:, header.index(name)]) for name in INPUTS])


def envelope_of(poses: np.ndarray, rates: np.ndarray) -> dict[str, np.ndarray]:
    core = Core()
    kinematics = core.pose_kinematics(poses)
    return {"length": kinematics["length"], "angle": np.maximum(kinematics["lower_angle"], kinematics["upper_angle"]),
            "speed": core.leg_velocities_many(poses, rates)}


def test_its_vestibular_models_are_the_published_ones():
    """A platform that cannot move (its accelerations limited to 1e-12) leaves the perceived error
    at minus what the vehicle's occupant perceives: the otoliths' and canals' responses to a
    multisine (exact for its piecewise-linear samples) equal perception.py's, which hold the
    published transfer functions at every frequency."""
    def multisine(t):
        u = at_rest(t)
        wave = np.sin(0.3 * t) + 0.6 * np.sin(1.7 * t + 0.4) + 0.3 * np.sin(6.0 * t + 1.0)
        u[:, :3] += np.outer(wave, [1.5, -1.0, 0.8])
        u[:, 3:] += np.outer(wave, [0.2, -0.1, 0.3])
        return u
    t, perceived, _, u = run({"mpc.acceleration_limit": 1e-12, "mpc.angular_acceleration_limit": 1e-12}, multisine,
                             20.0, outputs=PERCEIVED)
    vehicle = perception.vehicle_motion(u[:, :3], u[:, 3:], G)
    for c, organ in enumerate(perception.ORGANS):
        expected = -organ.perceive(t, vehicle[:, c])
        scale = np.abs(expected).max()
        assert np.abs(perceived[:, c] - expected).max() < 1e-6 * scale, INPUTS[c]


@pytest.mark.parametrize("motion, duration", [(drive_csv, 20.0), (sustained, 16.0)], ids=["car drive", "sustained"])
def test_keeps_the_platform_in_its_envelope(motion, duration):
    t, poses, rates, u = run({}, motion, duration, h=2e-3)
    envelope = envelope_of(poses, rates)
    length = envelope["length"]
    assert length.min() >= LENGTH_MIN + MARGIN - LENGTH_SLACK, length.min()
    assert length.max() <= LENGTH_MAX - MARGIN + LENGTH_SLACK, length.max()
    assert envelope["angle"].max() <= JOINT_ANGLE * (1 + RELATIVE_SLACK)
    assert np.abs(envelope["speed"]).max() <= LEG_VELOCITY * (1 + RELATIVE_SLACK)
    # the platform's roll and pitch turn no faster than the tilt threshold plus the vehicle's own turning
    turning, allowed = np.hypot(rates[:, 3], rates[:, 4]), TILT_RATE + np.hypot(u[:, 3], u[:, 4])
    assert (turning <= allowed * (1 + RELATIVE_SLACK)).all(), np.degrees((turning - allowed).max())
    if motion is sustained:  # it did use the workspace: the tilt held for the sustained force
        assert np.degrees(np.abs(poses[:, 4]).max()) > 10.0


def test_a_sustained_acceleration_is_rendered_by_tilt():
    """Sustained forward acceleration ends up felt through gravity: the platform pitched back by
    about asin(a / g) (the perceived error of a sustained force is then what the joints' limits
    leave), not translated: the leg lengths stay within the stroke."""
    def forward(t):
        u = at_rest(t)
        u[t >= 0.5, 0] = 1.0
        return u
    t, poses, _, _ = run({}, forward, 30.0, h=2e-3)
    pitch = poses[-1, 4]
    assert pitch == pytest.approx(-np.arcsin(1.0 / G), rel=0.05)
    assert abs(poses[-1, 0]) < 0.05


def test_with_a_pitch_rate_limit_of_its_own_it_pitches_faster_within_their_ellipse():
    """tilt.pitch_rate_limit 3.5 deg/s, roll's 2.5: a sustained braking pitches the platform faster
    than roll's limit allows, and the platform's roll and pitch rates stay within their ellipse (pitch
    counted in roll's measure, scaled by 2.5 / 3.5) plus the vehicle's own turning."""
    roll_limit, pitch_limit = np.radians(2.5), np.radians(3.5)  # stated here: the mechanism, whatever the default

    def braking(t):
        u = at_rest(t)
        u[t >= 0.5, 0] = -2.0
        u[(t >= 3.0) & (t < 6.0), 3] = 0.05  # and a roll of the vehicle's own
        return u
    t, poses, rates, u = run({"tilt.rate_limit": roll_limit, "tilt.pitch_rate_limit": pitch_limit}, braking, 10.0,
                             h=2e-3)
    measure = roll_limit / pitch_limit
    turning, allowed = np.hypot(rates[:, 3], measure * rates[:, 4]), roll_limit + np.hypot(u[:, 3], measure * u[:, 4])
    assert (turning <= allowed * (1 + RELATIVE_SLACK)).all(), np.degrees((turning - allowed).max())
    still = np.hypot(u[:, 3], u[:, 4]) == 0.0  # the vehicle not turning: the tilt's limit alone
    assert np.abs(rates[still, 4]).max() > 1.1 * roll_limit  # pitch past roll's limit: its own holds it
    assert np.abs(rates[still, 4]).max() <= pitch_limit * (1 + RELATIVE_SLACK)


def test_its_derivatives_are_its_own():
    """pose_ref's rate (the output derivative) is the derivative of pose_ref: its integral over
    the run equals the change of the pose (the MPC's motion is piecewise quadratic, exact)."""
    t, poses, rates, _ = run({}, drive_csv, 8.0)
    integral = np.concatenate([[0.0 * poses[0]], np.cumsum(0.5 * (rates[1:] + rates[:-1]) * np.diff(t)[:, None], axis=0)])
    np.testing.assert_allclose(poses - poses[0], integral, atol=1e-5)


@pytest.mark.parametrize("values, says", [
    ({"mpc.horizon": 0.1}, "mpc.horizon = 0.1 s is shorter than its 12 intervals"),
    ({"limit.leg_length_max": 1.8}, "the neutral pose puts leg 1 at"),
    ({"geometry.base_joint[1].x": 0.4834652370381326, "geometry.base_joint[1].y": -0.637386354243376,
      "geometry.base_joint[1].z": 1.689527733348906}, "a leg has no length at the neutral pose"),
    # a weight within its range but so large that the cost's Hessian is not finite (found by the
    # system FMU's fuzzer: the factorisation searched for a shift for ever)
    ({"mpc.weight.specific_force": 1.7976931348623157e308}, "the MPC's cost has no positive definite Hessian"),
    ({f"mpc.weight.{w}": 0.0 for w in ("specific_force", "angular_rate", "position", "angle", "velocity",
                                        "angular_velocity", "acceleration", "angular_acceleration")},
     "the MPC's cost has no positive definite Hessian"),
])
def test_settings_it_cannot_run_are_refused(values, says):
    instance = FmuInstance(fmu_path("cueing"), "refused")
    try:
        with pytest.raises(FmuError) as error:
            instance.initialize({"algorithm": 2, **values})
        assert says in str(error.value)
    finally:
        instance.free()


def braking_table(folder) -> str:
    """A recorded drive: cruise, then braking at 6 m/s^2 from t = 2 s for 2 s (rows every 10 ms)."""
    t = np.arange(0.0, 6.0 + 1e-9, 0.01)
    u = at_rest(t)
    u[(t >= 2.0) & (t < 4.0), 0] = -6.0
    path = folder / "braking.csv"
    np.savetxt(path, np.column_stack([t, u]), delimiter=",", header="time," + ",".join(INPUTS), comments="",
               fmt="%.10g")
    return str(path)


@pytest.mark.parametrize("preview", [0.0, 3.0])
def test_it_reads_a_recorded_drive_only_as_far_ahead_as_its_preview(preview, tmp_path):
    """mpc.preview is foresight of a recorded drive: with 3 s the platform surges and pitches ahead
    of the car's braking at 2 s (what the occupant feels while the car still cruises); with 0, as a
    live drive comes, it stands at neutral until the braking is under way (to round-off), then cues
    it (mpc.prediction_decay predicting on from what it read)."""
    table = braking_table(tmp_path)
    t, poses, _, _ = run({"vehicle.file": table, "mpc.preview": preview}, at_rest, 3.0, h=2e-3)
    before, after = t < 2.0, (t > 2.2) & (t < 3.0)
    moved_before = max(np.abs(poses[before, 0]).max(), np.abs(poses[before, 4]).max())
    if preview == 0.0:
        assert moved_before < 1e-9, moved_before
    else:
        assert np.abs(poses[before, 0]).max() > 0.02 and np.degrees(np.abs(poses[before, 4]).max()) > 1.0
    assert np.abs(poses[after, 0]).max() > 0.02  # the braking is cued either way



def ramp_table(folder, noise: float = 0.0) -> str:
    """A recorded drive: cruise, then braking that grows by 0.5 m/s^3 from t = 2 s for 1 s and holds
    (within what Meng's platform renders; rows every 10 ms), with white noise of `noise` [m/s^2] rms
    on each row of its specific force along x (seeded)."""
    t = np.arange(0.0, 6.0 + 1e-9, 0.01)
    u = at_rest(t)
    u[:, 0] = -0.5 * np.clip(t - 2.0, 0.0, 1.0) + noise * np.random.default_rng(1).standard_normal(len(t))
    path = folder / "ramp.csv"
    np.savetxt(path, np.column_stack([t, u]), delimiter=",", header="time," + ",".join(INPUTS), comments="",
               fmt="%.10g")
    return str(path)


def test_its_trend_continues_the_motion_from_the_past_alone(tmp_path):
    """mpc.prediction_trend continues the vehicle's motion along its rate as the past shows it: with
    no preview the platform stands at neutral until the braking begins (to round-off: no row ahead
    read through the trend), and once it grows the MPC, predicting it grows on, keeps the felt surge
    closer to the car's than holding the last it read (the perceived error's rms over the growth and
    the second after it a quarter smaller at least; measured: 42 % with a trend of 0.5 s)."""
    table = ramp_table(tmp_path)
    felt = {}
    for trend in (0.0, 0.5):
        t, out, _, _ = run({"vehicle.file": table, "mpc.preview": 0.0, "mpc.prediction_trend": trend}, at_rest, 4.0,
                           h=2e-3, outputs=POSE + PERCEIVED)
        assert np.abs(out[t < 2.0, :6] - out[0, :6]).max() < 1e-9
        felt[trend] = np.sqrt(np.mean(out[(t > 2.0) & (t < 4.0), 6] ** 2))
    assert felt[0.5] < 0.75 * felt[0.0], felt


def test_its_trend_smoothed_does_not_predict_a_noisy_feeds_noise_on(tmp_path):
    """On the growing braking with an accelerometer's white noise (0.05 m/s^2 rms on its 10 ms rows),
    the trend taken as it comes (its rate over 20 ms) continues the noise: the felt surge's error is
    larger than with the motion held. mpc.trend_smoothing (a low-pass of 0.1 s on that rate, updated
    each solve) gives the trend its gain back: a fifth smaller than held at least (measured: 31 %;
    the raw trend 58 % larger)."""
    table = ramp_table(tmp_path, noise=0.05)
    felt = {}
    for trend, smoothing in ((0.0, 0.0), (0.5, 0.0), (0.5, 0.1)):
        t, out, _, _ = run({"vehicle.file": table, "mpc.preview": 0.0, "mpc.prediction_trend": trend,
                            "mpc.trend_smoothing": smoothing}, at_rest, 4.0, h=2e-3, outputs=POSE + PERCEIVED)
        felt[trend, smoothing] = np.sqrt(np.mean(out[(t > 2.0) & (t < 4.0), 6] ** 2))
    assert felt[0.5, 0.0] > felt[0.0, 0.0], felt
    assert felt[0.5, 0.1] < 0.8 * felt[0.0, 0.0], felt
