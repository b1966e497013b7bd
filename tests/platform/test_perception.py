"""The measure of motion cueing (cosim.platform.perception): the vestibular models against their
published transfer functions and responses, their exact recursion against scipy's lsim, the
platform's motion at the head against motions whose specific force and angular velocity are known
in closed form, and the quality figures on motions whose answer is known."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import ZerosPolesGain, lsim
from scipy.spatial.transform import Rotation

from cosim.platform.perception import (CANAL, CHANNELS, OTOLITH, THRESHOLDS, Perceived, perceive, platform_motion,
                                       quality, vehicle_motion)

G = 9.81


@pytest.mark.parametrize("organ", [OTOLITH, CANAL], ids=["otolith", "canal"])
def test_the_recursion_is_the_transfer_function_exactly(organ):
    """The per-mode recursion (exact for inputs linear between samples) against scipy's lsim of the
    same transfer function from the same settled state, on a rough random input."""
    rng = np.random.default_rng(3)
    t = np.arange(4001) * 2e-3
    u = 1.0 + np.cumsum(rng.standard_normal(len(t))) * 0.05
    ss = ZerosPolesGain(organ.zeros, organ.poles, organ.gain).to_ss()
    settled = np.linalg.solve(ss.A, -ss.B[:, 0] * u[0])
    _, expected, _ = lsim(ss, u, t, X0=settled)
    assert np.abs(organ.perceive(t, u) - expected).max() < 1e-9 * np.abs(expected).max()


def test_the_otoliths_are_young_and_meirys():
    """1.5 (s + 0.076) / ((s + 0.19)(s + 1.5)): a sustained specific force is sensed at 0.4 of it;
    a step of 1 m/s^2 gives 0.4 + 0.687 e^(-0.19 t) - 1.087 e^(-1.5 t) (its partial fractions)."""
    assert OTOLITH.static_gain() == pytest.approx(0.4, rel=1e-12)
    t = np.arange(0, 40.0, 1e-3)
    u = np.where(t > 0, 1.0, 0.0)
    u[0] = 0.0
    a = 1.5 * (-0.19 + 0.076) / (-0.19 * (-0.19 + 1.5))
    b = 1.5 * (-1.5 + 0.076) / (-1.5 * (-1.5 + 0.19))
    assert a == pytest.approx(0.687, abs=1e-3) and b == pytest.approx(-1.087, abs=1e-3)
    exact = 0.4 + a * np.exp(-0.19 * t) + b * np.exp(-1.5 * t)
    # the step between the first two samples is a ramp to the recursion: compare from 10 ms on
    late = t > 0.01
    assert np.abs(OTOLITH.perceive(t, u)[late] - exact[late] - (OTOLITH.perceive(t, u) - exact)[late][-1]).max() < 2e-3
    assert OTOLITH.perceive(t, u)[-1] == pytest.approx(0.4, abs=2e-3)


def test_the_canals_sense_rotation_between_their_time_constants_and_forget_a_steady_one():
    """Unit gain from about 0.1 to 1 Hz (the lead tau_L lifts it above 1 / (2 pi tau_L) = 2.7 Hz);
    no sense of a steady rotation; a step to a constant rate
    felt at once and fading with the cupula's time constant (5.73 s, the adaptation's 80 s slowing
    it a little)."""
    for hz in (0.1, 0.3, 1.0):
        assert abs(CANAL.response(np.array([2 * math.pi * hz]))[0]) == pytest.approx(1.0, abs=0.08)
    assert abs(CANAL.response(np.array([2 * math.pi * 1e3]))[0]) == pytest.approx(0.06 / 0.005, rel=1e-3)
    assert CANAL.static_gain() == 0.0
    t = np.arange(0, 30.0, 1e-3)
    rate = np.where(t >= 1.0, 1.0, 0.0)
    felt = CANAL.perceive(t, rate)
    after = t >= 1.0
    assert felt[after].max() > 5.0  # the jump itself: the lead tau_L over tau_2 (12 for a true step)
    assert 0.9 < felt[t >= 1.2][0] < 1.05  # felt at once, its rate sensed whole
    fade = t[after][np.argmax(felt[after] < felt[after][200] / math.e)] - t[after][200]
    assert 5.0 < fade < 6.0


def test_a_steady_motion_is_felt_steadily_from_the_start():
    """Each model starts settled on its input's first value: a vehicle at rest (1 g), or cruising in
    a curve, gives a constant perceived motion, not a start-up transient."""
    t = np.arange(0, 10.0, 1e-3)
    for organ, value in ((OTOLITH, G), (OTOLITH, -2.5), (CANAL, 0.3)):
        felt = organ.perceive(t, np.full(len(t), value))
        assert np.abs(felt - organ.static_gain() * value).max() < 1e-12 * max(1.0, abs(value))


def poses_of(times: np.ndarray, position, angles) -> np.ndarray:
    return np.column_stack([*(np.broadcast_to(p, times.shape) for p in position),
                            *(np.broadcast_to(a, times.shape) for a in angles)]).astype(float)


def test_a_tilted_platform_at_rest_feels_gravity_along_its_axes():
    """Pitch theta and roll phi at rest: f = R^T (0, 0, g), f_x = -g sin(theta), f_y = g cos(theta)
    sin(phi), heave cue g cos(theta) cos(phi) - g, no rotation."""
    t = np.linspace(0.0, 1.0, 101)
    theta, phi = 0.1, -0.05
    motion = platform_motion(t, poses_of(t, (0, 0, 1.7), (phi, theta, 0.3)), np.zeros((len(t), 6)), np.zeros(3),
                             np.array([0.0, 0.0, -G]))
    expected = [-G * math.sin(theta), G * math.cos(theta) * math.sin(phi), G * math.cos(theta) * math.cos(phi) - G,
                0, 0, 0]
    assert np.abs(motion - expected).max() < 1e-12


def test_a_head_away_from_the_axis_of_a_turn_feels_the_centripetal_and_tangential_force():
    """A yaw turning at w(t) = 0.5 + 0.2 t about the platform's origin, the head 1 m forward:
    f_x = -w^2 r (towards the axis), f_y = w' r, angular rate w about z; to the differences' second order."""
    t = np.arange(0, 2.0, 1e-3)
    w = 0.5 + 0.2 * t
    yaw = 0.5 * t + 0.1 * t ** 2
    twist = np.column_stack([np.zeros((len(t), 5)), w])
    motion = platform_motion(t, poses_of(t, (0, 0, 1.7), (0, 0, 0)) + np.c_[np.zeros((len(t), 5)), yaw], twist,
                             np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -G]))
    assert np.abs(motion[:, 0] + w ** 2).max() < 1e-9
    assert np.abs(motion[:, 1] - 0.2).max() < 1e-9
    assert np.abs(motion[:, 5] - w).max() < 1e-12 and np.abs(motion[:, [2, 3, 4]]).max() < 1e-12


def test_a_surge_oscillation_is_felt_as_its_acceleration_to_second_order():
    """x = A sin(omega t): f_x = -A omega^2 sin(omega t); the error of the differences falls as h^2."""
    errors = []
    for h in (2e-3, 1e-3):
        t = np.arange(0, 3.0, h)
        x, v = 0.1 * np.sin(2.0 * t), 0.2 * np.cos(2.0 * t)
        twist = np.column_stack([v, np.zeros((len(t), 5))])
        motion = platform_motion(t, poses_of(t, (0, 0, 1.7), (0, 0, 0)) + np.c_[x, np.zeros((len(t), 5))], twist,
                                 np.zeros(3), np.array([0.0, 0.0, -G]))
        errors.append(np.abs(motion[1:-1, 0] + 0.4 * np.sin(2.0 * t[1:-1])).max())
    assert errors[1] < 1e-6 and errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)


def test_the_body_angular_velocity_is_the_rotations_own():
    """w_head = R^T w for a general rotation: against the rotation matrices' own derivative
    (R^T R' = [w_head]x)."""
    t = np.arange(0, 1.0, 1e-4)
    angles = np.column_stack([0.1 * np.sin(3 * t), 0.2 * np.cos(2 * t), 0.3 * t])
    R = Rotation.from_euler("ZYX", angles[:, ::-1]).as_matrix()
    derivative = np.gradient(R, t, axis=0, edge_order=2)
    skew = np.einsum("nji,njk->nik", R, derivative)
    body = np.column_stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]])
    w_base = np.einsum("nij,nj->ni", R, body)
    twist = np.column_stack([np.zeros((len(t), 3)), w_base])
    motion = platform_motion(t, poses_of(t, (0, 0, 1.7), (0, 0, 0)) + np.c_[np.zeros((len(t), 3)), angles], twist,
                             np.zeros(3), np.array([0.0, 0.0, -G]))
    assert np.abs(motion[:, 3:] - body).max() < 1e-12


