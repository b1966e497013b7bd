"""The motion-cueing FMU (the classical washout): each filter is its transfer function (against
scipy's exact response to the same piecewise-linear input), its output derivatives are the
filters' own, a sustained acceleration ends as tilt at no more than the tilt's rate limit, the
platform comes back to neutral after a manoeuvre, and wrong parameters are refused by name."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from cosim.engine.artifacts import ROOT, fmu_path
from cosim.engine.fmi import FmuError, FmuInstance

G = 9.81  # the platform's gravity, the cueing FMU's default (one gravity for every FMU)
INPUTS = ["specific_force.x", "specific_force.y", "specific_force.z", "angular_rate.x", "angular_rate.y",
          "angular_rate.z"]
POSE = ["pose_ref.x", "pose_ref.y", "pose_ref.z", "pose_ref.roll", "pose_ref.pitch", "pose_ref.yaw"]
RATE = [name.replace("pose_ref", "pose_ref_rate") for name in POSE]
NEUTRAL_Z = 1.689527733348906


@pytest.fixture
def cueing():
    made = []

    def make(values: dict | None = None) -> FmuInstance:
        instance = FmuInstance(fmu_path("cueing"), f"cueing{len(made)}")
        made.append(instance)
        instance.initialize(values or {})
        return instance

    yield make
    for instance in made:
        instance.free()


def drive(instance: FmuInstance, motion, h: float, n: int, outputs=POSE):
    """Steps the FMU through `motion(t)` (n x 6: specific force and angular rate), each step's
    input the chord to the next sample (value and rate: the piecewise-linear input scipy's lsim
    takes); returns the times, the outputs and their first and second derivatives."""
    t = np.arange(n + 1) * h
    u = motion(t)
    inputs, out = instance.real_group(INPUTS), instance.real_group(list(outputs))
    inputs.write(u[0])  # after the initialization (from rest: scipy's response starts from a zero state)
    rows, rates, accelerations = [out.read().copy()], [out.read_derivatives(1)], [out.read_derivatives(2)]
    for k in range(n):
        inputs.write(u[k])
        inputs.write_derivatives((u[k + 1] - u[k]) / h)
        instance.do_step(h)
        rows.append(out.read().copy())
        rates.append(out.read_derivatives(1))
        accelerations.append(out.read_derivatives(2))
    return t, u, np.array(rows), np.array(rates), np.array(accelerations)


def multisine(t: np.ndarray, amplitude: float) -> np.ndarray:
    """Three frequencies across each filter's band (0.1, 0.8 and 5 rad/s)."""
    return amplitude * (np.sin(0.1 * t) + 0.6 * np.sin(0.8 * t + 0.4) + 0.3 * np.sin(5.0 * t + 1.0))


def test_each_filter_is_its_transfer_function(cueing):
    values = {"translation.x.frequency": 2.0, "translation.x.damping": 0.8, "translation.x.break": 0.4,
              "translation.z.frequency": 3.0, "translation.z.damping": 1.1, "translation.z.break": 0.0,
              "rotation.roll.frequency": 1.5, "rotation.roll.damping": 0.7, "tilt.frequency": 2.5,
              "tilt.damping": 0.9, "tilt.rate_limit": 10.0}
    k = 0.5  # every channel's default gain

    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 0] = multisine(t, 0.4)      # surge: translation and tilt (pitch)
        u[:, 2] = G + multisine(t, 0.3)  # heave
        u[:, 3] = multisine(t, 0.05)     # roll rate
        return u

    h = 2e-3
    t, u, rows, rates, accelerations = drive(cueing(values), motion, h, 10000)

    def response(numerator, denominator, column):
        return signal.lsim((numerator, denominator), k * u[:, column] - (k * G if column == 2 else 0.0), t)[1]

    def scale(x):
        return np.abs(x).max()

    w, z, b = 2.0, 0.8, 0.4
    surge = np.polymul([1, 2 * z * w, w * w], [1, b])
    x = response([1, 0], surge, 0)  # p = s / ((s^2 + 2 zeta w s + w^2)(s + w_b)) u
    assert np.abs(rows[:, 0] - x).max() < 1e-9 * scale(x)
    x_rate, x_acceleration = response([1, 0, 0], surge, 0), response([1, 0, 0, 0], surge, 0)
    assert np.abs(rates[:, 0] - x_rate).max() < 1e-9 * scale(x_rate)
    assert np.abs(accelerations[:, 0] - x_acceleration).max() < 1e-9 * scale(x_acceleration)
    heave = response([1], [1, 2 * 1.1 * 3.0, 9.0], 2)  # second order: p = u / (s^2 + 2 zeta w s + w^2)
    assert np.abs(rows[:, 2] - NEUTRAL_Z - heave).max() < 1e-9 * scale(heave)
    roll_rate_cue = response([1, 0], [1, 2 * 0.7 * 1.5, 1.5 ** 2], 3)  # b = s / (s^2 + ...) u
    tilt = np.arcsin(response([6.25], [1, 2 * 0.9 * 2.5, 6.25], 0) / G)  # pitch = -asin(l_x / g)
    assert np.abs(rows[:, 3] - roll_rate_cue).max() < 1e-9 * scale(roll_rate_cue)
    assert np.abs(rows[:, 4] + tilt).max() < 1e-9 * scale(tilt)


