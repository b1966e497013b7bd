"""The test oracle: a plain Python transcription of the engine's step kernel
(cosim/engine/kernel/kernel.c), operation for operation. It is never used to run anything; the
tests hold the kernel to it bit for bit (tests/engine/test_kernel.py), so this file is the
readable statement of what the kernel computes.

Inputs over a macro step are polynomials in time fitted to the samples of the source outputs:
- Jacobi: every instance steps from t with inputs extrapolated from the outputs at t, t - h, ...
  (order k uses the last k + 1 samples), so the global error is O(h^(k+1)).
- Gauss-Seidel: instances step in sequence; an input whose source has already stepped is
  interpolated through that source's new sample at t + h and its last k samples, the others are
  extrapolated as in Jacobi.
A source that provides its outputs' time derivatives is not extrapolated from its history: its
inputs are its Taylor polynomial at t of order min(k, its order). An FMU that does not declare
canInterpolateInputs gets each input held at its polynomial's value at the step's midpoint and no
derivatives (one that extrapolates held inputs itself, fmi.extrapolate_inputs, the value at t). At the start the outputs are made consistent with the connected inputs; the first
macro step is iterated to a fixed point (FMU states restored between sweeps).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections import deque
from typing import Callable, Mapping, Sequence

import numpy as np

from cosim.engine.coupling import Coupling


def polynomial_at(times: Sequence[float], values: Sequence[np.ndarray], t: float, order: int):
    """Value and first two derivatives at t of the polynomial of degree len(times) - 1 through the
    samples (Newton divided differences), for up to three samples."""
    times = list(times)
    y = [np.asarray(v, dtype=float) for v in values]
    zero = np.zeros_like(y[0])
    if len(times) == 1 or order == 0:
        return y[-1], zero, zero
    d1 = [(y[i + 1] - y[i]) / (times[i + 1] - times[i]) for i in range(len(y) - 1)]
    if len(times) == 2 or order == 1:
        slope = d1[-1]
        return y[-1] + slope * (t - times[-1]), slope, zero
    d2 = (d1[1] - d1[0]) / (times[2] - times[0])
    # p(s) = y0 + d1_0 (s - t0) + d2 (s - t0)(s - t1)
    value = y[0] + d1[0] * (t - times[0]) + d2 * (t - times[0]) * (t - times[1])
    rate = d1[0] + d2 * ((t - times[0]) + (t - times[1]))
    return value, rate, 2.0 * d2


class History:
    """The last few output samples of every source instance, with the output derivatives of the
    sources that provide them."""

    def __init__(self, keep: int):
        self.samples: deque[tuple[float, dict[str, np.ndarray], dict[str, list[np.ndarray]]]] = deque(maxlen=keep)

    def push(self, t: float, outputs: dict[str, np.ndarray], rates: dict[str, list[np.ndarray]] | None = None) -> None:
        self.samples.append((t, outputs, rates or {}))

    def source_samples(self, name: str, extra: tuple[float, np.ndarray] | None = None, count: int = 3):
        times = [t for t, _, _ in self.samples][-count:]
        values = [o[name] for _, o, _ in self.samples][-count:]
        if extra is not None:
            times = (times + [extra[0]])[-count:]
            values = (values + [extra[1]])[-count:]
        return times, values


class CouplingAlgorithm(ABC):
    """Base of the algorithms: `step` advances every instance from t to t + h."""

    def __init__(self, order: int = 0):
        if order not in (0, 1, 2):
            raise ValueError(f"extrapolation order {order}: 0, 1 and 2 are supported")
        self.order = order
        self.history = History(keep=max(order + 1, 2))
        self.inputs_set: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.energy_residuals: list[float] = []  # per macro step, the largest over the bonds [J]
        # of the last step, per bond: the energy residual and the energy transferred [J]
        self.bond_energies: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros(0))
        self.feedthrough: list[tuple[str, list[int], list[int]]] = []  # Coupling.feedthrough(), if resolved

    def initialize(self, coupling: Coupling, t: float, sweeps: int = 20, zero_start: bool = False) -> None:
        """Makes the outputs at t consistent with the connected inputs (outputs that feed through
        from inputs, such as a spring force from a position, depend on them) and starts the history."""
        self.energy_residuals = []
        outputs, exact = coupling.read(), coupling.read_rates()
        for _ in range(sweeps):
            for name, feeds in coupling.feeds.items():
                coupling.inputs[name].write([outputs[source][index] for source, index in feeds])
                top = max((coupling.rate_orders.get(source, 0) for source, _ in feeds), default=0)
                if self.order > 0 and coupling.interpolating[name] and top > 0:
                    # the exact derivatives at t of the sources that give them (0 for the other inputs)
                    for k in range(1, top + 1):
                        coupling.inputs[name].write_derivatives(
                            [exact[source][k - 1][index] if len(exact.get(source, [])) >= k else 0.0
                             for source, index in feeds], k)
            new = coupling.read()
            settled = all(np.array_equal(new[n], outputs[n]) for n in new)
            outputs = new
            if settled:
                break
        if zero_start:
            outputs = {n: np.zeros_like(v) for n, v in outputs.items()}
        self.history = History(keep=max(self.order + 1, 2))
        self.history.push(t, outputs, coupling.read_rates())

    def _set_inputs(self, coupling: Coupling, name: str, t: float, new: dict[str, np.ndarray], t_new: float,
                    order: int, polynomials: dict) -> None:
        """Inputs of `name` over [t, t + h]: from the polynomial through its sources' samples (with
        the new sample at t + h where a source has one), evaluated at t. `polynomials` caches each
        source's polynomial for this step (key: source and whether it had a new sample)."""
        values, rates, curvatures = [], [], []
        sent = order  # the highest derivative order sent: a source's exact derivatives all go
        for source, index in coupling.feeds[name]:
            key = (source, source in new)
            if source in coupling.rate_orders and order > 0:
                sent = max(sent, coupling.rate_orders[source])
            if key not in polynomials and source in coupling.rate_orders:
                _, outputs, exact = self.history.samples[-1]  # at t: Taylor with the exact derivatives
                zero = np.zeros_like(outputs[source])
                derivatives = [*(exact[source] if order > 0 else []), zero, zero][:2]
                polynomials[key] = (outputs[source], derivatives[0], derivatives[1])
            if key not in polynomials:
                extra = (t_new, new[source]) if source in new else None
                times, samples = self.history.source_samples(source, extra, count=order + 1)
                polynomials[key] = polynomial_at(times, samples, t, order)
            v, r, c = polynomials[key]
            values.append(v[index]); rates.append(r[index]); curvatures.append(c[index])
        group = coupling.inputs[name]
        if order >= 1 and not coupling.interpolating[name]:  # held at the midpoint value
            half = 0.0 if coupling.extrapolating[name] else 0.5 * (t_new - t)  # (at t: it extrapolates itself)
            values = [v + r * half + 0.5 * c * half * half for v, r, c in zip(values, rates, curvatures)]
            rates, curvatures = [0.0] * len(values), [0.0] * len(values)
            sent = 0
        self.inputs_set[name] = (np.array(values), np.array(rates), np.array(curvatures))
        group.write(values)
        if sent >= 1:
            group.write_derivatives(rates, 1)
        if sent >= 2:
            group.write_derivatives(curvatures, 2)

    def step(self, coupling: Coupling, t: float, h: float) -> None:
        if len(self.history.samples) == 1 and self.order > 0:
            self._start_up(coupling, t, h)
        else:
            self._sweep(coupling, t, h)
        self._resolve_feedthrough(coupling)
        if coupling.bonds:
            self.energy_residuals.append(self._energy_residual(coupling, h))

    def _resolve_feedthrough(self, coupling: Coupling) -> None:
        """The outputs that depend on inputs at the same communication point, read again in
        dependency order with those inputs at their sources' newest values (and the exact
        derivatives of the sources that give them, under extrapolation)."""
        _, outputs, exact = self.history.samples[-1]
        for name, inputs, indices in self.feedthrough:
            names, values, rates, curvatures, top = [], [], [], [], 0
            for i in inputs:
                source, index = coupling.feeds[name][i]
                given = coupling.rate_orders.get(source, 0) if self.order > 0 and coupling.interpolating[name] else 0
                names.append(coupling.input_names[name][i])
                values.append(outputs[source][index])
                rates.append(exact[source][0][index] if given >= 1 else 0.0)
                curvatures.append(exact[source][1][index] if given >= 2 else 0.0)
                top = max(top, given)
            instance = coupling.instances[name]
            instance.set(dict(zip(names, values)))
            if top >= 1:
                instance.set_input_derivatives(names, rates, 1)
            if top >= 2:
                instance.set_input_derivatives(names, curvatures, 2)
            for index in indices:
                outputs[name][index] = instance.get(coupling.sources[name][index])

    def _energy_residual(self, coupling: Coupling, h: float) -> float:
        """Largest |energy residual| of the bonds over the step just taken: the energy the output
        sides delivered minus what the input sides received, each power taken as its side saw it
        (outputs at t and t + h against the inputs as set over the step), by the trapezoidal rule."""
        (_, before, _), (_, after, _) = self.history.samples[-2], self.history.samples[-1]
        residuals, transferred = [], []
        for ((effort_out, effort_in), (flow_out, flow_in)), slope_in in zip(coupling.bonds, coupling.bond_slopes):
            def seen(target, dt):
                values, rates, curvatures = self.inputs_set[target[0]]
                k = target[1]
                return values[k] + rates[k] * dt + 0.5 * curvatures[k] * dt * dt
            e0, e1 = before[effort_out[0]][effort_out[1]], after[effort_out[0]][effort_out[1]]
            f0, f1 = before[flow_out[0]][flow_out[1]], after[flow_out[0]][flow_out[1]]
            # the effort side sees the flow it was given; the flow side the effort it was given
            given_side = 0.5 * h * (e0 * seen(flow_in, 0.0) + e1 * seen(flow_in, h))
            felt_0, felt_1 = seen(effort_in, 0.0), seen(effort_in, h)
            if slope_in is not None:  # the flow's side felt effort + slope (flow - the flow the effort's side saw)
                felt_0 += seen(slope_in, 0.0) * (f0 - seen(flow_in, 0.0))
                felt_1 += seen(slope_in, h) * (f1 - seen(flow_in, h))
            taken_side = 0.5 * h * (felt_0 * f0 + felt_1 * f1)
            residuals.append(given_side - taken_side)
            transferred.append(0.5 * (abs(given_side) + abs(taken_side)))
        self.bond_energies = (np.array(residuals), np.array(transferred))
        return float(np.max(np.abs(residuals)))

    @abstractmethod
    def _sweep(self, coupling: Coupling, t: float, h: float) -> None:
        """One pass over the instances from t to t + h, pushing the new outputs to the history."""

    def _start_up(self, coupling: Coupling, t: float, h: float, tolerance: float = 1e-13, sweeps: int = 50) -> None:
        """First step: iterate with inputs interpolated linearly between t and the latest guess of
        the outputs at t + h until the guess stops changing."""
        states = {n: i.get_state() for n, i in coupling.instances.items()}
        guess = self.history.samples[-1][1]
        rates: dict = {}
        try:
            for sweep in range(sweeps):
                polynomials: dict = {}
                for name in coupling.names:
                    if name in coupling.feeds:
                        self._set_inputs(coupling, name, t, guess, t + h, 1, polynomials)
                    coupling.instances[name].do_step(h)
                new, rates = coupling.read(), coupling.read_rates()
                change = max(np.max(np.abs(new[n] - guess[n]) / (1.0 + np.abs(new[n]))) for n in new)
                guess = new
                if change < tolerance or sweep == sweeps - 1:
                    break  # the instances stay at t + h
                for n, instance in coupling.instances.items():
                    instance.set_state(states[n])
        finally:
            for n, instance in coupling.instances.items():
                instance.free_state(states[n])
        self.history.push(t + h, guess, rates)


