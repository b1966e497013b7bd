"""The shared internal solvers (fmu/common/ode.c) on problems with known solutions."""

from __future__ import annotations

import ctypes
import subprocess

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT

RK4, DOPRI5, ROSENBROCK, ROSENBROCK_ADAPTIVE, HEUN = 1, 2, 3, 4, 5


@pytest.fixture(scope="module")
def probe(tmp_path_factory) -> ctypes.CDLL:
    lib = tmp_path_factory.mktemp("ode") / "ode_probe.so"
    common = ROOT / "fmu" / "common"
    subprocess.run(["cc", "-O2", "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-shared", "-fPIC",
                    f"-I{common}", str(ROOT / "tests" / "c" / "ode_probe.c"), str(common / "ode.c"),
                    "-o", str(lib), "-lm"], check=True)
    dll = ctypes.CDLL(str(lib))
    d, i, p = ctypes.c_double, ctypes.c_int, ctypes.POINTER(ctypes.c_double)
    dll.probe_oscillator.argtypes = [i, d, d, d, i, p, p]
    dll.probe_oscillator.restype = d
    dll.probe_events.argtypes = [i, d, d, d, p]
    dll.probe_events.restype = i
    dll.probe_stiff.argtypes = [i, d, d, d, d, i, p, p]
    dll.probe_stiff.restype = d
    dll.probe_linear.argtypes = [i, d, i, p, p, d, i]
    dll.probe_linear.restype = i
    dll.probe_logistic.argtypes = [i, d, d]
    dll.probe_logistic.restype = d
    return dll


def oscillator(probe, method, step, rtol=1e-6, t_end=10.0, pieces=1):
    steps, rejected = ctypes.c_double(), ctypes.c_double()
    error = probe.probe_oscillator(method, step, rtol, t_end, pieces, ctypes.byref(steps), ctypes.byref(rejected))
    assert error >= 0, "solver failed"
    return error, steps.value, rejected.value


def test_rk4_is_fourth_order(probe):
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = np.array([oscillator(probe, RK4, h)[0] for h in steps])
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(4.0, abs=0.15)


def test_heun_is_second_order_at_two_evaluations_a_step(probe):
    """Heun's method on the oscillator x'' = -x: order 2 and, at the smallest step, the error its
    amplification factor 1 + ih - h^2/2 predicts: a phase lead of h^3/6 a step, t h^2 / 6 at
    t = 10 s, in x' = -sin t by |cos 10| of it (its growth of the amplitude, t h^3 / 8, is far below
    that)."""
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    runs = [oscillator(probe, HEUN, h) for h in steps]
    errors = np.array([r[0] for r in runs])
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(2.0, abs=0.05)
    assert errors[-1] == pytest.approx(abs(np.cos(10.0)) * 10.0 * steps[-1] ** 2 / 6.0, rel=0.02)
    assert [r[1] for r in runs] == [100, 200, 400, 800]


def test_rk4_cuts_any_interval_into_equal_steps(probe):
    """Communication points that are not multiples of the step change nothing but round-off:
    10 s in 7 pieces with h = 0.01 takes ceil(10/7/0.01) = 143 equal steps per piece."""
    error_one, steps_one, _ = oscillator(probe, RK4, 0.01)
    error_seven, steps_seven, _ = oscillator(probe, RK4, 0.01, pieces=7)
    assert steps_one == 1000 and steps_seven == 7 * 143
    assert error_seven <= error_one * 1.05


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_dormand_prince_meets_its_tolerance(probe, rtol):
    """Error per unit step below tolerance: over 10 s (about 1.6 periods) the global error stays
    within 100 x rtol, and tightening rtol by 100 costs about 100^(1/5) = 2.5 x the steps."""
    error, steps, _ = oscillator(probe, DOPRI5, 1.0, rtol=rtol)
    assert error < 100 * rtol
    error_tight, steps_tight, _ = oscillator(probe, DOPRI5, 1.0, rtol=rtol / 100)
    assert steps_tight / steps == pytest.approx(100 ** 0.2, rel=0.3)


def test_dormand_prince_respects_its_largest_step(probe):
    _, steps, _ = oscillator(probe, DOPRI5, 0.01, rtol=1e-3)
    assert steps >= 1000


