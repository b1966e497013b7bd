"""A system of Model Exchange FMUs integrated as one ODE by one solver (SUNDIALS CVODE, BDF with a
dense Jacobian, through fmpy): no coupling, so no coupling error: the reference a co-simulation of
the same models is measured against, and the answer a tool with a monolithic solver gives
(OMSimulator's strongly coupled master, Dymola, fmpy).

The state is every FMU's continuous states end to end. At each evaluation of the right-hand side
the time and states are set, then the connections carry each output to its input, sweep after
sweep in the structure's order until no input changes (a system without algebraic loops settles
in as many sweeps as its longest chain), then each FMU gives its derivatives. Time events (an FMU's
next event time, from fmi2NewDiscreteStates) end an integration interval; the solver restarts
after each. Results are recorded on the output grid (the plan's interval, else the experiment's
step), each FMU told of the completed step there.

`cosim run SCENE --me` (integrate_plan) integrates the scene as ONE Model Exchange FMU
(cosim.engine.system_fmu), whose binary carries the connections in C: a system of one FMU, so the
carrying here is then empty. A system that is Model Exchange FMUs as they are (`cosim run FILE.fmu`
on one, an SSP of them) is carried here; tests/engine/test_system_fmu_me.py holds the two to the
same derivatives bit for bit.
"""

from __future__ import annotations

import ctypes
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Model, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

from .errors import UsageError
from .fmi import LogMessage, loaded
from .outcome import Outcome
from .structure import SystemStructure

_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]
_STATUS = ("ok", "warning", "discard", "error", "fatal", "pending")
_DOUBLES = ctypes.POINTER(ctypes.c_double)
RELATIVE_TOLERANCE = 1e-8  # CVODE's, the absolute one per state as much of the FMU's nominal of it


class Stopped(RuntimeError):
    """An FMU refused a call or the solver failed: the results up to then stand."""


@dataclass
class _Member:
    name: str
    fmu: FMU2Model
    references: dict[str, int]
    types: dict[str, str]
    states: slice


