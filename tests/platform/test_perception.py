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
    """K (1 + tau_a s) / ((1 + tau_L s)(1 + tau_S s)) with K = 0.4, tau_a = 13.2 s, tau_L = 5.33 s,
    tau_S = 0.66 s (Young and Meiry 1968, as Telban and Cardullo 2005 give them): a sustained
    specific force is sensed at 0.4 of it; a step of 1 m/s^2 gives
    K [1 + (tau_a - tau_L)/(tau_L - tau_S) e^(-t/tau_L) - (tau_a - tau_S)/(tau_L - tau_S) e^(-t/tau_S)]
    (its partial fractions); the gain at each frequency is the published magnitude, largest (0.89)
    near 0.5 rad/s."""
    K, tau_a, tau_L, tau_S = 0.4, 13.2, 5.33, 0.66
    assert OTOLITH.static_gain() == pytest.approx(K, rel=1e-12)
    for w in (0.05, 0.2, 0.5, 1.0, 1.5, 5.0, 20.0):
        published = K * math.hypot(1, tau_a * w) / (math.hypot(1, tau_L * w) * math.hypot(1, tau_S * w))
        assert abs(OTOLITH.response(np.array([w]))[0]) == pytest.approx(published, rel=1e-12)
    w = np.logspace(-2, 2, 4001)
    gain = np.abs(OTOLITH.response(w))
    assert gain.max() == pytest.approx(0.891, abs=1e-3) and 0.4 < w[gain.argmax()] < 0.6
    t = np.arange(0, 40.0, 1e-3)
    u = np.where(t > 0, 1.0, 0.0)
    a, b = (tau_a - tau_L) / (tau_L - tau_S), -(tau_a - tau_S) / (tau_L - tau_S)
    exact = K * (1 + a * np.exp(-t / tau_L) + b * np.exp(-t / tau_S))
    # the step between the first two samples is a ramp to the recursion: compare from 10 ms on
    late = t > 0.01
    assert np.abs(OTOLITH.perceive(t, u)[late] - exact[late] - (OTOLITH.perceive(t, u) - exact)[late][-1]).max() < 2e-3
    assert OTOLITH.perceive(t, u)[-1] == pytest.approx(K, abs=2e-3)


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
    the other sign: a sign error wherever both are felt; a cue where the vehicle has none:
    spurious; a vehicle's cue the platform leaves out: missing."""
    t = np.arange(0, 20.0, 1e-2)
    vehicle = np.zeros((len(t), 6))
    vehicle[:, 0] = 2.0 * np.sin(0.5 * t)
    vehicle[:, 5] = 0.2 * np.sin(0.7 * t)
    same = quality(perceive(t, vehicle, vehicle))
    assert all(q.rms_error == 0.0 and q.false_cue_time == 0.0 and q.missing_time == 0.0 for q in same)
    assert same[0].correlation == pytest.approx(1.0) and math.isnan(same[1].correlation)
    wrong = vehicle.copy()
    wrong[:, 0] *= -1
    wrong[:, 3] = np.where(t > 5.0, 0.2, 0.0)  # a roll the vehicle does not have: felt at first, then faded
    wrong[:, 5] = 0.0                         # the yaw left out
    felt = perceive(t, vehicle, wrong)
    q = quality(felt)
    assert q[0].correlation == pytest.approx(-1.0)
    both = (np.abs(felt.platform_perceived[:, 0]) > THRESHOLDS[0]) & (np.abs(felt.vehicle_perceived[:, 0]) > THRESHOLDS[0])
    assert q[0].sign_error_time == pytest.approx(both.sum() * 1e-2) and q[0].sign_error_time > 10.0
    assert q[0].spurious_time == q[0].missing_time == 0.0  # the same size, so felt together
    assert q[3].spurious_time > 0 and q[3].spurious_largest > THRESHOLDS[3] and q[3].sign_error_time == 0.0
    yaw_felt = np.abs(felt.vehicle_perceived[:, 5]) > THRESHOLDS[5]
    assert q[5].missing_time == pytest.approx(yaw_felt.sum() * 1e-2) and q[5].missing_time > 5.0
    assert q[5].missing_largest == pytest.approx(np.abs(felt.vehicle_perceived[:, 5]).max())
    assert q[5].false_cue_time == 0.0
    assert [c.channel for c in q] == list(CHANNELS)