def test_the_output_derivatives_are_the_outputs_own(cueing):
    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 1], u[:, 2] = multisine(t, 1.0), G + multisine(t, 0.5)
        u[:, 4], u[:, 5] = multisine(t, 0.1), multisine(t, 0.2)
        return u

    h = 1e-3
    t, _, rows, rates, accelerations = drive(cueing({"tilt.rate_limit": 10.0}), motion, h, 8000)
    central = (rows[2:] - rows[:-2]) / (2 * h)
    second = (rows[2:] - 2 * rows[1:-1] + rows[:-2]) / h ** 2
    for d in range(6):
        span = np.abs(rates[:, d]).max()
        assert np.abs(central[:, d] - rates[1:-1, d]).max() < 1e-4 * span + 1e-12, POSE[d]
        span = np.abs(accelerations[:, d]).max()
        # the input's rate is piecewise constant (a chord a step): the acceleration jumps by about h u'' a step
        assert np.abs(second[:, d] - accelerations[1:-1, d]).max() < 5e-3 * span + 1e-9, POSE[d]


def test_the_rate_outputs_are_the_pose_rate_with_its_own_exact_derivatives(cueing):
    """pose_ref_rate.* (for masters without input derivatives) is pose_ref's rate bit for bit, its
    first derivative pose_ref's second, and its second the jerk: against the central difference of
    the acceleration for a piecewise-linear motion (corners every 0.5 s, left out), within 2e-5 of
    the jerk's range (the difference's O(h^2) error, with every channel's filter and the tilt's
    asin, is at most 7e-6 of it at h = 1 ms)."""
    knots = np.arange(0.0, 8.5, 0.5)
    values = np.random.default_rng(7).normal(0.0, 1.0, (len(knots), 6)) * [1.0, 1.0, 0.5, 0.1, 0.1, 0.2]
    values[:, 2] += G

    def motion(t):
        return np.column_stack([np.interp(t, knots, values[:, k]) for k in range(6)])

    h = 1e-3
    t, _, rows, rates, accelerations = drive(cueing({"tilt.rate_limit": 10.0}), motion, h, 8000, POSE + RATE)
    assert np.array_equal(rows[:, 6:], rates[:, :6]) and np.array_equal(rates[:, 6:], accelerations[:, :6])
    away = np.min(np.abs(t[1:-1, None] - knots[None, :]), axis=1) > 2 * h
    jerk = (accelerations[2:, :6] - accelerations[:-2, :6]) / (2 * h)
    for d in range(6):
        span = np.abs(accelerations[:, 6 + d]).max()
        assert np.abs(jerk[away, d] - accelerations[1:-1, 6 + d][away]).max() <= 2e-5 * span, RATE[d]


def test_a_sustained_acceleration_ends_as_tilt_within_its_rate_limit(cueing):
    """A car accelerating at 2 m/s^2 from t = 1 s on: the surge cue washes out, and the tilt takes
    over until gravity gives the occupant the scaled acceleration, never turning faster than 3 deg/s."""
    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 0], u[:, 2] = np.where(t >= 1.0, 2.0, 0.0), G
        return u

    h = 1e-3
    limit = np.radians(3.0)  # stated here: the mechanism, whatever the default
    t, _, rows, rates, _ = drive(cueing({"translation.x.gain": 1.0, "tilt.gain": 1.0, "tilt.rate_limit": limit}),
                                 motion, h, 40000, POSE + ["tilt.pitch"])
    assert np.abs(np.diff(rows[:, 6]) / h).max() <= limit * (1 + 1e-12)  # the tilt's rate limit, every step
    assert np.abs(rates[:, 6]).max() <= limit * (1 + 1e-12)
    assert np.abs(rates[:, 6]).max() > 0.99 * limit  # and it is what holds it back here
    felt = -G * np.sin(rows[-1, 4])  # a pitch theta is felt as f_x = -g sin(theta)
    assert abs(felt - 2.0) < 1e-6  # the whole acceleration, through tilt alone
    assert abs(rows[-1, 0]) < 1e-3 and rows[:, 0].max() > 0.05  # the surge cue moved forward, then washed out
    assert np.abs(rows[:, 1:4] - [0.0, NEUTRAL_Z, 0.0]).max() == 0.0  # nothing else moved