class MonolithicSystem:
    """The structure's FMUs instantiated as Model Exchange, initialized with their parameters and
    connections; time, states, derivatives and outputs of the whole."""

    def __init__(self, structure: SystemStructure):
        self.structure = structure
        self.messages: list[tuple[str, LogMessage]] = []
        self.members: dict[str, _Member] = {}
        self._reads: dict[tuple, list] = {}  # per record: each FMU's references and their places in it
        self.fmi_seconds = 0.0
        self._callbacks = []
        self.time = structure.experiment.start
        self.first_event = math.inf  # the first time event after the start (set by the initial event iteration)
        offset = 0
        try:
            for component in structure.components:
                description = read_model_description(str(component.fmu))
                if description.modelExchange is None:
                    raise UsageError(f"{component.name}: {component.fmu.name} is not a Model Exchange FMU (a run as "
                                     "one system needs every FMU as Model Exchange)")
                n = description.numberOfContinuousStates
                fmu = FMU2Model(guid=description.guid, unzipDirectory=str(loaded(component.fmu)[1]),
                                modelIdentifier=description.modelExchange.modelIdentifier, instanceName=component.name)
                fmu.instantiate(callbacks=self._callbacks_for(component.name))
                variables = description.modelVariables
                self.members[component.name] = _Member(component.name, fmu, {v.name: v.valueReference for v in variables},
                                                       {v.name: v.type for v in variables}, slice(offset, offset + n))
                offset += n
            self.size = offset
            self._connections = self._grouped()
            self._initialize()
        except BaseException:
            self.free()
            raise

    # -- set-up ------------------------------------------------------------------------------

    def _callbacks_for(self, name: str) -> fmi2CallbackFunctions:
        def log(env, instance, status, category, message):
            self.messages.append((name, LogMessage(_STATUS[status] if 0 <= status < 6 else str(status),
                                                   (category or b"").decode(), (message or b"").decode(), self.time)))
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(log)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
        self._callbacks.append(callbacks)  # kept alive with the system
        return callbacks

    def _grouped(self) -> list[tuple[_Member, list[int], _Member, list[int]]]:
        """The connections, per (source, target) pair of FMUs in the structure's order."""
        pairs: dict[tuple[str, str], tuple[list[int], list[int]]] = {}
        for c in self.structure.connections:
            source, target = self.members[c.source[0]], self.members[c.target[0]]
            outputs, inputs = pairs.setdefault((source.name, target.name), ([], []))
            outputs.append(source.references[c.source[1]])
            inputs.append(target.references[c.target[1]])
        return [(self.members[s], o, self.members[t], i) for (s, t), (o, i) in pairs.items()]

    def _set(self, member: _Member, values: dict) -> None:
        for name, value in values.items():
            kind, reference = member.types[name], [member.references[name]]
            if kind == "Real":
                member.fmu.setReal(reference, [float(value)])
            elif kind in ("Integer", "Enumeration"):
                member.fmu.setInteger(reference, [int(value)])
            elif kind == "Boolean":
                member.fmu.setBoolean(reference, [bool(value)])
            else:
                member.fmu.setString(reference, [str(value)])

    def _initialize(self) -> None:
        start = self.structure.experiment.start
        for component in self.structure.components:
            member = self.members[component.name]
            self._call(member, "fmi2SetupExperiment", member.fmu.setupExperiment, startTime=start)
            self._call(member, "set parameters", self._set, member, component.parameters)
            self._call(member, "fmi2EnterInitializationMode", member.fmu.enterInitializationMode)
        self.propagate()
        for member in self.members.values():
            self._call(member, "fmi2ExitInitializationMode", member.fmu.exitInitializationMode)
        self.first_event = self.event(enter=False)[0]  # the initial event's iteration (each FMU in Event Mode)

    def _call(self, member: _Member, what: str, function, *args, **kwargs):
        start = time.perf_counter()
        try:
            return function(*args, **kwargs)
        except FMICallException:
            said = "; ".join(m.text for n, m in self.messages if n == member.name and m.status in ("error", "fatal"))
            raise Stopped(f"{member.name}: {what} failed at t = {self.time:.9g} s: {said or 'the FMU gave no reason'}")
        finally:
            self.fmi_seconds += time.perf_counter() - start

    # -- the whole as one ODE ----------------------------------------------------------------

    def propagate(self, sweeps: int = 10) -> None:
        """Every connection's output to its input, until no input changes."""
        if not self._connections:  # one FMU (a system FMU carries its own inside)
            return
        start, last = time.perf_counter(), None
        try:
            for _ in range(sweeps):
                carried = []
                for source, outputs, target, inputs in self._connections:
                    values = source.fmu.getReal(outputs)
                    target.fmu.setReal(inputs, values)
                    carried.extend(values)
                if carried == last:
                    return
                last = carried
        except FMICallException:
            raise Stopped(f"the connections could not be carried at t = {self.time:.9g} s: "
                          + ("; ".join(m.text for _, m in self.messages if m.status in ("error", "fatal"))
                             or "an FMU gave no reason")) from None
        finally:
            self.fmi_seconds += time.perf_counter() - start

    def _refused(self, member: _Member, call: str) -> Stopped:
        said = "; ".join(m.text for s, m in self.messages if s == member.name and m.status in ("error", "fatal"))
        return Stopped(f"{member.name}: {call} failed at t = {self.time:.9g} s: {said or 'the FMU gave no reason'}")

    def set_time(self, t: float) -> None:
        """Every FMU's time (straight into its function, as the right-hand side's calls)."""
        self.time = t
        start = time.perf_counter()
        try:
            for member in self.members.values():
                if member.fmu.dll.fmi2SetTime(member.fmu.component, t) > 1:
                    raise self._refused(member, "fmi2SetTime")
        finally:
            self.fmi_seconds += time.perf_counter() - start

    @staticmethod
    def _pointer(values: np.ndarray):
        return values.ctypes.data_as(ctypes.POINTER(ctypes.c_double))

    def set_states(self, x: np.ndarray) -> None:
        x = np.ascontiguousarray(x, dtype=float)
        for member in self.members.values():
            n = member.states.stop - member.states.start
            if n:
                part = np.ascontiguousarray(x[member.states])
                self._call(member, "fmi2SetContinuousStates", member.fmu.setContinuousStates, self._pointer(part), n)
        self.propagate()

    def _each_part(self, call: str, name: str, pointer) -> None:
        """Every FMU's part of the vector at `pointer` (its states, their derivatives: `name` the
        fmpy method) passed to or filled by it in place: the solver's right-hand side, called
        straight into each FMU's function (fmpy's own wrapper costs more than the call)."""
        start = time.perf_counter()
        base = None
        try:
            for member in self.members.values():
                n = member.states.stop - member.states.start
                if not n:
                    continue
                part = pointer
                if member.states.start:  # a later FMU's part: its place in the vector
                    base = base or ctypes.cast(pointer, ctypes.c_void_p).value
                    part = ctypes.cast(base + 8 * member.states.start, _DOUBLES)
                if getattr(member.fmu.dll, call)(member.fmu.component, part, n) > 1:
                    raise self._refused(member, call)
        finally:
            self.fmi_seconds += time.perf_counter() - start

    def _gathered(self, call: str, name: str) -> np.ndarray:
        out = np.zeros(max(self.size, 1))
        self._each_part(call, name, self._pointer(out))
        return out[:self.size]

    def states(self) -> np.ndarray:
        return self._gathered("fmi2GetContinuousStates", "getContinuousStates")

    def derivatives(self) -> np.ndarray:
        return self._gathered("fmi2GetDerivatives", "getDerivatives")

    def set_states_at(self, pointer) -> None:
        """set_states from the solver's vector in place."""
        self._each_part("fmi2SetContinuousStates", "setContinuousStates", pointer)
        self.propagate()

    def states_into(self, pointer) -> None:
        self._each_part("fmi2GetContinuousStates", "getContinuousStates", pointer)

    def derivatives_into(self, pointer) -> None:
        self._each_part("fmi2GetDerivatives", "getDerivatives", pointer)

    def nominals_into(self, pointer) -> None:
        """Each FMU's nominals of its states (a solver's absolute tolerance is its relative one
        times them, as fmpy and fmusim set it)."""
        self._each_part("fmi2GetNominalsOfContinuousStates", "getNominalsOfContinuousStates", pointer)

    def event(self, enter: bool = True) -> tuple[float, bool]:
        """Every FMU through Event Mode (entered unless it is there: after initialization); the
        next time event of any (inf: none), and whether any changed its states or right-hand side
        there (the solver restarts; an event that changed nothing lets it step on)."""
        following, changed = math.inf, False
        for member in self.members.values():
            fmu = member.fmu
            if enter:
                self._call(member, "fmi2EnterEventMode", fmu.enterEventMode)
            needed = True
            while needed:
                needed, terminate, _, values_changed, defined, at = self._call(member, "fmi2NewDiscreteStates",
                                                                               fmu.newDiscreteStates)
                changed = changed or bool(values_changed)
            if terminate:
                raise Stopped(f"{member.name}: asked to terminate at t = {self.time:.9g} s")
            if defined:
                following = min(following, at)
            self._call(member, "fmi2EnterContinuousTimeMode", fmu.enterContinuousTimeMode)
        self.propagate()
        return following, changed

    def completed_step(self) -> None:
        start = time.perf_counter()
        event, terminate = ctypes.c_int(0), ctypes.c_int(0)
        try:
            for member in self.members.values():
                if member.fmu.dll.fmi2CompletedIntegratorStep(member.fmu.component, 1, ctypes.byref(event),
                                                              ctypes.byref(terminate)) > 1:
                    raise self._refused(member, "fmi2CompletedIntegratorStep")
                if terminate.value:
                    raise Stopped(f"{member.name}: asked to terminate at t = {self.time:.9g} s")
        finally:
            self.fmi_seconds += time.perf_counter() - start

    def outputs(self, record: Sequence[tuple[str, str]]) -> list[float]:
        """The recorded values, one fmi2GetReal per FMU."""
        start = time.perf_counter()
        key = tuple(record)
        if key not in self._reads:
            places: dict[str, tuple[list[int], list[int]]] = {}
            for k, (c, v) in enumerate(record):
                references, positions = places.setdefault(c, ([], []))
                references.append(self.members[c].references[v])
                positions.append(k)
            self._reads[key] = [(self.members[c], r, p) for c, (r, p) in places.items()]
        values = [0.0] * len(record)
        try:
            for member, references, positions in self._reads[key]:
                for position, value in zip(positions, member.fmu.getReal(references)):
                    values[position] = value
            return values
        finally:
            self.fmi_seconds += time.perf_counter() - start

    def free(self) -> None:
        for member in self.members.values():
            try:
                member.fmu.terminate()
            except FMICallException:
                pass
            member.fmu.freeInstance()
        self.members = {}