def test_the_quality_figures_on_motions_whose_answer_is_known():
    """The platform's cue a copy of the vehicle's: no error, correlation 1, no false cue; its cue of
    the other sign: a false cue wherever it is felt; a cue where the vehicle has none: false too."""
    t = np.arange(0, 20.0, 1e-2)
    vehicle = np.zeros((len(t), 6))
    vehicle[:, 0] = 2.0 * np.sin(0.5 * t)
    vehicle[:, 5] = 0.2 * np.sin(0.7 * t)
    same = quality(perceive(t, vehicle, vehicle))
    assert all(q.rms_error == 0.0 and q.false_cue_time == 0.0 for q in same)
    assert same[0].correlation == pytest.approx(1.0) and math.isnan(same[1].correlation)
    wrong = vehicle.copy()
    wrong[:, 0] *= -1
    wrong[:, 3] = np.where(t > 5.0, 0.2, 0.0)  # a roll the vehicle does not have: felt at first, then faded
    felt = perceive(t, vehicle, wrong)
    q = quality(felt)
    assert q[0].correlation == pytest.approx(-1.0)
    expected = np.sum(np.abs(felt.platform_perceived[:, 0]) > THRESHOLDS[0]) * 1e-2
    assert q[0].false_cue_time == pytest.approx(expected) and q[0].false_cue_time > 10.0
    assert q[3].false_cue_time > 0 and q[3].largest_false_cue > THRESHOLDS[3]
    assert [c.channel for c in q] == list(CHANNELS)


def test_the_vehicle_at_rest_feels_nothing():
    """A vehicle table's 1 g at rest is no heave cue."""
    motion = vehicle_motion(np.tile([0.0, 0.0, 9.80665], (5, 1)), np.zeros((5, 3)), 9.80665)
    assert np.abs(motion).max() == 0.0
    assert isinstance(perceive(np.arange(5.0), motion, motion), Perceived)