def test_a_diagonal_acceleration_turns_the_tilt_vector_within_the_rate_limit(cueing):
    """Braking and cornering at once (2 m/s^2 along x and y): roll and pitch tilt together, and the
    tilt vector's rate, sqrt(roll'^2 + pitch'^2), stays within the limit, every step; each axis
    alone then turns at 1/sqrt(2) of it (a per-axis limit would let the vector turn at sqrt(2)
    times the limit, 4.24 deg/s for 3)."""
    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 0] = u[:, 1] = np.where(t >= 1.0, 2.0, 0.0)
        u[:, 2] = G
        return u

    h = 1e-3
    limit = np.radians(3.0)  # stated here: the mechanism, whatever the default
    t, _, rows, rates, _ = drive(cueing({"translation.x.gain": 1.0, "translation.y.gain": 1.0, "tilt.gain": 1.0,
                                         "tilt.rate_limit": limit}), motion, h, 30000, POSE + ["tilt.roll", "tilt.pitch"])
    stepped = np.hypot(np.diff(rows[:, 6]), np.diff(rows[:, 7])) / h
    assert stepped.max() <= limit * (1 + 1e-9)
    assert np.hypot(rates[:, 6], rates[:, 7]).max() <= limit * (1 + 1e-9)
    assert stepped.max() > 0.99 * limit  # the limit holds it back
    assert np.abs(np.diff(rows[:, 6]) / h).max() < 0.75 * limit  # each axis alone: about 1/sqrt(2) of it


@pytest.mark.parametrize("direction", [(1.0, 0.0), (1.0, 1.0), (1.0, -0.4)])
def test_with_a_pitch_rate_limit_of_its_own_the_tilt_turns_within_their_ellipse(cueing, direction):
    """tilt.pitch_rate_limit (here 4 deg/s, roll's 3): the tilt's rates stay within the ellipse
    (roll'/3)^2 + (pitch'/4)^2 <= 1 every step and on it where the limit holds them back; a surge
    alone pitches at 4 deg/s, a diagonal turns each axis slower than its own limit."""
    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 0], u[:, 1] = (2.0 * c * (t >= 1.0) for c in direction)
        u[:, 2] = G
        return u

    h = 1e-3
    roll_limit, pitch_limit = np.radians(3.0), np.radians(4.0)  # stated here: the mechanism, whatever the default
    t, _, rows, rates, _ = drive(cueing({"translation.x.gain": 1.0, "translation.y.gain": 1.0, "tilt.gain": 1.0,
                                         "tilt.rate_limit": roll_limit, "tilt.pitch_rate_limit": pitch_limit}),
                                 motion, h, 30000, POSE + ["tilt.roll", "tilt.pitch"])
    for roll, pitch in ((np.diff(rows[:, 6]) / h, np.diff(rows[:, 7]) / h), (rates[:, 6], rates[:, 7])):
        within = np.hypot(roll / roll_limit, pitch / pitch_limit)
        assert within.max() <= 1 + 1e-9 and within.max() > 0.99  # within the ellipse, and held back on it
    pitch_rate, roll_rate = np.abs(np.diff(rows[:, 7]) / h).max(), np.abs(np.diff(rows[:, 6]) / h).max()
    if direction[1] == 0.0:
        assert pitch_rate == pytest.approx(pitch_limit, rel=1e-9) and roll_rate == 0.0  # pitch at its own limit
    else:
        assert pitch_rate < pitch_limit and roll_rate < roll_limit
    felt = -G * np.sin(rows[-1, 4]), G * np.sin(rows[-1, 3])
    assert np.allclose(felt, [2.0 * c for c in direction], atol=1e-6)  # the whole acceleration, through tilt alone


