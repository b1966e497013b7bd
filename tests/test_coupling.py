"""Coupling algorithms on a two-mass oscillator split into two test FMUs (tests/fmus/): the global
error converges with order k + 1 for extrapolation order k, under Jacobi and Gauss-Seidel."""

from __future__ import annotations

import numpy as np
import pytest
from fmpy import extract
from scipy.linalg import expm

from cosim.coupling import Bond, Connection, Coupling, GaussSeidel, Jacobi
from cosim.fmu_instance import FmuInstance
from cosim.fmus import fmu_path

M1, K1, D1, M2, K2, KC, DC, X0 = 1.0, 10.0, 0.1, 1.0, 10.0, 100.0, 1.0, 1.0  # the test FMUs' defaults
CONNECTIONS = [
    Connection(("mass", "position"), ("coupling", "position_1")),
    Connection(("mass", "velocity"), ("coupling", "velocity_1")),
    Connection(("coupling", "force"), ("mass", "force")),
]


def exact_position_1(t: float) -> float:
    """x1(t) of the monolithic linear system [x1, v1, x2, v2]' = A [x1, v1, x2, v2]."""
    A = np.array([[0, 1, 0, 0],
                  [-(K1 + KC) / M1, -(D1 + DC) / M1, KC / M1, DC / M1],
                  [0, 0, 0, 1],
                  [KC / M2, DC / M2, -(K2 + KC) / M2, -DC / M2]])
    return float((expm(A * t) @ np.array([X0, 0, 0, 0]))[0])


@pytest.fixture(scope="module")
def unzipped():
    return {name: extract(str(fmu_path(name, test=True))) for name in ("oscillator_mass", "oscillator_coupling")}


BONDS = [Bond(effort=CONNECTIONS[2], flow=CONNECTIONS[1])]  # force x velocity of mass 1


def coupled_error(unzipped, algorithm, steps: int, stop_time: float = 1.0, interpolating: bool = True) -> float:
    instances = {"mass": FmuInstance(fmu_path("oscillator_mass", test=True), "mass", unzipped["oscillator_mass"]),
                 "coupling": FmuInstance(fmu_path("oscillator_coupling", test=True), "coupling",
                                         unzipped["oscillator_coupling"])}
    try:
        for instance in instances.values():
            instance.initialize()
        coupling = Coupling(instances, CONNECTIONS, BONDS, None if interpolating else dict.fromkeys(instances, False))
        h = stop_time / steps
        algorithm.initialize(coupling, 0.0)
        for k in range(steps):
            algorithm.step(coupling, k * h, h)
        return abs(instances["mass"].get("position") - exact_position_1(stop_time))
    finally:
        for instance in instances.values():
            instance.free()


@pytest.mark.parametrize("order", [0, 1, 2])
@pytest.mark.parametrize("kind", ["jacobi", "gauss-seidel"])
def test_global_error_converges_with_order_k_plus_1(unzipped, kind, order):
    """Fitted slope of log(error) over log(h) for h = 1/200 ... 1/1600 s (the asymptotic range:
    h w < 0.1 for the coupled mode w ~ 15 rad/s) is k + 1 within 0.15; the FMUs' internal solvers
    run at rtol 1e-12, far below the coupling error. The start-up is exact enough: the outputs at
    t = 0 are made consistent with the inputs and the first step is iterated to a fixed point."""
    make = (lambda: Jacobi(order)) if kind == "jacobi" else (lambda: GaussSeidel(order, ["coupling", "mass"]))
    steps = np.array([200, 400, 800, 1600])
    errors = np.array([coupled_error(unzipped, make(), n) for n in steps])
    slope = np.polyfit(np.log(1.0 / steps), np.log(errors), 1)[0]
    assert slope == pytest.approx(order + 1, abs=0.15), (errors, slope)


@pytest.mark.parametrize("order", [0, 1, 2])
@pytest.mark.parametrize("kind", ["jacobi", "gauss-seidel"])
def test_fmus_that_cannot_interpolate_get_held_inputs(unzipped, kind, order, monkeypatch):
    """Treated as FMUs without canInterpolateInputs, both halves get no input derivatives (no
    fmi2SetRealInputDerivatives call) but each input held at its extrapolant's value at the step's
    midpoint. The coupling FMU's force feeds through from its held inputs, so the global order is 1
    for every k, within 0.15; the hold still beats order 0 at k >= 1 (measured about 10 %)."""
    from cosim.fmu_instance import RealGroup

    def refuse(*args, **kwargs):
        raise AssertionError("input derivatives sent to an FMU that cannot interpolate")

    monkeypatch.setattr(RealGroup, "write_derivatives", refuse)
    make = (lambda k: Jacobi(k)) if kind == "jacobi" else (lambda k: GaussSeidel(k, ["coupling", "mass"]))
    steps = np.array([200, 400, 800, 1600])
    errors = np.array([coupled_error(unzipped, make(order), n, interpolating=False) for n in steps])
    slope = np.polyfit(np.log(1.0 / steps), np.log(errors), 1)[0]
    assert slope == pytest.approx(1.0, abs=0.15), (errors, slope)
    if order >= 1:
        assert errors[-1] < coupled_error(unzipped, make(0), steps[-1], interpolating=False)


