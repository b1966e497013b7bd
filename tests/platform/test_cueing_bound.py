"""The floor under every cueing (cosim.platform.design.cueing_bound): the least perceived error any
platform motion within the stroke, the joints and the tilt rate limit could reach, knowing the whole
drive. It is the conic program's dual bound, reached by a motion the project's own perception
measure finds as far from the vehicle; it is converged in its samples; it is exact where the
answer is known (a platform frozen feels what standing still feels; a motion the platform can make
is felt exactly); and no cueing, with foresight or without, classical or MPC, feels closer."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT
from cosim.platform.core import Core
from cosim.platform.design.cueing import screen
from cosim.platform.design.cueing_bound import WIDEN, excursion_ranges, least_perceived_error, scene_bound
from cosim.platform.perception import perceive, perceived_error, quality
from cosim.platform.scene import load_scene

VEHICLE = ROOT / "examples" / "vehicle"
STROKE, JOINT = (1.535, 2.2), math.radians(20.0)  # Meng's platform, Table 4
LIMIT = math.radians(2.5)


@pytest.fixture(scope="module")
def emergency_stop():
    return load_scene(VEHICLE / "emergency_stop.toml")


@pytest.fixture(scope="module")
def floor(emergency_stop):
    return scene_bound(emergency_stop)


@pytest.fixture(scope="module")
def ranges():
    return excursion_ranges(Core(), STROKE, JOINT)


def test_the_floor_is_the_programs_optimum_measured_and_converged(emergency_stop, floor):
    """The best motion found, measured by cosim.platform.perception, feels as far from the vehicle as
    the program's dual bound says, to the solver's tolerance (the dead zone's slack is the
    indifference threshold's): the floor is reached; halving the samples' spacing moves it by less
    than 0.5 %."""
    assert floor.perceived_error <= floor.reached <= floor.perceived_error * (1 + 1e-5)
    assert floor.tilt_rate_limit == pytest.approx(LIMIT)
    assert scene_bound(emergency_stop, step=0.005).perceived_error == pytest.approx(floor.perceived_error, rel=0.005)
    tilt = np.diff(floor.excursions[:, 4]) / floor.step
    assert np.abs(tilt).max() <= LIMIT * (1 + 1e-6)  # the braking is felt by tilting, at the limit's rate at most
    assert np.abs(floor.excursions[:, 4]).max() > math.radians(5.0)


def test_the_excursions_are_the_workspaces_extremes(ranges):
    """Each DOF's extreme is reached at a pose within the stroke and joints (the program's relaxation
    rests on them), the platform's symmetry about its x-z plane holds (y and roll symmetric); the surge
    reaches 0.5-1 m (the other DOFs free: the relaxation), the pitch past the joints' 20 deg."""
    assert ranges[1, 0] == pytest.approx(-ranges[1, 1], rel=1e-3)
    assert ranges[3, 0] == pytest.approx(-ranges[3, 1], rel=1e-3)
    assert np.all(ranges[:, 0] < 0) and np.all(ranges[:, 1] > 0)
    assert 0.5 < ranges[0, 1] < 1.0 and math.radians(20) < ranges[4, 1] < math.radians(45)


def test_a_frozen_platform_feels_what_standing_still_feels(emergency_stop, floor):
    """No excursion, no tilt: the floor is the error of the platform standing still, measured directly."""
    times = floor.times
    vehicle = np.zeros((len(times), 6))
    d = np.genfromtxt(VEHICLE / "emergency_stop.csv", delimiter=",", names=True, skip_header=1)
    vehicle[:, 0] = np.interp(times, d["time"], d["specific_forcex"])
    frozen = least_perceived_error(times, vehicle, np.zeros((6, 2)), 0.0)
    still = perceived_error(quality(perceive(times, vehicle, np.zeros_like(vehicle))))
    assert frozen.perceived_error == pytest.approx(still, rel=1e-6)
    assert frozen.reached == pytest.approx(still, rel=1e-6)
    assert floor.perceived_error < 0.8 * still