SYSTEM = "system"  # the one Model Exchange FMU's component in integrate_plan


def integrate_plan(plan, progress: Sequence = ()) -> Outcome:
    """A co-simulation plan's system (`cosim run --me`) as ONE Model Exchange FMU
    (cosim.engine.system_fmu: the connections carried inside its derivatives, in C) integrated by
    CVODE as `integrate` integrates any system: the right-hand side one call into the FMU. Its
    results are named as the plan's; each message is its component's again. A system of Model
    Exchange FMUs only (a lone one: `cosim run FILE.fmu`) is integrated as it is."""
    import tempfile
    from dataclasses import replace
    from .structure import Component
    from .system_fmu import write_system_fmu
    from .fmi import forget, loaded
    progress = list(progress)
    if all(loaded(c.fmu)[0].coSimulation is None for c in plan.structure.components):  # Model Exchange FMUs as
        return integrate(plan.structure, plan.stop_time, plan.record, plan.names,  # they are (a lone one's run)
                         plan.output_interval, progress=progress)
    names = list(plan.names) if plan.names is not None else [f"{c}.{v}" for c, v in plan.record]
    with tempfile.TemporaryDirectory(prefix="cosim-me-") as folder:
        fmu = write_system_fmu(replace(plan, model_exchange=False), Path(folder) / "system.fmu",
                               model_exchange=True)
        one = replace(plan.structure, components=[Component(SYSTEM, fmu)], connections=[])
        try:
            outcome = integrate(one, plan.stop_time, [(SYSTEM, n) for n in names], names, plan.output_interval,
                                progress=progress)
        finally:
            forget(fmu)  # written for this run: its extraction goes with it
    components = {c.name for c in plan.structure.components}
    messages = []
    for _, message in outcome.messages:  # "mechanics: t = ... leg 4 ..." is mechanics' own
        whose, _, text = message.text.partition(": ")
        messages.append((whose, replace(message, text=text)) if whose in components else (plan.structure.name, message))
    return replace(outcome, messages=messages)