@pytest.mark.parametrize("order", [0, 1, 2])
def test_energy_residual_of_the_bond_converges_with_order_k_plus_1(unzipped, order):
    """The energy that the force x velocity bond loses or gains in the coupling, summed over the
    run, shrinks like h^(k+1): each step's residual is h times the flow's extrapolation error."""
    totals = []
    for n in (200, 400, 800, 1600):
        algorithm = Jacobi(order)
        coupled_error(unzipped, algorithm, n)
        assert len(algorithm.energy_residuals) == n
        totals.append(sum(algorithm.energy_residuals))
    slope = np.polyfit(np.log(1.0 / np.array([200, 400, 800, 1600])), np.log(totals), 1)[0]
    assert slope == pytest.approx(order + 1, abs=0.2), (totals, slope)


def test_gauss_seidel_is_more_accurate_than_jacobi_at_equal_order(unzipped):
    for order in (0, 1):
        assert coupled_error(unzipped, GaussSeidel(order, ["coupling", "mass"]), 100) < \
            coupled_error(unzipped, Jacobi(order), 100)


def test_bad_connection_names_the_instance_and_variable(unzipped):
    mass = FmuInstance(fmu_path("oscillator_mass", test=True), "mass", unzipped["oscillator_mass"])
    try:
        with pytest.raises(KeyError, match="mass: no variable 'forse'"):
            Coupling({"mass": mass}, [Connection(("mass", "position"), ("mass", "forse"))])
        with pytest.raises(KeyError, match="no instance 'spring'"):
            Coupling({"mass": mass}, [Connection(("spring", "force"), ("mass", "force"))])
    finally:
        mass.free()


def adaptive_run(unzipped, rtol: float, force_reject=()):
    from cosim.coupling import AdaptiveStep
    instances = {"mass": FmuInstance(fmu_path("oscillator_mass", test=True), "mass", unzipped["oscillator_mass"]),
                 "coupling": FmuInstance(fmu_path("oscillator_coupling", test=True), "coupling",
                                         unzipped["oscillator_coupling"])}
    try:
        for instance in instances.values():
            instance.initialize()
        coupling = Coupling(instances, CONNECTIONS, BONDS)
        control = AdaptiveStep(GaussSeidel(1, ["coupling", "mass"]), rtol=rtol, atol=rtol, h_initial=1e-3)
        control.force_reject = set(force_reject)
        control.algorithm.initialize(coupling, 0.0)
        control.advance(coupling, 0.0, 1.0)
        return instances["mass"].get("position"), control
    finally:
        for instance in instances.values():
            instance.free()


def test_adaptive_step_meets_its_tolerance_with_fewer_steps(unzipped):
    """Step doubling at rtol = atol = 1e-3 on the oscillator: the error at t = 1 s against the
    exact solution stays below the tolerance (measured 2.2e-4 with 276 steps), and a fixed step
    with as many macro steps is less accurate (measured 6e-4; it needs about twice the steps for
    the same error)."""
    position, control = adaptive_run(unzipped, 1e-3)
    error = abs(position - exact_position_1(1.0))
    assert error < 1e-3
    steps = len(control.accepted)
    assert control.rejected > 0  # the controller did work
    assert coupled_error(unzipped, GaussSeidel(1, ["coupling", "mass"]), steps) > 1.5 * error


def test_a_run_with_rejected_steps_equals_one_without(unzipped):
    """Rollback restores every FMU state and the coupling's history: a run whose 3rd, 10th and 20th
    steps are first rejected and retried gives bit for bit the result of the run without."""
    clean, control_clean = adaptive_run(unzipped, 1e-5)
    forced, control_forced = adaptive_run(unzipped, 1e-5, force_reject={3, 10, 20})
    assert control_forced.rejected == control_clean.rejected + 3
    assert control_forced.accepted == control_clean.accepted
    assert forced == clean