def test_the_platform_comes_back_to_neutral_after_a_manoeuvre(cueing):
    """Braking, a lane change and a curve, then driving straight on: every cue washes out."""
    def motion(t):
        u = np.zeros((len(t), 6))
        u[:, 0] = -4.0 * ((t > 1) & (t < 3))                                      # braking
        u[:, 1] = 3.0 * np.sin(2 * np.pi * 0.4 * (t - 4)) * ((t > 4) & (t < 6.5))  # lane change
        u[:, 5] = 0.3 * ((t > 8) & (t < 12))                                      # a curve's yaw rate
        u[:, 1] += 3.0 * ((t > 8) & (t < 12))                                     # and its lateral force
        u[:, 2] = G
        return u

    h = 2e-3
    t, _, rows, rates, _ = drive(cueing(), motion, h, 40000)
    neutral = np.array([0.0, 0.0, NEUTRAL_Z, 0.0, 0.0, 0.0])
    assert np.abs(rows[t < 20] - neutral).max() > 0.05  # it moved
    assert np.abs(rows[-1] - neutral).max() < 1e-3  # and is back
    assert np.abs(rates[-1]).max() < 1e-3


@pytest.mark.parametrize("name, value", [("translation.y.frequency", 0.0), ("rotation.yaw.damping", -1.0),
                                         ("tilt.rate_limit", 0.0), ("tilt.frequency", float("nan")),
                                         ("tilt.pitch_rate_limit", -0.05), ("tilt.pitch_rate_limit", 1e-310),
                                         ("tilt.pitch_rate_limit", 1e3)])
def test_wrong_parameters_are_refused_by_name(cueing, name, value):
    """A bound the table states, and tilt.pitch_rate_limit more than a thousand times from roll's (its
    scale enters the MPC's constraint rows: 1e-310 would make them infinite)."""
    with pytest.raises(FmuError) as caught:
        cueing({name: value})
    assert name in str(caught.value)


def braking(t: np.ndarray) -> np.ndarray:
    """A car braking at 8 m/s^2 from 0.5 s on (0.15 s onset), at its occupant's head."""
    u = np.zeros((len(t), 6))
    u[:, 0], u[:, 2] = -8.0 * np.clip((t - 0.5) / 0.15, 0.0, 1.0), G
    return u


def envelope_excess(rows: np.ndarray) -> tuple[float, float]:
    """How far the pose references (n x 6) take Meng's platform (the cueing's default joints) past
    the cueing's default envelope: the legs past the stroke 1.535-2.2 m less 10 mm [m], the joints
    past 20 deg [rad] (0 or less: inside)."""
    from cosim.platform.core import Core
    kinematics = Core().pose_kinematics(rows)
    legs, tilt = kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    return max(1.545 - legs.min(), legs.max() - 2.19), tilt.max() - np.radians(20.0)


HELD = [f"guard.held.{kind}" for kind in ("stroke", "joint", "leg_velocity", "leg_acceleration", "return")]


def test_the_guard_holds_the_reference_in_the_envelope_with_its_exact_motion(cueing):
    """A hard braking, strongly cued, takes Meng's platform past its joints' 20 deg unguarded; with
    guard = true the reference stays within the stroke less its margin and the joints' limit at every
    step (the steps held counted by what held them), and wherever the guard held it the reference
    moves as its outputs' derivatives say: over the step, value + rate h + acceleration h^2 / 2 and
    rate + acceleration h, to round-off (its acceleration constant over a step, as the guard chose)."""
    strong = {"translation.x.gain": 1.0, "translation.x.limit": 10.0, "translation.x.frequency": 1.0,
              "tilt.gain": 1.0, "tilt.rate_limit": 0.3}
    h, n = 1e-3, 3000
    _, _, free, _, _ = drive(cueing(strong), braking, h, n)
    assert envelope_excess(free)[1] > np.radians(2.0)  # unguarded: well past the joints' limit
    guarded = cueing({**strong, "guard": True})
    t, _, rows, rates, accelerations = drive(guarded, braking, h, n, POSE + HELD)
    stroke, joint = envelope_excess(rows[:, :6])
    assert stroke <= 1e-12 and joint <= 1e-12
    held = rows[:, 6:].sum(axis=1)
    assert rows[-1, 6 + 1] > 100 and np.all(np.diff(held) >= 0)
    took = np.flatnonzero(np.diff(held) > 0) + 1  # at t[k] the guard held the step on from there
    took = took[took + 1 < len(t)]
    assert len(took) > 100
    for d in range(6):
        span = np.ptp(rows[:, d]) + 1e-3
        moved = rows[took, d] + rates[took, d] * h + 0.5 * accelerations[took, d] * h * h
        assert np.abs(rows[took + 1, d] - moved).max() <= 1e-12 * max(1.0, np.abs(rows[:, d]).max()), POSE[d]
        assert np.abs(rates[took + 1, d] - (rates[took, d] + accelerations[took, d] * h)).max() <= 1e-12 * span