def model_exchange_structure(structure: SystemStructure) -> SystemStructure:
    """The structure with each FMU as Model Exchange: the FMU itself where it offers it, else its
    twin built beside it (build/fmus_me/ for build/fmus/); UsageError naming the component that
    has neither."""
    from dataclasses import replace
    from .artifacts import FMU_DIR, FMU_ME_DIR
    components = []
    for component in structure.components:
        path = Path(component.fmu)
        if read_model_description(str(path)).modelExchange is None:
            twin = FMU_ME_DIR / path.name
            if path.resolve().parent != FMU_DIR.resolve() or not twin.is_file():
                raise UsageError(f"{component.name}: {path.name} is Co-Simulation only (no Model Exchange FMU of it): "
                                 "this system runs as co-simulation")
            path = twin
        components.append(replace(component, fmu=path))
    return replace(structure, components=components)


def _solver(system: MonolithicSystem, t: float, relative_tolerance: float):
    """fmpy's CVODE (BDF) on the system's states from t, its absolute tolerance per state the
    relative one times the FMU's nominal of it."""
    from fmpy.sundials import CVodeSolver

    class _NoInput:
        def apply(self, t):
            pass

    return CVodeSolver(system.size, 0, lambda pointer, n: system.states_into(pointer),
                       lambda pointer, n: system.set_states_at(pointer),
                       lambda pointer, n: system.derivatives_into(pointer), lambda pointer, n: None,
                       lambda pointer, n: system.nominals_into(pointer), system.set_time, _NoInput(), t,
                       relativeTolerance=relative_tolerance, maxNumSteps=100000)