class Jacobi(CouplingAlgorithm):
    """All instances step from t together; inputs extrapolated from the sources' history."""

    def _sweep(self, coupling: Coupling, t: float, h: float) -> None:
        polynomials: dict = {}
        for name in coupling.names:
            if name in coupling.feeds:
                self._set_inputs(coupling, name, t, {}, t + h, self.order, polynomials)
        for name in coupling.names:
            coupling.instances[name].do_step(h)
        self.history.push(t + h, coupling.read(), coupling.read_rates())


class GaussSeidel(CouplingAlgorithm):
    """Instances step in `sequence` (default: the coupling's order); an input whose source has
    already stepped is interpolated through the source's new sample."""

    def __init__(self, order: int = 0, sequence: Sequence[str] | None = None):
        super().__init__(order)
        self.sequence = list(sequence) if sequence else None

    def _sweep(self, coupling: Coupling, t: float, h: float) -> None:
        new: dict[str, np.ndarray] = {}
        polynomials: dict = {}
        for name in self.sequence or coupling.names:
            if name in coupling.feeds:
                self._set_inputs(coupling, name, t, new, t + h, self.order, polynomials)
            coupling.instances[name].do_step(h)
            if name in coupling.outputs:
                new[name] = coupling.outputs[name].read().copy()
        self.history.push(t + h, new, coupling.read_rates())


