"""The trajectory FMU: its signals against their formulas, its output derivatives against finite
differences, its CSV table, and its errors."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.engine.fmi import FmuError, FmuInstance
from cosim.engine.artifacts import fmu_path
from cosim.platform.scene import Pulse, Ramp, Signal, Sine, Step
from cosim.platform.scene.signals import trajectory_parameters

POSE = ("x", "y", "z", "roll", "pitch", "yaw")


@pytest.fixture
def make_trajectory():
    made = []

    def make(values: dict, initialize: bool = True) -> FmuInstance:
        instance = FmuInstance(fmu_path("trajectory"), f"trajectory{len(made)}")
        made.append(instance)
        if initialize:
            instance.initialize(values)
        return instance

    yield make
    for instance in made:
        instance.free()


SIGNALS = {"x": Signal(0.1, [Sine(0.2, 0.5, 0.3), Sine(0.05, 2.0)], [Step(0.35, 0.01)], [Ramp(0.1, 0.6, 0.02)]),
           "yaw": Signal(0.0, [Sine(0.1, 1.5)], [], [Ramp(0.2, 0.4, -0.3), Ramp(0.5, 0.9, 0.1)])}


def x_formula(t):
    return (0.1 + 0.2 * np.sin(np.pi * t + 0.3) + 0.05 * np.sin(4 * np.pi * t) + 0.01 * (t >= 0.35)
            + 0.02 * (np.clip(t, 0.1, 0.6) - 0.1))


def sample(instance: FmuInstance, names: list[str], h: float, n: int):
    group = instance.real_group(names)
    rows, rates, curvatures = [group.read().copy()], [group.read_derivatives(1)], [group.read_derivatives(2)]
    for _ in range(n):
        instance.do_step(h)
        rows.append(group.read().copy())
        rates.append(group.read_derivatives(1))
        curvatures.append(group.read_derivatives(2))
    return np.arange(n + 1) * h, np.array(rows), np.array(rates), np.array(curvatures)


def test_signals_follow_their_formulas_and_unset_coordinates_hold_their_offsets(make_trajectory):
    trajectory = make_trajectory(trajectory_parameters(SIGNALS, [Pulse("force.z", 500.0, 0.25, 0.27)]))
    t, rows, _, _ = sample(trajectory, ["pose_ref.x", "pose_ref.z", "load.force.z", "load.torque.x"], 1e-3, 1000)
    np.testing.assert_allclose(rows[:, 0], x_formula(t), atol=1e-12)
    assert np.all(rows[:, 1] == 0.0)  # every offset is set by trajectory_parameters, z's too
    pulse = (t >= 0.25 - 1e-9) & (t <= 0.27 + 1e-9)
    np.testing.assert_allclose(rows[:, 2], np.where(pulse, 500.0, 0.0))
    assert np.all(rows[:, 3] == 0.0)


def test_default_pose_is_the_meng_platform_at_rest(make_trajectory):
    """Without parameters, another FMI tool gets a reference at the Meng platform's neutral pose."""
    trajectory = make_trajectory({})
    pose = trajectory.real_group([f"pose_ref.{a}" for a in POSE]).read()
    np.testing.assert_array_equal(pose, [0, 0, 1.689527733348906, 0, 0, 0])


def test_output_derivatives_match_central_differences(make_trajectory):
    """fmi2GetRealOutputDerivatives against central differences of the outputs, away from the steps
    and ramp corners: first derivative within 1e-6 (the O(h^2) difference error at h = 1e-4 s is
    ~1e-7 here), second within 1e-3."""
    trajectory = make_trajectory(trajectory_parameters(SIGNALS))
    h = 1e-4
    t, rows, rates, curvatures = sample(trajectory, ["pose_ref.x", "pose_ref.yaw"], h, 10000)
    corners = np.array([0.1, 0.2, 0.35, 0.4, 0.5, 0.6, 0.9])
    smooth = np.min(np.abs(t[1:-1, None] - corners[None, :]), axis=1) > 2 * h
    first = (rows[2:] - rows[:-2]) / (2 * h)
    second = (rows[2:] - 2 * rows[1:-1] + rows[:-2]) / h**2
    np.testing.assert_allclose(rates[1:-1][smooth], first[smooth], atol=1e-6)
    np.testing.assert_allclose(curvatures[1:-1][smooth], second[smooth], atol=1e-3)


