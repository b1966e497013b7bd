"""The run loop: one for every algorithm and step control.

An `Execution` instantiates a `SystemStructure`, resolves its wiring, hands it to the step kernel
and runs it to a stop time in batches; after each batch the observers see the new rows (recorder,
divergence monitor, progress). The kernel advances the system; the execution only loops; the
observers only watch (libcosim's split of algorithm, execution and observers).
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from .checks import check_capabilities, check_parameters
from .coupling import Coupling
from . import interrupts
from .fmi import FmuError, FmuInstance, LogMessage
from .kernel import Kernel
from .observers import Diverged, Observer, RecordFull, Recorder
from .realtime import RealTime, Session, batch_size
from .settings import Algorithm, FixedStep, SettingsError, StepControl, control_name
from .structure import SystemStructure


class RunFailed(RuntimeError):
    """An FMU failed mid-run (`error` an FmuError: which instance, call and time), an observer
    stopped the run (`error` e.g. a Diverged: when, how much, where, what to try) or the run could
    not take a step; `result` holds the rows computed up to then, and `outcome` (a
    cosim.engine.outcome.Outcome, where the run path made one) everything else the run measured."""

    def __init__(self, error: Exception, result: np.ndarray, outcome=None):
        super().__init__(str(error))
        self.error, self.result, self.outcome = error, result, outcome


class Execution:
    """`structure` instantiated and run by `algorithm` under `control`, recording `record`
    ((component, variable) pairs) as columns `names` (default 'component.variable') after every
    accepted step. The time column is that of component `clock` (default the first).
    `interpolating` overrides per component whether it takes input derivatives (default: its
    modelDescription's canInterpolateInputs). `real_time`: the run paced to the wall clock,
    streamed and driven from outside (cosim.engine.realtime; fixed steps only). A context manager:
    the FMUs are freed on leaving it."""

    def __init__(self, structure: SystemStructure, algorithm: Algorithm, control: StepControl,
                 record: Sequence[tuple[str, str]] = (), names: Sequence[str] | None = None,
                 clock: str | None = None, logging_on: bool = False,
                 interpolating: Mapping[str, bool] | None = None, real_time: RealTime | None = None):
        check_parameters(structure)  # before any FMU is instantiated
        check_capabilities(structure, control)
        if real_time is not None and not isinstance(control, FixedStep):
            what = ("a real-time run takes fixed steps, one a deadline" if real_time.factor is not None or
                    real_time.stream or real_time.listen else
                    "a guarded reference takes fixed steps, held within its envelope at each (a cueing scene's)")
            raise SettingsError(f"{what}; the step control '{control_name(control)}' chooses its steps as it goes: set "
                                "step_control = fixed", "step_control")
        self.real_time, self.pacing = real_time, None
        self.structure, self.algorithm, self.control = structure, algorithm, control
        self.record = list(record)
        self.control_name = control_name(control)
        if algorithm.sequence and sorted(algorithm.sequence) != sorted(c.name for c in structure.components):
            raise SettingsError(f"the Gauss-Seidel sequence {list(algorithm.sequence)} must name every component "
                                f"once: {[c.name for c in structure.components]}", "sequence")
        self.instances: dict[str, FmuInstance] = structure.instantiate(logging_on)
        try:
            self.coupling = Coupling(self.instances, structure.connections, structure.bonds, interpolating)
            self.kernel = Kernel(self.coupling, algorithm, list(record), clock or structure.components[0].name)
        except BaseException:
            self.free()
            raise
        self.names = ["time", *(names if names is not None else [f"{c}.{v}" for c, v in record])]
        self.bond_names = self.coupling.bond_names()
        self.energy_residuals = np.zeros(0)  # per macro step, the largest |energy residual| of a bond [J]
        self.steps = np.zeros(0)              # the accepted macro steps [s]
        self.bond_residual_max = np.zeros(len(self.bond_names))  # per bond, the largest |residual| of a step [J]
        self.start_time = self.stop_time = structure.experiment.start
        self.session: Session | None = None
        self.master_messages: list[LogMessage] = []  # what the master itself logs (the live input's watchdog)
        self.record_budget = 0.5 * _memory()  # [bytes] of recorded rows; a fixed-step run is refused above it

    @property
    def rejected(self) -> int:
        return self.kernel.rejected

    @property
    def time(self) -> float:
        return self.kernel.time

    @property
    def fmi_seconds(self) -> float:
        return sum(i.fmi_seconds for i in self.instances.values())

    def messages(self, status: str | None = None) -> list[tuple[str, LogMessage]]:
        """(instance, message) of everything the FMUs logged and the master ("master": a live
        input's watchdog), or only of one status."""
        return [*((n, m) for n, i in self.instances.items() for m in i.messages if status in (None, m.status)),
                *(("master", m) for m in self.master_messages if status in (None, m.status))]

    def run(self, stop_time: float, observers: Sequence[Observer] = ()) -> np.ndarray:
        """Runs from the start to stop_time; returns the recorded results (structured array).
        Raises RunFailed with the results up to the last good step when an FMU fails, an observer
        stops the run, or not a single step fits before stop_time."""
        self._check_stop(stop_time)
        recorder = Recorder(self.names, self.record_budget)
        observers = [recorder, *observers]
        self.start_time, self.stop_time = self.time, stop_time
        parts_residuals, parts_steps = [], []
        session = Session(self.real_time, self.names[1:], self.record, self.coupling.names, self.coupling.sources) \
            if self.real_time else None
        self.session = session
        try:
            recorder.add(self.kernel.initialize())
            for observer in observers:
                observer.start(self)
            if isinstance(self.control, FixedStep):
                batches = self._fixed_batches(stop_time)
            else:
                self.kernel.start_controller(self.control)
                batches = self._controlled_batches(stop_time)
            for batch in batches:
                parts_residuals.append(batch.residuals)
                parts_steps.append(batch.steps)
                if len(batch.bond_energy):
                    self.bond_residual_max = np.maximum(self.bond_residual_max,
                                                        np.abs(batch.bond_energy[:, :, 0]).max(axis=0))
                for observer in observers:
                    observer.batch(self, batch)
                for observer in observers:
                    if observer.stop is not None:
                        raise observer.stop
                interrupts.check()  # a Ctrl-C an FMU's callback held back
                if session:
                    session.between_batches()
                    self.master_messages += session.news()
        except FmuError as error:
            batch = getattr(error, "batch", None)
            if batch is not None:
                recorder.batch(self, batch)
                parts_residuals.append(batch.residuals)
                parts_steps.append(batch.steps)
            raise RunFailed(error, recorder.result()) from error
        except (Diverged, RecordFull) as error:
            raise RunFailed(error, recorder.result()) from error
        finally:
            self.energy_residuals = np.concatenate([self.energy_residuals, *parts_residuals])
            self.steps = np.concatenate([self.steps, *parts_steps])
            if session:
                self.master_messages += session.news()
                self.pacing = session.pacing()
                session.close()
            for observer in observers:
                observer.finish(self)
        return recorder.result()

    def _check_stop(self, stop_time: float) -> None:
        if not (isinstance(stop_time, (int, float)) and math.isfinite(stop_time)):
            raise NoStep(f"the stop time {stop_time!r} is not a finite number")
        if isinstance(self.control, FixedStep):
            steps = round((stop_time - self.time) / self.control.step)
            if steps < 1:
                raise NoStep(f"the macro step {self.control.step:g} s does not fit once between t = {self.time:g} s "
                             f"and the stop time {stop_time:g} s")
            finer = round(self.control.step / self.control.startup_step) if self.control.startup_time > 0 else 1
            rows = steps + (finer - 1) * (round(self.control.startup_time / self.control.step)
                                          + sum(round((b - a) / self.control.step) + 1 for a, b in self.control.windows))
            needed = 8.0 * rows * len(self.names)
            if needed > self.record_budget:
                raise NoStep(f"the run would record {rows:.3g} rows of {len(self.names)} columns ({needed / 2 ** 30:.3g} "
                             f"GiB), more than half of this machine's {2 * self.record_budget / 2 ** 30:.3g} GiB: "
                             "shorten it, or record fewer outputs or take longer steps")
        elif stop_time - self.time <= 1e-12 * max(1.0, abs(stop_time)):
            raise NoStep(f"the stop time {stop_time:g} s is not after the start {self.time:g} s")

    def _fixed_batches(self, stop_time: float):
        """The regular steps from now to stop_time, those of the finer start and of the windows
        taken at startup_step instead, landing on the regular grid (fixed_runs)."""
        for h, n in fixed_runs(self.control, self.time, stop_time):
            yield from self._batches(h, n)

    def _batches(self, h: float, n: int):
        done, size = 0, 100  # small batches first: a divergence shows early
        largest = 1000
        if self.session:  # under real time: long batches (the work between them is a step's lateness) ...
            largest = size = batch_size(self.real_time, h)
            if not self.session.started:  # ... and the clock starts after the first step, the start-up iteration
                yield self.kernel.run_fixed(h, 1, self.session.unpaced())
                self.session.start(self.time)
                done = 1
        while done < n:
            take = min(size, largest, n - done)
            size = min(2 * size, largest)
            yield self.kernel.run_fixed(h, take, self.session)
            done += take

    def _controlled_batches(self, stop_time: float):
        while stop_time - self.kernel.controller_time > 1e-12 * max(1.0, abs(stop_time)):
            yield self.kernel.run_controlled(stop_time, 500)

    def __enter__(self) -> "Execution":
        return self

    def __exit__(self, *exc) -> None:
        self.free()

    def free(self) -> None:
        if getattr(self, "kernel", None) is not None:
            self.kernel.release()
        for instance in self.instances.values():
            instance.free()
        self.instances = {}


def fixed_runs(control: FixedStep, start: float, stop_time: float) -> list[tuple[float, int]]:
    """A fixed-step run from start to stop_time as runs of equal steps (step, count): the regular
    steps, those of the finer start and of the windows taken at startup_step instead, landing on
    the regular grid. The one plan of a fixed-step run, ours and the system FMU's."""
    h = control.step
    n = int(round((stop_time - start) / h))
    fine = np.zeros(n, dtype=bool)  # per regular step: taken at the finer step
    if control.startup_time > 0.0:
        fine[:int(round(control.startup_time / h))] = True
    for window_start, window_end in control.windows:
        first = max(0, math.floor((window_start - start) / h + 1e-9))
        last = min(n, math.ceil((window_end - start) / h - 1e-9))
        fine[first:max(first, last)] = True
    per = int(round(h / control.startup_step)) if control.startup_time > 0.0 else 1
    bounds = [0, *(np.flatnonzero(np.diff(fine)) + 1).tolist(), n] if n else [0]  # runs of equal kind
    return [(control.startup_step, (end - k) * per) if fine[k] else (h, end - k)
            for k, end in zip(bounds[:-1], bounds[1:])]


def _memory() -> float:
    """This machine's physical memory [bytes] (inf where it cannot be read)."""
    import os
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return math.inf


class NoStep(ValueError):
    """A run that cannot take a single step (stop time not after the start, step longer than the
    run): a user error, raised before anything is stepped or recorded."""