class AdaptiveStep:
    """Macro-step control by step doubling with rollback. Each macro step H is taken once whole
    and, from the same saved FMU states and history, once as two halves; the difference of the
    coupled outputs estimates the local error of the halves (Richardson). Accepted when
    err = max |y_half - y_full| / (atol + rtol |y_half|) <= 1 (the halves' result is kept);
    otherwise every FMU is rolled back through fmi2SetFMUstate and the step retried with a smaller
    H. H_next = H min(2, max(0.2, 0.9 err^(-1/(k+2)))) for extrapolation order k, within
    [h_min, h_max]."""

    def __init__(self, algorithm: CouplingAlgorithm, rtol: float = 1e-4, atol: float | Mapping[str, float] = 1e-6,
                 h_initial: float = 1e-3, h_min: float = 1e-6, h_max: float = 1e-2,
                 before_step: Callable[[float], None] | None = None,
                 after_accept: Callable[[float], None] | None = None):
        """atol is one number or one per source instance; a mapping also selects the instances
        whose outputs the error is measured on (those it names). before_step(t) runs before every
        (partial) macro step from t, e.g. to set external inputs; after_accept(t) after every
        accepted step, e.g. to record results."""
        self.algorithm, self.rtol, self.atol = algorithm, rtol, atol
        self.before_step, self.after_accept = before_step or (lambda t: None), after_accept or (lambda t: None)
        self.h, self.h_min, self.h_max = h_initial, h_min, h_max
        self.accepted: list[float] = []  # accepted macro steps H
        self.rejected = 0
        self.force_reject: set[int] = set()  # test hook: reject the first try of these accepted-step indices

    def error(self, full: dict[str, np.ndarray], half: dict[str, np.ndarray]) -> float:
        """The scaled difference of the two results: <= 1 is within tolerance."""
        atol = self.atol if isinstance(self.atol, Mapping) else dict.fromkeys(half, self.atol)
        return max(float(np.max(np.abs(half[n] - full[n]) / (atol[n] + self.rtol * np.abs(half[n]))))
                   for n in atol)

    def _snapshot(self, coupling: Coupling):
        states = {n: i.get_state() for n, i in coupling.instances.items()}
        memory = (deque(self.algorithm.history.samples, maxlen=self.algorithm.history.samples.maxlen),
                  dict(self.algorithm.inputs_set), list(self.algorithm.energy_residuals))
        return states, memory

    def _restore(self, coupling: Coupling, snapshot) -> None:
        states, (samples, inputs_set, residuals) = snapshot
        for n, instance in coupling.instances.items():
            instance.set_state(states[n])
        self.algorithm.history.samples = deque(samples, maxlen=samples.maxlen)
        self.algorithm.inputs_set, self.algorithm.energy_residuals = dict(inputs_set), list(residuals)

    @staticmethod
    def _free(coupling: Coupling, snapshot) -> None:
        for n, instance in coupling.instances.items():
            instance.free_state(snapshot[0][n])

    def advance(self, coupling: Coupling, t: float, t_end: float, max_accepted: int | None = None) -> float:
        """Steps from t to t_end (the last step shortened to land on it), or until max_accepted
        steps were accepted; returns the time reached."""
        accepted_before = len(self.accepted)
        while t_end - t > 1e-12 * max(1.0, abs(t_end)):
            if max_accepted is not None and len(self.accepted) - accepted_before >= max_accepted:
                return t
            h = min(self.h, t_end - t)
            start = self._snapshot(coupling)
            try:
                self.before_step(t)
                self.algorithm.step(coupling, t, h)
                full = self.algorithm.history.samples[-1][1]
                self._restore(coupling, start)
                self.before_step(t)
                self.algorithm.step(coupling, t, h / 2)
                self.before_step(t + h / 2)
                self.algorithm.step(coupling, t + h / 2, h / 2)
                half = self.algorithm.history.samples[-1][1]
                error = self.error(full, half)
                forced = len(self.accepted) in self.force_reject
                if forced:
                    self.force_reject.discard(len(self.accepted))
                if (error <= 1.0 or h <= self.h_min) and not forced:
                    t += h
                    self.accepted.append(h)
                    self.after_accept(t)
                else:
                    self._restore(coupling, start)
                    self.rejected += 1
                factor = 2.0 if error == 0 else min(2.0, max(0.2, 0.9 * error ** (-1.0 / (self.algorithm.order + 2))))
                if forced:
                    factor = 1.0  # the forced retry takes the same step again
                self.h = min(self.h_max, max(self.h_min, h * factor))
            finally:
                self._free(coupling, start)
        return t