def test_the_rate_outputs_are_the_pose_rate_with_its_own_exact_derivatives(make_trajectory, tmp_path):
    """pose_ref_rate.* (for masters without input derivatives) is pose_ref's first derivative bit for
    bit, its first derivative pose_ref's second, and its second (the jerk) the central difference
    of the curvature away from the corners: within 1e-6 of the jerk's range (the difference's O(h^2)
    error, h^2/6 of the fifth derivative, is ~1e-7 of it here); for a cubic table too, whose jerk is
    constant on each interval."""
    path = tmp_path / "table.csv"
    times = np.linspace(0.0, 1.0, 11)
    path.write_text("time,y\n" + "".join(f"{a},{0.1 * np.sin(2 * np.pi * a)}\n" for a in times))
    trajectory = make_trajectory({**trajectory_parameters(SIGNALS), "table.file": str(path), "table.interpolation": 2})
    names = ["pose_ref.x", "pose_ref.yaw", "pose_ref.y"]
    h = 1e-4
    t, rows, rates, curvatures = sample(trajectory, names + [n.replace("pose_ref", "pose_ref_rate") for n in names],
                                        h, 10000)
    n = len(names)
    assert np.array_equal(rows[:, n:], rates[:, :n]) and np.array_equal(rates[:, n:], curvatures[:, :n])
    corners = np.array([0.1, 0.2, 0.35, 0.4, 0.5, 0.6, 0.9, *times])
    smooth = np.min(np.abs(t[1:-1, None] - corners[None, :]), axis=1) > 2 * h
    jerk = (curvatures[2:, :n] - curvatures[:-2, :n]) / (2 * h)
    for k in range(n):
        scale = np.abs(jerk[smooth, k]).max()
        assert np.abs(curvatures[1:-1, n + k][smooth] - jerk[smooth, k]).max() <= 1e-6 * scale, names[k]


@pytest.mark.parametrize("interpolation,order", [(1, 2), (2, 3)])
def test_table_interpolation_converges_with_its_order(make_trajectory, tmp_path, interpolation, order):
    """A table of sin(2 pi t) sampled every dt: the interpolation error falls as dt^2 (linear) and
    dt^3 (cubic Hermite whose slopes, three-point differences, are second-order accurate; the end
    intervals, with one-sided slopes, are left out), within 0.3 of the order."""
    errors = []
    for rows in (21, 41, 81):
        times = np.linspace(0.0, 1.0, rows)
        path = tmp_path / f"table{rows}.csv"
        np.savetxt(path, np.c_[times, np.sin(2 * np.pi * times)], delimiter=",", header="time,z", comments="")
        trajectory = make_trajectory({"table.file": str(path), "table.interpolation": interpolation, "z.offset": 0.0})
        assert trajectory.get("table.rows") == rows
        assert trajectory.get("table.file") == str(path)
        t, values, _, _ = sample(trajectory, ["pose_ref.z"], 1e-3, 1000)
        inside = (t > 0.1) & (t < 0.9)
        errors.append(np.abs(values[:, 0] - np.sin(2 * np.pi * t))[inside].max())
    fitted = np.polyfit(np.log([1 / 20, 1 / 40, 1 / 80]), np.log(errors), 1)[0]
    assert abs(fitted - order) < 0.3, (errors, fitted)


@pytest.mark.parametrize("content,message", [
    (None, "'table.file' = \"{path}\": cannot be opened for reading"),
    ("time,x\n0,0\n0,1\n", "{path}:3: time 0 does not increase"),
    ("time,x\n0,0\n1,nan\n", "{path}:3: expected 2 finite numbers"),
    ("time,x,x\n0,0,0\n", "{path}:1: column 'x' is repeated"),
    ("t,x\n0,0\n", "{path}:1: the first column must be 'time'"),
    ("time,surge\n0,0\n", "{path}:1: column 'surge' is unknown"),
    ("time,x\n", "{path}: no rows after the header"),
])
def test_a_bad_table_is_named_with_its_line(make_trajectory, tmp_path, content, message):
    path = tmp_path / "bad.csv"
    if content is not None:
        path.write_text(content)
    with pytest.raises(FmuError) as error:
        make_trajectory({"table.file": str(path)})
    assert "fmi2EnterInitializationMode" in str(error.value)
    assert message.format(path=path) in str(error.value)


def test_a_ramp_ending_before_it_starts_is_rejected(make_trajectory):
    with pytest.raises(FmuError) as error:
        make_trajectory({"x.ramp[1].start": 1.0, "x.ramp[1].end": 0.5})
    assert "'x.ramp[1].end' = 0.5 s: must not be before the ramp's start" in str(error.value)


def test_a_string_parameter_too_long_is_rejected(make_trajectory):
    trajectory = make_trajectory({}, initialize=False)
    with pytest.raises(FmuError) as error:
        trajectory.set({"table.file": "x" * 2000})
    assert "'table.file' rejected: longer than 1023 bytes" in str(error.value)


def test_the_table_is_not_part_of_the_fmu_state(make_trajectory, tmp_path):
    """The table stays with the instance (model data), so FMU states stay small; a state restored
    gives the same outputs."""
    path = tmp_path / "big.csv"
    times = np.linspace(0, 10, 20001)
    np.savetxt(path, np.c_[times, 0.01 * times], delimiter=",", header="time,x", comments="")
    trajectory = make_trajectory({"table.file": str(path)})
    small = make_trajectory({})
    trajectory.do_step(0.5)
    state = trajectory.get_state()
    assert len(trajectory.serialize_state(state)) == len(small.serialize_state(small.get_state()))
    trajectory.do_step(0.5)
    later = trajectory.get("pose_ref.x")
    trajectory.set_state(state)
    trajectory.do_step(0.5)
    assert trajectory.get("pose_ref.x") == later == pytest.approx(0.01)
