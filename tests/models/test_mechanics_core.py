"""The mechanics' plain-C dynamics core (fmu/mechanics/platform.c) against independent
computations: kinematics, Jacobians by finite differences, the mass matrix, energy and power."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from cosim.platform.core import Core, core_library


@pytest.fixture(scope="module")
def dll():
    return core_library()


@pytest.fixture
def core(dll):
    return Core(dll)


def random_poses(core, count, seed=1):
    rng = np.random.default_rng(seed)
    poses = []
    for _ in range(count):
        offset = np.concatenate([rng.uniform(-0.15, 0.15, 3), rng.uniform(-0.15, 0.15, 3)])
        poses.append(core.neutral_pose + offset)
    return poses


def test_neutral_layout_matches_the_parameter_set(core):
    """params/meng2010.toml: z0 = 1.68953 m so that every leg is l_0 = 1.86 m at the zero pose."""
    assert core.neutral_pose[2] == pytest.approx(1.68953, abs=1e-5)
    np.testing.assert_allclose(core.leg_lengths(core.neutral_pose), 1.86, rtol=1e-12)


def test_inverse_kinematics_against_an_independent_computation(core):
    """l_i = |t + R a_i - b_i| with R from scipy (extrinsic x-y-z = Rz Ry Rx)."""
    a = np.array(core.p.upper_joint[:]).reshape(6, 3)
    b = np.array(core.p.lower_joint[:]).reshape(6, 3)
    for pose in random_poses(core, 20):
        R = Rotation.from_euler("xyz", pose[3:]).as_matrix()
        expected = np.linalg.norm(pose[:3] + a @ R.T - b, axis=1)
        np.testing.assert_allclose(core.leg_lengths(pose), expected, rtol=1e-13)


def twist_motion(x, h):
    """State moved along its own twist for time h: t + h v, R -> exp(h [w]x) R."""
    y = x.copy()
    y[:3] = x[:3] + h * x[7:10]
    q = Rotation.from_quat(np.r_[x[4:7], x[3]])
    moved = Rotation.from_rotvec(h * x[10:13]) * q
    xyzw = moved.as_quat()
    y[3:7] = np.r_[xyzw[3], xyzw[:3]]
    return y


def test_leg_velocity_jacobian_against_finite_differences(core):
    """L_dot = n' (v + w x r) (Eqs 3-4, the leg rows of J_a,q and J_theta,q / i_theta) against
    central differences of the leg lengths along the twist: relative error <= 1e-6."""
    rng = np.random.default_rng(2)
    for pose in random_poses(core, 10):
        x = core.state(pose)
        x[7:] = rng.normal(size=6) * 0.3
        h = 1e-5
        lengths = lambda y: core.leg_lengths(np.r_[y[:3], Rotation.from_quat(np.r_[y[4:7], y[3]]).as_euler("xyz")])
        fd = (lengths(twist_motion(x, h)) - lengths(twist_motion(x, -h))) / (2 * h)
        np.testing.assert_allclose(core.leg_velocities(x), fd, rtol=1e-6, atol=1e-9)


def test_upper_joint_jacobian_against_finite_differences(core):
    """v_a = J_a,q u = t_dot + w x (R a_i) (Eq 3) against central differences of the core's upper
    joint positions along the twist: relative error <= 1e-6."""
    rng = np.random.default_rng(9)
    for pose in random_poses(core, 10, seed=10):
        x = core.state(pose)
        x[7:] = rng.normal(size=6) * 0.3
        h = 1e-5
        fd = (core.upper_joints(twist_motion(x, h)) - core.upper_joints(twist_motion(x, -h))) / (2 * h)
        arms = core.upper_joints(x) - x[:3]
        J_a_u = x[7:10] + np.cross(x[10:13], arms)
        np.testing.assert_allclose(J_a_u, fd, rtol=1e-6, atol=1e-9)


def test_mass_matrix_is_symmetric_positive_definite(core):
    for pose in random_poses(core, 30, seed=3):
        _, diag = core.derivatives(core.state(pose))
        M = np.array(diag.mass_matrix[:]).reshape(6, 6)
        np.testing.assert_allclose(M, M.T, atol=1e-9 * np.abs(M).max())
        assert np.linalg.eigvalsh(M).min() > 0


@pytest.mark.parametrize("switches,spin_and_joints", [((True, True, True), False), ((False, False, True), False),
                                                     ((True, False, False), False), ((True, True, True), True),
                                                     ((True, True, False), True)])
def test_power_balance_at_every_state(dll, switches, spin_and_joints):
    """dE/dt along the motion = drive power - transmission loss - friction loss + load power, at
    random states, torques, forces and wrenches. dE/dt is a central difference of the core's own
    energy along its own derivative (h = 1e-6 s); any term of M, of the velocity terms or of
    gravity that does not derive from the same energy breaks it by far more than 1e-6. With
    spin_and_joints, the legs turn with the platform (I_s = 0.5 kg m^2, exaggerated to be seen) and
    the joints have viscous friction (C_S = 3, C_U = 2 N m s/rad)."""
    core = Core(dll, *switches)
    if spin_and_joints:
        core.p.leg_spin_inertia, core.p.joint_friction_lower, core.p.joint_friction_upper = 0.5, 3.0, 2.0
    rng = np.random.default_rng(4)
    for pose in random_poses(core, 10, seed=5):
        x = core.state(pose)
        x[7:] = rng.normal(size=6) * 0.4
        torque, force, wrench = rng.normal(size=6) * 20, rng.normal(size=6) * 500, rng.normal(size=6) * 300
        dx, diag = core.derivatives(x, torque, force, wrench)
        h = 1e-6
        dE = (core.energy(x + h * dx) - core.energy(x - h * dx)) / (2 * h)
        expected = diag.drive_power - diag.transmission_loss - diag.friction_loss + diag.load_power
        scale = abs(diag.drive_power) + abs(diag.load_power) + diag.friction_loss + 1.0
        assert dE == pytest.approx(expected, abs=1e-6 * scale)


@pytest.mark.parametrize("gravity,duration", [(0.0, 10.0), (-9.81, 0.3)], ids=["weightless-10s", "falling-0.3s"])
def test_free_motion_conserves_energy(dll, gravity, duration):
    """Friction off, zero inputs, a random start twist, integrated by scipy's DOP853 at rtol 1e-10:
    kinetic plus potential energy stays constant. Weightless for 10 s (the platform drifts and
    tumbles with its legs in tow) and falling under gravity for 0.3 s (energy moves from potential
    to kinetic). The solver's local error is about rtol |x| per step over a few hundred steps, so
    the energy may drift by about 1e-8 of what is exchanged or carried; the bound is 1e-7."""
    core = Core(dll, friction=False)
    core.p.gravity[2] = gravity
    x0 = core.state(core.neutral_pose)
    x0[7:] = np.random.default_rng(8).normal(size=6) * 0.05
    sol = solve_ivp(lambda t, x: core.derivatives(x)[0], (0, duration), x0, method="DOP853", rtol=1e-10,
                    atol=1e-12, t_eval=np.linspace(0, duration, 21))
    assert sol.success
    energies = np.array([core.energy(x) for x in sol.y.T])
    kinetic = np.array([core.derivatives(x)[1].kinetic for x in sol.y.T])
    scale = np.ptp(kinetic) if gravity else kinetic[0]
    assert scale > 1.0  # there is energy to keep
    assert np.ptp(energies) < 1e-7 * scale


def test_inverse_dynamics_reproduces_the_acceleration(core):
    """Torques from the inverse model, fed to the forward model, give back the commanded
    acceleration (twist rate from the Euler-angle derivatives)."""
    rng = np.random.default_rng(6)
    for pose in random_poses(core, 10, seed=7):
        rate, acceleration = rng.normal(size=6) * 0.2, rng.normal(size=6) * 1.0
        wrench = rng.normal(size=6) * 200
        torque = core.inverse_dynamics(pose, rate, acceleration, wrench)
        x = core.state(pose, rate)
        dx, _ = core.derivatives(x, torque, np.zeros(6), wrench)
        # expected twist rate: translational acceleration and w_dot = E a + E_dot rate (finite difference)
        h = 1e-6
        w = lambda s: core.state(pose + s * rate + 0.5 * s * s * acceleration, rate + s * acceleration)[10:13]
        w_dot = (w(h) - w(-h)) / (2 * h)
        np.testing.assert_allclose(dx[7:10], acceleration[:3], rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(dx[10:13], w_dot, rtol=1e-6, atol=1e-6)


def test_held_neutral_pose_needs_the_weight_shared_by_six_legs(core):
    """Statics at the neutral pose: the six torques carry the platform's and the legs' weight; by
    symmetry they are equal, and with legs off they are m_p g / (6 K_FT cos(leg elevation))."""
    torque = core.inverse_dynamics(core.neutral_pose, np.zeros(6), np.zeros(6))
    np.testing.assert_allclose(torque, torque[0], rtol=1e-9)
    bare = Core(core.dll, actuators=False, motors=False)
    torque_bare = bare.inverse_dynamics(core.neutral_pose, np.zeros(6), np.zeros(6))
    elevation = core.neutral_pose[2] / 1.86
    assert torque_bare[0] == pytest.approx(950 * 9.81 / (6 * 250 * elevation), rel=1e-9)
    assert torque[0] > torque_bare[0]  # the legs' own weight adds to it


def test_accelerations_satisfy_lagranges_equations(dll):
    """Independent of Kane's bookkeeping: with the pose q (x, y, z, roll, pitch, yaw) as generalized
    coordinates, the core's own kinetic and potential energy T(q, q_dot), V(q), differentiated
    numerically, and its accelerations converted to q_ddot satisfy
        d/dt dT/dq_dot - dT/dq + dV/dq = 0   (no inputs, friction off)
    at random states, to 1e-5 of the inertial term. Power balance cannot see forces that do no work
    (gyroscopic terms); this can. Not for spinning legs: their spin rate n.w (Halder's kinematics)
    is not the rate of any function of q, so the spin is a non-holonomic motion that Lagrange's
    equations in q do not describe (Kane's method, which the core uses, does)."""
    core = Core(dll, friction=False)
    rng = np.random.default_rng(11)

    def kinetic(q, qd):
        return core.derivatives(core.state(q, qd))[1].kinetic

    def potential(q):
        return core.derivatives(core.state(q))[1].potential

    def omega(q, qd):
        return core.state(q, qd)[10:13]

    eps = 1e-5
    unit = np.eye(6)
    for pose in random_poses(core, 4, seed=12):
        q, qd = pose, rng.normal(size=6) * 0.5
        u_dot = core.derivatives(core.state(q, qd))[0][7:13]
        E = np.column_stack([omega(q, unit[k])[:3] for k in (3, 4, 5)])
        E_dot_qd = (omega(q + eps * qd, qd) - omega(q - eps * qd, qd)) / (2 * eps)
        qdd = np.r_[u_dot[:3], np.linalg.solve(E, u_dot[3:] - E_dot_qd)]

        def dT_dqd(q_, qd_):
            return np.array([(kinetic(q_, qd_ + eps * unit[j]) - kinetic(q_, qd_ - eps * unit[j])) / (2 * eps)
                             for j in range(6)])

        h = 1e-4  # d/dt dT/dq_dot along the motion: central difference in time of the momentum
        momentum_rate = (dT_dqd(q + h * qd + 0.5 * h * h * qdd, qd + h * qdd)
                         - dT_dqd(q - h * qd + 0.5 * h * h * qdd, qd - h * qdd)) / (2 * h)
        dT_dq = np.array([(kinetic(q + eps * unit[j], qd) - kinetic(q - eps * unit[j], qd)) / (2 * eps) for j in range(6)])
        dV_dq = np.array([(potential(q + eps * unit[j]) - potential(q - eps * unit[j])) / (2 * eps) for j in range(6)])
        residual = momentum_rate - dT_dq + dV_dq
        assert np.abs(residual).max() < 1e-5 * (np.abs(momentum_rate).max() + np.abs(dV_dq).max()), residual