def integrate(structure: SystemStructure, stop_time: float, record: Sequence[tuple[str, str]],
              names: Sequence[str] | None = None, output_interval: float | None = None,
              relative_tolerance: float = RELATIVE_TOLERANCE, progress: Sequence = ()) -> Outcome:
    """The structure's FMUs as one ODE under CVODE from its start to stop_time, `record` on the
    output grid (columns `names`, default component.variable). An FMU's refusal or the solver's
    failure ends the results where they got (Outcome.failure). `progress`: observers that show how
    far it got (cosim.engine.observers.Progress, the co-simulation's bar), told every 100 rows."""
    from types import SimpleNamespace
    from .execution import RunFailed
    names = list(names) if names is not None else [f"{c}.{v}" for c, v in record]
    interval = output_interval or structure.experiment.step
    start = time.perf_counter()
    system = MonolithicSystem(structure)
    rows, failure = [], None
    run = SimpleNamespace(start_time=structure.experiment.start, stop_time=stop_time)  # as Progress reads a run
    for observer in progress:
        observer.start(run)
    try:
        t = structure.experiment.start
        next_event = system.first_event

        solver = _solver(system, t, relative_tolerance)
        rows.append([t, *system.outputs(record)])
        grid = 1

        def reached(at: float) -> bool:  # a time within rounding of now (a grid point and a table's row
            return at - t <= 1e-12 * max(1.0, abs(t))  # a few ulps apart): CVODE cannot step there

        while not reached(stop_time):
            target = min(structure.experiment.start + grid * interval, stop_time)
            goal = min(target, next_event)
            if not reached(goal):
                try:
                    _, _, t = solver.step(t, goal)
                except RuntimeError as error:
                    raise Stopped(f"the solver failed at t = {system.time:.9g} s: {error}") from None
                system.set_time(t)  # the solver's states at t are set (CVodeSolver.step)
                system.propagate()
                system.completed_step()
            elif goal > t:  # taken as now: time moves on to it, the states stay
                t = goal
                system.set_time(t)
                system.propagate()
            if reached(next_event):
                next_event, changed = system.event()
                if changed:
                    solver.reset(t)
            if reached(target):
                rows.append([t, *system.outputs(record)])
                grid += 1
                if grid % 100 == 0:
                    for observer in progress:
                        observer.batch(run, SimpleNamespace(rows=np.array([[t]])))
        for observer in progress:  # and where it ended
            observer.batch(run, SimpleNamespace(rows=np.array([[t]])))
    except Stopped as stopped:
        failure = RunFailed(stopped, None)
    finally:
        system.free()
        for observer in progress:
            observer.finish(run)
    wall = time.perf_counter() - start
    result = np.array([tuple(r) for r in rows], dtype=[("time", float)] + [(n, float) for n in names])
    if failure is not None:
        failure = RunFailed(failure.error, result)
    return Outcome(structure.name, result, np.zeros(len(result)), np.diff(result["time"]) if len(result) > 1 else
                   np.zeros(0), 0, wall, system.fmi_seconds, "cvode", system.messages, failure=failure)