@pytest.mark.parametrize("method,step", [(RK4, 0.02), (DOPRI5, 0.5), (ROSENBROCK, 0.01), (ROSENBROCK_ADAPTIVE, 0.5),
                                         (HEUN, 5e-4)])
def test_events_are_located_where_the_exact_solution_crosses(probe, method, step):
    """x = cos t crosses 0.5 downward at pi/3 and upward at 5 pi/3; the handler flips the sign of
    g each time, so both are events, and the second one leaves g at exactly zero (x = 0.5 to the
    last bit), which must count as cleared. Located to 1e-7 of the step; what remains is the
    method's own error in x (about 1e-9 here) over |x'| = 0.87."""
    times = (ctypes.c_double * 4)()
    count = probe.probe_events(method, step, 1e-10, 7.0, times)
    assert count == 2
    assert times[0] == pytest.approx(np.pi / 3, abs=1e-6)
    assert times[1] == pytest.approx(5 * np.pi / 3, abs=1e-6)


def stiff(probe, method, step, lam, rtol=1e-6, t_end=2.0, pieces=1):
    steps, calls = ctypes.c_double(), ctypes.c_double()
    error = probe.probe_stiff(method, step, rtol, lam, t_end, pieces, ctypes.byref(steps), ctypes.byref(calls))
    return error, steps.value, calls.value


@pytest.mark.parametrize("pieces", [1, 10])
def test_rosenbrock_is_third_order(probe, pieces):
    """ROS34PW2 with fixed steps on the oscillator: order 3, in one call or in ten."""
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = np.array([oscillator(probe, ROSENBROCK, h, pieces=pieces)[0] for h in steps])
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(3.0, abs=0.1)


def test_rosenbrock_keeps_its_order_with_a_lagged_jacobian(probe):
    """A W-method: on the logistic equation, integrated in one call, every step uses the Jacobian of
    t = 0 (+0.8, while the true one ends at -0.8), and the order is still 3 (a Rosenbrock method
    that needs the exact Jacobian would drop to order 1 or 2 here)."""
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = np.array([probe.probe_logistic(ROSENBROCK, h, 5.0) for h in steps])
    assert np.all(errors > 0)
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order == pytest.approx(3.0, abs=0.25), errors


def test_rosenbrock_takes_steps_far_beyond_the_explicit_limit(probe):
    """Prothero-Robinson with lambda = -1e6 at h = 0.1 (h |lambda| = 1e5; RK4's limit is 2.8):
    RK4 overflows, ROS34PW2 (L-stable, stiffly accurate) stays on the exact solution: its error
    is of the order of the non-stiff local error h^3 / 6 times the first derivative's scale, far
    below it here since the stiff component is slaved to sin t (1e-6 bounds both states)."""
    assert stiff(probe, RK4, 0.1, -1e6)[0] == -2.0
    error, steps, calls = stiff(probe, ROSENBROCK, 0.1, -1e6)
    assert 0 <= error < 1e-4
    assert steps == 20
    # one Jacobian (1 column, the quadrature's skipped, plus f and f_t: 3 evaluations), then 4 per
    # step, the first of which reuses f
    assert calls == 3 + 4 * 20 - 1


def test_rosenbrock_converges_at_third_order_on_the_stiff_problem_too(probe):
    """Order in the stiff regime (h lambda from -1e4 to -1e3): the quadrature state, which sees the
    stiff one only through its integral, converges at order 3 or better (no order reduction
    below 2.5 at this stiffness)."""
    steps = np.array([0.1, 0.05, 0.025, 0.0125])
    errors = np.array([stiff(probe, ROSENBROCK, h, -1e5)[0] for h in steps])
    assert np.all(errors > 0)
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert order > 2.5


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_adaptive_rosenbrock_meets_its_tolerance(probe, rtol):
    """The embedded order-2 solution controls the step: the global error over 10 s stays within
    100 x rtol, and tightening rtol by 100 costs about 100^(1/3) = 4.6 x the steps."""
    error, steps, _ = oscillator(probe, ROSENBROCK_ADAPTIVE, 1.0, rtol=rtol)
    assert error < 100 * rtol
    _, steps_tight, _ = oscillator(probe, ROSENBROCK_ADAPTIVE, 1.0, rtol=rtol / 100)
    assert steps_tight / steps == pytest.approx(100 ** (1 / 3), rel=0.3)