class EnergyStep:
    """Macro-step control from the power bonds' energy residuals (ECCO, Sadjina et al. 2017): after
    each step the residual of every bond is scaled, eps = |dE| / (atol + rtol |E|) with E the energy
    the bond transferred over the step, and the next step follows a PI law,
    H_next = H safety (1 / eps_n)^k_I (eps_{n-1} / eps_n)^k_P, limited to [change_min H, change_max H]
    and [h_min, h_max].
    No rollback: the controller only looks ahead (it needs no FMU state), so it is cheap, and it
    keeps the coupling's energy error, not a state error, near its tolerance."""

    def __init__(self, algorithm: CouplingAlgorithm, rtol: float = 1e-3, atol: float = 1e-4,
                 h_initial: float = 1e-3, h_min: float = 1e-6, h_max: float = 1e-2, k_i: float = 0.15,
                 k_p: float = 0.2, safety: float = 1.0, change_min: float = 0.2, change_max: float = 2.0,
                 before_step: Callable[[float], None] | None = None,
                 after_accept: Callable[[float], None] | None = None):
        self.algorithm, self.rtol, self.atol = algorithm, rtol, atol
        self.h, self.h_min, self.h_max, self.k_i, self.k_p = h_initial, h_min, h_max, k_i, k_p
        self.safety, self.change_min, self.change_max = safety, change_min, change_max
        self.before_step, self.after_accept = before_step or (lambda t: None), after_accept or (lambda t: None)
        self.accepted: list[float] = []
        self.rejected = 0  # never: kept for the same report as AdaptiveStep
        self._previous = 1.0

    def advance(self, coupling: Coupling, t: float, t_end: float) -> float:
        if not coupling.bonds:
            raise ValueError("energy step control needs power bonds in the coupling")
        while t_end - t > 1e-12 * max(1.0, abs(t_end)):
            h = min(self.h, t_end - t)
            self.before_step(t)
            self.algorithm.step(coupling, t, h)
            t += h
            self.accepted.append(h)
            self.after_accept(t)
            residual, transferred = self.algorithm.bond_energies
            eps = max(float(np.max(np.abs(residual) / (self.atol + self.rtol * transferred))), 1e-10)
            factor = self.safety * (1.0 / eps) ** self.k_i * (self._previous / eps) ** self.k_p
            self._previous = eps
            self.h = min(self.h_max, max(self.h_min, h * min(self.change_max, max(self.change_min, factor))))
        return t_end


