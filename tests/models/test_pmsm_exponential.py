"""solver.exponential of the PMSM drive (fmu/pmsm_drive/model.c): the current loops, the inverter's
lag and the winding, linear with constant coefficients between the limits, taken exactly (ETDRK4
on that linear part, the rest explicit). Against RK4 at a step a hundred times finer on the drive
bench, it converges as the step shrinks and keeps the torque at 1 ms within 1e-3 of its peak where
RK4 at 1 ms diverges; where a voltage limit holds it is RK4 at the inverter's time scale, bit for
bit; and the phi-functions it rests on (fmu/common/ode.c) agree with scipy's matrix exponential."""

from __future__ import annotations

import ctypes
import subprocess

import numpy as np
import pytest
from scipy.linalg import expm

from cosim.engine.artifacts import ROOT
from drive_bench import RigidInertia, run_on_inertia

J_EQ = 0.0209  # one leg's motor-side inertia [kg m^2]


def bench(make_drive, values: dict, name: str, stop: float = 0.3, reference=lambda t: {"angle_ref": 0.5}):
    """The drive turning the leg's inertia after a 0.5 rad step of its reference (the current
    limit holds for the first milliseconds), coupled at 1 ms: time, torque, angle."""
    drive = make_drive({"inverter.model": 2, **values}, name=name)
    return run_on_inertia(drive, RigidInertia(J_EQ), stop, 1e-3, reference, record=["current.q"])


def test_the_exponential_integrator_converges_to_the_fine_solution(make_drive):
    """Torque over 0.3 s against RK4 at 10 us (the same bench, the same 1 ms coupling): at 1 ms
    within 1e-3 of the torque's peak, and the error falls as the exponential step does."""
    fine = bench(make_drive, {"solver.step": 1e-5}, "fine")
    peak = np.abs(fine["torque"]).max()
    errors = {}
    for step in (1e-3, 5e-4, 2.5e-4):
        run = bench(make_drive, {"solver.exponential": True, "solver.step": step}, f"exp{step}")
        errors[step] = np.abs(run["torque"] - fine["torque"]).max() / peak
    assert errors[1e-3] < 1e-3, errors
    assert errors[2.5e-4] < errors[5e-4] < errors[1e-3], errors
    with pytest.raises(Exception):  # what it replaces: RK4 at 1 ms leaves the solution (tau_v = 0.1 ms)
        bench(make_drive, {"solver.step": 1e-3}, "rk4")


def test_where_a_voltage_limit_holds_it_is_rk4_at_the_inverters_time_scale(make_drive):
    """limit.voltage at 5 V: the current controller is clamped through every step, so each step
    is RK4's at h = tau_v (0.1 ms, h |lambda| = 1 on the inverter's lag): the run equals RK4 at
    0.1 ms bit for bit."""
    limited = {"limit.voltage": 5.0}
    exponential = bench(make_drive, {**limited, "solver.exponential": True, "solver.step": 1e-3}, "exp", stop=0.05)
    rk4 = bench(make_drive, {**limited, "solver.step": 1e-4}, "rk4", stop=0.05)
    for name in exponential.dtype.names:
        assert np.array_equal(exponential[name], rk4[name]), name


@pytest.fixture(scope="module")
def ode(tmp_path_factory) -> ctypes.CDLL:
    lib = tmp_path_factory.mktemp("phi") / "ode.so"
    common = ROOT / "fmu" / "common"
    subprocess.run(["cc", "-O2", "-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-shared", "-fPIC",
                    f"-I{common}", str(common / "ode.c"), "-o", str(lib), "-lm"], check=True)
    dll = ctypes.CDLL(str(lib))
    p = ctypes.POINTER(ctypes.c_double)
    dll.ode_phi_functions.argtypes = [ctypes.c_int, p, ctypes.c_double, ctypes.c_int, p]
    return dll


@pytest.mark.parametrize("n, scale", [(1, -1e4), (3, 1e2), (7, 3e5)])
def test_the_phi_functions_are_scipys_matrix_exponential(ode, n, scale):
    """phi_0..phi_3(hA) against scipy's expm (Pade, an independent algorithm) of the augmented
    matrix, and phi_1 against its definition (e^Z - I) Z^-1, for matrices from a scalar to the
    drive's 7 x 7 norms (h = 1 ms): within 1e-12 of the largest entry."""
    rng = np.random.default_rng(n)
    a = rng.normal(size=(n, n)) * scale / n - np.eye(n) * abs(scale)
    h = 1e-3
    out = np.zeros(4 * n * n)
    p = ctypes.POINTER(ctypes.c_double)
    ode.ode_phi_functions(n, np.ascontiguousarray(a).ctypes.data_as(p), h, 3, out.ctypes.data_as(p))
    phi = out.reshape(4, n, n)
    augmented = np.zeros((4 * n, 4 * n))
    augmented[:n, :n] = h * a
    for k in range(1, 4):
        augmented[(k - 1) * n:k * n, k * n:(k + 1) * n] = np.eye(n)
    expected = expm(augmented)
    for k in range(4):
        block = expected[:n, k * n:(k + 1) * n]
        assert np.abs(phi[k] - block).max() <= 1e-12 * max(1.0, np.abs(block).max()), k
    z = h * a
    assert np.allclose(phi[1], np.linalg.solve(z, expm(z) - np.eye(n)), rtol=1e-9, atol=1e-12)