def test_the_cue_kinds_on_constructed_signals():
    """Felt means beyond the threshold: each sample is spurious, a sign error, missing or none."""
    from cosim.platform.perception import cue_kinds
    vehicle = np.array([0.0, 0.5, 0.5, -0.5, 0.05, 0.0])
    platform = np.array([0.5, 0.5, -0.5, 0.05, 0.5, 0.05])
    kinds = cue_kinds(vehicle, platform, 0.17)
    assert kinds["spurious"].tolist() == [True, False, False, False, True, False]
    assert kinds["sign error"].tolist() == [False, False, True, False, False, False]
    assert kinds["missing"].tolist() == [False, False, False, True, False, False]


def test_the_vehicle_at_rest_feels_nothing():
    """A vehicle table's 1 g at rest is no heave cue."""
    motion = vehicle_motion(np.tile([0.0, 0.0, 9.80665], (5, 1)), np.zeros((5, 3)), 9.80665)
    assert np.abs(motion).max() == 0.0
    assert isinstance(perceive(np.arange(5.0), motion, motion), Perceived)


def test_an_error_below_the_indifference_threshold_is_not_felt():
    """The perceived error counts what passes each channel's threshold: a perceived error of half a
    threshold everywhere counts nothing; of twice a threshold in one channel, one threshold for as
    long as it lasts (rms over the run: its root of the fraction of time)."""
    from cosim.platform.perception import perceived_error, quality
    t = np.arange(0, 10.0, 1e-2)
    felt = np.zeros((len(t), 6))
    felt[:, 0] = np.sin(t)

    def measured(platform: np.ndarray) -> float:
        return perceived_error(quality(Perceived(t, felt, felt, felt, platform)))

    assert measured(felt + 0.5 * THRESHOLDS) == 0.0
    doubled = felt.copy()
    doubled[t >= 7.5, 2] += 2.0 * THRESHOLDS[2]  # the last quarter of the run
    assert measured(doubled) == pytest.approx(math.sqrt(0.25), rel=1e-9)


def test_the_second_model_is_the_published_one():
    """The second opinion's organs (Reid and Nahon 1985, cosim.platform.perception.SECOND_ORGANS):
    the otoliths' static gain 0.4 and their response 0.4 (1 + 10 s) / ((1 + 5 s)(1 + 0.016 s)) at
    a few frequencies; the canals' 80 * 5.73 s^2 / ((1 + 80 s)(1 + 5.73 s)): no response to a
    constant rate, unit gain between their corners; scipy's simulation of both equals theirs."""
    from cosim.platform.perception import SECOND_CANAL, SECOND_OTOLITH
    w = np.array([0.01, 0.3, 2.0, 30.0])
    s = 1j * w
    assert np.allclose(SECOND_OTOLITH.response(w), 0.4 * (1 + 10 * s) / ((1 + 5 * s) * (1 + 0.016 * s)), rtol=1e-12)
    assert SECOND_OTOLITH.static_gain() == pytest.approx(0.4)
    assert np.allclose(SECOND_CANAL.response(w), 80 * 5.73 * s ** 2 / ((1 + 80 * s) * (1 + 5.73 * s)), rtol=1e-12)
    assert abs(SECOND_CANAL.response(np.array([3.0]))[0]) == pytest.approx(1.0, abs=0.01)
    t = np.arange(0, 30.0, 1e-3)
    u = np.sin(0.7 * t) + (t > 3.0)
    for organ in (SECOND_OTOLITH, SECOND_CANAL):
        _, expected, _ = lsim(ZerosPolesGain(organ.zeros, organ.poles, organ.gain), u - u[0], t)
        assert np.abs(organ.perceive(t, u) - organ.static_gain() * u[0] - expected).max() < 1e-6