def test_a_motion_the_platform_can_make_is_felt_exactly(ranges):
    """A vehicle whose motion is one the platform can make (a surge of 0.1 m and a pitch of 3 deg,
    turning within the tilt's limit beyond the vehicle's own pitch rate, a sway and a yaw) leaves no
    felt error: the program's model of the platform and of perception is the measure's own."""
    step, times = 0.01, np.arange(0.0, 12.0 + 0.005, 0.01)
    bump = np.where(times < 10.0, np.sin(np.pi * times / 10.0) ** 2, 0.0)
    motion = {0: 0.1 * bump, 1: -0.05 * bump, 4: math.radians(3.0) * bump, 5: math.radians(4.0) * bump}

    def acceleration(p):  # piecewise constant between samples, as the program takes it
        v = np.r_[np.diff(p) / step, 0.0]
        return np.r_[np.diff(v) / step, 0.0]
    vehicle = np.zeros((len(times), 6))
    vehicle[:, 0] = acceleration(motion[0]) - 9.81 * motion[4]
    vehicle[:, 1] = acceleration(motion[1])
    vehicle[:, 4] = np.r_[np.diff(motion[4]) / step, 0.0]
    vehicle[:, 5] = np.r_[np.diff(motion[5]) / step, 0.0]
    exact = least_perceived_error(times, vehicle, ranges, LIMIT, step=step)
    assert exact.perceived_error < 1e-6 and exact.reached < 1e-6


def test_a_motion_optimised_without_the_dead_zone_is_felt_above_the_floor(emergency_stop, floor):
    """Counting every error, below the thresholds too (the MPC's quadratic cost does), the best motion
    is one the measure finds above the floor (the floor is least), and below what that program
    counted (the measure forgives the errors within the thresholds)."""
    counted = scene_bound(emergency_stop, dead_zone=False)
    assert floor.perceived_error < counted.reached < counted.perceived_error


def test_the_floor_falls_as_the_tilt_may_turn_faster(emergency_stop, floor):
    faster = [scene_bound(emergency_stop, math.radians(rate)).perceived_error for rate in (5.0, 10.0)]
    assert floor.perceived_error > faster[0] > faster[1]


def test_a_braking_is_held_back_by_the_pitch_rate_alone(emergency_stop, floor):
    """The emergency stop brakes straight (no sway, no roll): with a pitch rate limit of its own
    (tilt.pitch_rate_limit) the floor is that of both axes at pitch's limit; roll's limit raised alone
    leaves it where it was."""
    fast = math.radians(5.0)
    both = scene_bound(emergency_stop, fast).perceived_error
    assert scene_bound(emergency_stop, LIMIT, pitch_rate_limit=fast).perceived_error == pytest.approx(both, rel=1e-4)
    assert scene_bound(emergency_stop, fast, pitch_rate_limit=LIMIT).perceived_error == pytest.approx(
        floor.perceived_error, rel=1e-4)
    assert both < 0.9 * floor.perceived_error


@pytest.mark.parametrize("changes", [{"cueing.algorithm": "classical"},
                                     {"cueing.algorithm": "mpc", "cueing.preview": 3.0},
                                     {"cueing.algorithm": "mpc", "cueing.preview": 0.0}],
                         ids=["classical", "MPC with 3 s of foresight", "MPC live"])
def test_no_cueing_feels_closer_than_the_floor(emergency_stop, floor, changes):
    """The scene's classical washout, the MPC reading the drive ahead and the live MPC, each screened
    (the platform on its reference), feel further from the vehicle than the floor."""
    judged = screen(emergency_stop.changed(changes), {})
    assert judged.perceived_error > floor.perceived_error


def test_no_pose_within_the_limits_reaches_past_the_excursions(ranges):
    """The relaxation holds only if the excursions are the workspace's true extremes (SLSQP finds
    local ones): searched from four times as many other starts, none reaches further than the
    percent the floor widens them by (WIDEN); of 200000 poses
    drawn uniformly from a box half as large again, every one that keeps its legs in the stroke and
    its joints within their angle lies within every DOF's excursion."""
    core = Core()
    for seed in (3, 7):
        assert np.all(np.abs(excursion_ranges(core, STROKE, JOINT, starts=12, seed=seed)) <= WIDEN * np.abs(ranges))
    rng = np.random.default_rng(20261206)
    poses = core.neutral_pose + rng.uniform(1.5 * ranges[:, 0], 1.5 * ranges[:, 1], size=(200_000, 6))
    kinematics = core.pose_kinematics(poses)
    tilt = np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    feasible = ((kinematics["length"] >= STROKE[0]) & (kinematics["length"] <= STROKE[1]) & (tilt <= JOINT)).all(axis=1)
    excursions = poses[feasible] - core.neutral_pose
    assert feasible.sum() > 100  # the draw reaches into the workspace
    assert np.all(excursions >= ranges[:, 0] - 1e-9) and np.all(excursions <= ranges[:, 1] + 1e-9)