# -- running a system with the oracle (as cosim.engine.Execution runs it with the kernel) ---------

def algorithm_of(settings) -> CouplingAlgorithm:
    """The oracle algorithm for cosim.engine.Algorithm settings."""
    return Jacobi(settings.order) if settings.kind == "jacobi" else GaussSeidel(settings.order, settings.sequence)


class OracleRun:
    """rows (time and recorded columns per accepted step), energy residuals, accepted steps,
    rejections and the FmuError that stopped the run, if any."""

    def __init__(self, rows, residuals, steps, rejected, failure):
        self.rows, self.residuals, self.steps, self.rejected, self.failure = rows, residuals, steps, rejected, failure


def run(structure, settings, control, stop_time: float, record, clock: str, interpolating=None) -> OracleRun:
    from cosim.engine import EnergyControl, FixedStep, FmuError, StepDoubling

    instances = structure.instantiate()
    try:
        coupling = Coupling(instances, structure.connections, structure.bonds, interpolating)
        algorithm = algorithm_of(settings)
        algorithm.feedthrough = coupling.feedthrough() if getattr(settings, "feedthrough", False) else []
        algorithm.initialize(coupling, instances[clock].time, settings.initial_sweeps, settings.zero_start)

        def row():
            return [instances[clock].time, *[instances[c].get(v) for c, v in record]]

        rows, steps, rejected, failure = [row()], [], 0, None
        try:
            if isinstance(control, FixedStep):
                n = int(round((stop_time - instances[clock].time) / control.step))
                for _ in range(n):
                    algorithm.step(coupling, instances[clock].time, control.step)
                    rows.append(row())
                    steps.append(control.step)
            else:
                if isinstance(control, StepDoubling):
                    controller = AdaptiveStep(algorithm, control.rtol, control.atol, control.step, control.h_min,
                                              control.h_max)
                    controller.force_reject = set(control.force_reject)
                else:
                    assert isinstance(control, EnergyControl)
                    controller = EnergyStep(algorithm, control.rtol, control.atol, control.step, control.h_min,
                                            control.h_max, control.k_i, control.k_p, control.safety,
                                            control.change_min, control.change_max)
                controller.after_accept = lambda t: rows.append(row())
                try:
                    controller.advance(coupling, instances[clock].time, stop_time)
                finally:
                    steps, rejected = list(controller.accepted), controller.rejected
        except FmuError as error:
            failure = error
        return OracleRun(np.array(rows), list(algorithm.energy_residuals), steps, rejected, failure)
    finally:
        for instance in instances.values():
            instance.free()