def test_the_guard_refuses_an_envelope_without_the_neutral_pose(cueing):
    """A stroke that leaves the neutral pose outside gives the guard nowhere to hold the reference:
    refused in one line at initialization."""
    with pytest.raises(FmuError) as caught:
        cueing({"guard": True, "limit.leg_length_max": 1.6})
    assert "guard: the neutral pose is outside the envelope" in str(caught.value)


DRIVE = ROOT / "examples" / "vehicle" / "drive.csv"


def test_the_shipped_drives_are_what_their_generator_writes():
    """drive.csv, slalom.csv, emergency_stop.csv: each what examples/vehicle/drive.py makes, and each
    the vehicle of its shipped scene."""
    import importlib.util
    from cosim.platform.scene import load_scene
    spec = importlib.util.spec_from_file_location("drive", ROOT / "examples" / "vehicle" / "drive.py")
    generator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generator)
    for name, (make, _) in generator.DRIVES.items():
        path = ROOT / "examples" / "vehicle" / name
        shipped = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
        assert path.read_text().splitlines()[1] == ",".join(generator.COLUMNS)
        np.testing.assert_allclose(shipped, make(), rtol=1e-9, atol=1e-12)
    for scene, drive_file in (("car_drive", "drive.csv"), ("slalom", "slalom.csv"),
                              ("emergency_stop", "emergency_stop.csv")):
        assert load_scene(ROOT / "examples" / "vehicle" / f"{scene}.toml").vehicle.name == drive_file


def test_a_recorded_drive_runs_as_the_same_motion_given_through_the_inputs(cueing):
    table = np.loadtxt(DRIVE, delimiter=",", comments="#", skiprows=2)

    def motion(t):
        return np.column_stack([np.interp(t, table[:, 0], table[:, 1 + k]) for k in range(6)])

    h = 2e-3
    recorded = cueing({"vehicle.file": str(DRIVE)})
    assert recorded.get("vehicle.rows") == len(table)
    _, _, from_file, rates_file, _ = drive(recorded, lambda t: np.zeros((len(t), 6)), h, 5000)
    _, _, from_inputs, rates_inputs, _ = drive(cueing(), motion, h, 5000)
    scale = np.abs(from_inputs - from_inputs[0]).max(axis=0) + 1e-300
    assert np.all(np.abs(from_file - from_inputs).max(axis=0) <= 1e-9 * scale)
    assert np.abs(from_inputs[:, 4]).max() > 0.01  # the braking tilted it


def test_an_excel_csv_is_read_as_the_plain_one(cueing, tmp_path):
    """A table saved by Excel (a UTF-8 byte order mark, CRLF line ends) drives the cueing exactly as
    the same table written plainly."""
    plain = (ROOT / "examples/vehicle/drive.csv").read_text().splitlines()[1:400]  # its comment line left out
    files = {"plain.csv": "\n".join(plain) + "\n", "excel.csv": "\ufeff" + "\r\n".join(plain) + "\r\n"}
    runs = []
    for name, text in files.items():
        (tmp_path / name).write_bytes(text.encode("utf-8"))
        instance = cueing({"vehicle.file": str(tmp_path / name)})
        runs.append([instance.get("pose_ref.x") for _ in range(300) if instance.do_step(0.01) is None])
    assert np.ptp(runs[0]) > 0.01 and runs[0] == runs[1]


@pytest.mark.parametrize("text, message", [
    ("time,specific_force.w\n0,1\n", ":1: column 'specific_force.w' is unknown (use specific_force.x, specific_force.y, "
                                     "specific_force.z, angular_rate.x, angular_rate.y, angular_rate.z, each once)"),
    ("time,specific_force.x\n0,1\n0,2\n", ":3: time 0 does not increase"),
    ("time,specific_force.x\n0,1\n0.1,fast\n", ":3: expected 2 finite numbers separated by commas"),
    ("time,angular_rate.z\n", ": no rows after the header"),
    ("speed,angular_rate.z\n0,1\n", ":1: the first column must be 'time'"),
    ("time;specific_force.x\n0;1\n", ":1: the columns are separated by ';': separate them by ','"),
])
def test_bad_vehicle_tables_are_one_line_each(cueing, tmp_path, text, message):
    path = tmp_path / "drive.csv"
    path.write_text(text)
    with pytest.raises(FmuError) as caught:
        cueing({"vehicle.file": str(path)})
    logged = [m.text for m in caught.value.messages if "vehicle.file" in m.text]
    assert len(logged) == 1 and message in logged[0] and str(path) in logged[0]
