"""The shared internal solvers (fmu/common/ode.c) on problems with known solutions."""

from __future__ import annotations

import ctypes
import subprocess

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT

RK4, DOPRI5 = 1, 2


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


@pytest.mark.parametrize("method,step", [(RK4, 0.02), (DOPRI5, 0.5)])
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