def test_adaptive_rosenbrock_is_not_limited_by_stiffness(probe):
    """On the stiff problem the step is set by the accuracy of sin t, not by lambda: the steps
    taken at lambda = -1e6 are within 10 % of those at lambda = -1e2 (where the stiff mode is slow
    enough to need resolving just after the start), while Dormand-Prince needs a step below its
    stability limit 3.3 / |lambda|."""
    error, steps_stiff, _ = stiff(probe, ROSENBROCK_ADAPTIVE, 1.0, -1e6, rtol=1e-6)
    assert 0 <= error < 1e-4
    _, steps_mild, _ = stiff(probe, ROSENBROCK_ADAPTIVE, 1.0, -1e2, rtol=1e-6)
    assert steps_stiff <= 1.1 * steps_mild
    _, steps_dopri, _ = stiff(probe, DOPRI5, 1.0, -1e4, rtol=1e-6)
    assert steps_dopri > 2.0 * 1e4 / 3.3 * 0.9


# ROS34PW2's coefficients (Rang & Angermann 2005), for an independent evaluation of its steps.
ROS_GAMMA = 0.435866521508459
ROS_ALPHA = np.array([[0, 0, 0, 0], [0.87173304301691801, 0, 0, 0],
                      [0.84457060015369423, -0.11299064236484185, 0, 0], [0, 0, 1, 0]])
ROS_GAMMA_BELOW = np.array([[0, 0, 0, 0], [-0.87173304301691801, 0, 0, 0],
                            [-0.90338057013044082, 0.054180672388095326, 0, 0],
                            [0.24212380706095346, -1.2232505839045147, 0.54526025533510214, 0]])
ROS_B = np.array([0.24212380706095346, -1.2232505839045147, 1.5452602553351020, 0.435866521508459])


def rosenbrock_steps(a: np.ndarray, x: np.ndarray, h: float, steps: int) -> np.ndarray:
    """ROS34PW2 on x' = A x with the exact Jacobian, by numpy's LAPACK solver:
    (I - h gamma A) k_i = h A (x + sum_j (alpha_ij + gamma_ij) k_j)."""
    n = len(x)
    matrix = np.eye(n) - h * ROS_GAMMA * a
    for _ in range(steps):
        k = np.zeros((4, n))
        for i in range(4):
            k[i] = np.linalg.solve(matrix, h * a @ (x + (ROS_ALPHA[i] + ROS_GAMMA_BELOW[i]) @ k))
        x = x + ROS_B @ k
    return x


def test_rosenbrock_steps_equal_an_independent_evaluation_with_pivoting(probe):
    """A 6-state linear system whose I - h gamma A needs row exchanges (zero diagonal, large
    off-diagonal couplings, steps of 0.5 with eigenvalues up to about 40 in modulus): the solver's
    steps (its Jacobian by forward differences, its own LU with partial pivoting) equal the same
    method evaluated with numpy's LAPACK solve to 1e-9 relative, and the result decays as the exact
    solution does (L-stability: no growth from the fast modes)."""
    rng = np.random.default_rng(7)
    a = rng.normal(size=(6, 6)) * 10.0
    np.fill_diagonal(a, 0.0)
    a -= np.eye(6) * (np.abs(np.linalg.eigvals(a).real).max() + 1.0)  # every mode decays
    x0 = rng.normal(size=6)
    x = (ctypes.c_double * 6)(*x0)
    flat = (ctypes.c_double * 36)(*a.ravel())
    assert probe.probe_linear(ROSENBROCK, 0.5, 6, flat, x, 5.0, 1) == 0
    expected = rosenbrock_steps(a, x0, 0.5, 10)
    assert np.allclose(np.array(x), expected, rtol=1e-9, atol=1e-9 * np.abs(x0).max())
    assert np.abs(np.array(x)).max() < np.abs(x0).max()
