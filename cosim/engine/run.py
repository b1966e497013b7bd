"""The one way a system is run: a `Plan` (the system, its coupling and step control, how long, what is
recorded and how often) goes through `run`, which executes it (`execute`: the execution loop, a
divergence monitor watching it, a progress bar on a terminal, a diverged run's advice probed),
thins its results to the output interval, makes its report, writes its files (the results as CSV
and .mat, the FMUs' log, and what the application adds: a scene's plots) on every path, and raises
`RunStopped`, with the results up to then, for a run that stopped part way. `run` is the one entry
the application uses; the execution (cosim.engine.execution) is this module's.

`run_system` runs any SSP system by its own settings (the SSP annotation's, the command line's over
them): `cosim run FILE.ssp`, `cosim.simulate(system)` and a sweep's points of a system; the
platform application makes a Plan of a scene the same way (cosim.platform.run.runner).
"""

from __future__ import annotations

import time
from contextlib import nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from .execution import Execution, RunFailed
from .observers import DivergenceMonitor, Diverged, Observer, Progress
from .realtime import RealTime
from .outcome import Outcome, Report, RunStopped
from .files import OutputError, folder_lock
from .interrupts import deferred
from .results import thin, write_csv, write_log, write_mat
from .settings import Algorithm, FixedStep, StepControl, control_name, output_interval, recorded, system_settings
from .structure import SystemStructure


@dataclass(frozen=True)
class Plan:
    """One run of a system: its coupling and step control, its stop time, the recorded variables
    (component, variable) and their column names (None: component.variable), the interval results are kept at (None: every
    macro step), whose time the results carry (None: the run's own), the divergence monitor's
    threshold (None: unwatched) and the run's real time (None: as fast as it goes, no stream, no
    live input: cosim.engine.realtime)."""
    structure: SystemStructure
    algorithm: Algorithm
    control: StepControl
    stop_time: float
    record: Sequence[tuple[str, str]] = ()
    names: Sequence[str] | None = None
    output_interval: float | None = None
    clock: str | None = None
    divergence: float | None = 0.05
    real_time: RealTime | None = None
    model_exchange: bool = False  # the structure as one Model Exchange FMU under one solver (monolithic.integrate_plan)


def run(plan: Plan, out: Path | None = None, stem: str | None = None, *, progress: bool = False,
        advice: bool = False, report: Callable[[Outcome, np.ndarray], Report] = Report.of,
        files: Callable[[np.ndarray, Report, Outcome, Path], None] | None = None) -> tuple[np.ndarray, Report]:
    """Runs the plan; returns its results and its report (`report(outcome, results)`). With `out`,
    writes <stem>.csv, .mat and .log there and then what `files` writes (results, report, outcome,
    folder), also for a run that stops. progress: a bar on a terminal; advice: a diverged run
    probes for a step that holds. Raises RunStopped (its report and the results up to then) when
    an FMU failed or the coupling diverged; before a step, what makes the run impossible
    (ParameterError, NoStep, an FmuError at set-up)."""
    if out is not None:
        refuse_overwriting_inputs(plan.structure, Path(out), stem or plan.structure.name)
    observers = [*([DivergenceMonitor(ratio=plan.divergence)] if plan.divergence else []),
                 *([Progress(plan.structure.name)] if progress else [])]
    with folder_lock(out) if out is not None else nullcontext(), deferred():  # one run's files at a time in a
        #                                                                         folder; Ctrl-C never lost in an FMU
        if plan.model_exchange:
            from .monolithic import integrate_plan
            outcome = integrate_plan(plan, progress=[o for o in observers if isinstance(o, Progress)])
        else:
            outcome = execute(plan.structure, plan.algorithm, plan.control, plan.stop_time, plan.record, plan.names,
                              clock=plan.clock, observers=observers, advice=advice, real_time=plan.real_time)
        result = thin(outcome.result, plan.output_interval)
        made = report(outcome, result)
        if out is not None:
            write_files(result, made, outcome, Path(out), stem or plan.structure.name, files)
    if outcome.failure is not None:
        raise RunStopped(made, result, outcome.diverged)
    return result, made


def execute(structure: SystemStructure, algorithm: Algorithm, control: StepControl, stop_time: float,
            record: Sequence[tuple[str, str]] = (), names: Sequence[str] | None = None, clock: str | None = None,
            observers: Sequence[Observer] = (), advice: bool = False, real_time: RealTime | None = None) -> Outcome:
    """Runs `structure` from its start to stop_time and returns the Outcome; a run that an FMU or
    an observer stops is an Outcome with its failure and the results up to then, not an exception.
    advice: a fixed-step run that diverged probes shorter steps on the same system and its failure
    says which one held (advice_text). Raises before a single step for what makes the run
    impossible (ParameterError, NoStep, an FmuError at set-up); the FMUs are freed on every path.
    real_time: paced, streamed, driven from outside (cosim.engine.realtime); its figures in .pacing."""
    with Execution(structure, algorithm, control, record, names, clock=clock, real_time=real_time) as execution:
        setup_fmi = execution.fmi_seconds  # instantiation and parameters: not part of the stepping
        setup_by_instance = {name: instance.fmi_seconds for name, instance in execution.instances.items()}
        start = time.perf_counter()
        failure = None
        try:
            result = execution.run(stop_time, observers)
        except RunFailed as failed:
            result, failure = failed.result, failed
        wall = time.perf_counter() - start
        outcome = Outcome(structure.name, result, execution.energy_residuals, execution.steps, execution.rejected,
                          wall, execution.fmi_seconds - setup_fmi, control_name(control), execution.messages(),
                          dict(zip(execution.bond_names, execution.bond_residual_max.tolist())), list(observers),
                          fmi_seconds_by_instance={name: instance.fmi_seconds - setup_by_instance[name]
                                                   for name, instance in execution.instances.items()},
                          pacing=execution.pacing)
    if failure is not None and advice and isinstance(failure.error, Diverged) and isinstance(control, FixedStep):
        failure = RunFailed(Diverged(f"{failure}; " + advice_text(structure, algorithm, control.step,
                                                                    failure.error.time, stop_time),
                                     failure.error.time), result)
    outcome.failure = failure
    return outcome



FRACTIONS = (4, 16)  # probe a quarter, then a sixteenth of the step


def stable_step(structure: SystemStructure, algorithm: Algorithm, step: float, diverged_at: float,
                stop_time: float, ratio: float = 0.05, margin: float = 0.5) -> tuple[float | None, float, list[float]]:
    """(the first probed step that ran without diverging or failing, or None; the time probed to;
    the steps tried). Each probe runs from the start to diverged_at + margin (at most stop_time)."""
    until = min(stop_time, diverged_at + margin)
    tried = []
    for fraction in FRACTIONS:
        h = step / fraction
        tried.append(h)
        with Execution(structure, algorithm, FixedStep(h)) as execution:
            try:
                execution.run(until, [DivergenceMonitor(ratio=ratio)])
                return h, until, tried
            except RunFailed:  # diverged or an FMU failed: not a step to recommend
                continue
    return None, until, tried


def advice_text(structure: SystemStructure, algorithm: Algorithm, step: float, diverged_at: float,
                stop_time: float, ratio: float = 0.05) -> str:
    h, until, tried = stable_step(structure, algorithm, step, diverged_at, stop_time, ratio)
    if h is not None:
        return f"a probe at {h * 1e3:g} ms ran stable to t = {until:g} s: try a step of {h * 1e3:g} ms"
    return (f"probes at {', '.join(f'{t * 1e3:g}' for t in tried)} ms diverged too before t = {until:g} s: "
            f"no stable fixed step found; step doubling is worth a try but was not probed")


def refuse_overwriting_inputs(structure: SystemStructure, out: Path, stem: str) -> None:
    """A UsageError, before anything runs, when a file the run reads (a parameter that names one:
    a table, a vehicle's motion) is where its results would go (<stem>.csv, .mat, .log and the
    application's <stem>_*.png, <stem>.html in `out`)."""
    from .errors import UsageError
    for component in structure.components:
        for name, value in component.parameters.items():
            if not isinstance(value, Path):
                continue
            read = value.resolve()
            if read.parent == out.resolve() and (read.stem == stem or read.name.startswith(f"{stem}_")):
                raise UsageError(f"--out {out}: the results {stem}.* would overwrite {read.name}, which this run reads "
                                 f"({component.name}'s {name}): write them to another folder")


def write_files(result: np.ndarray, report: Report, outcome: Outcome, out: Path, stem: str,
                files: Callable[[np.ndarray, Report, Outcome, Path], None] | None = None) -> None:
    """The results as <stem>.csv and .mat, the log as <stem>.log and what `files` adds, each whole
    or not at all; what the disk cannot take is one OutputError naming it (and the files that
    did get written), after every other file has been tried: the results are kept where the space
    allows."""
    writes = [lambda: write_csv(result, out / f"{stem}.csv"), lambda: write_mat(result, out / f"{stem}.mat"),
              lambda: write_log(outcome.messages, out / f"{stem}.log"),
              *([lambda: files(result, report, outcome, out)] if files is not None else [])]
    failures, written = [], []
    for write in writes:
        try:
            written.append(write())
        except OutputError as error:
            failures.append(error)
    report.log = out / f"{stem}.log" if out / f"{stem}.log" in written else None
    if failures:
        more = f" (and {len(failures) - 1} more files)" if len(failures) > 1 else ""
        kept = [p.name for p in written if isinstance(p, Path)]
        raise OutputError(f"{failures[0]}{more}" + (f"; written: {', '.join(kept)}" if kept else ""))


def recording(structure: SystemStructure) -> tuple[list[tuple[str, str]], list[str]]:
    """What a run of `structure` records: its `record` setting, else every connected output."""
    chosen = recorded(structure.settings)
    if chosen is not None:
        return chosen
    outputs = list(dict.fromkeys(c.source for c in structure.connections))
    return outputs, [f"{c}.{v}" for c, v in outputs]


def system_plan(structure: SystemStructure, overrides: Mapping[str, str] | None = None,
                stop_time: float | None = None) -> Plan:
    """The plan of any system by its settings (the overrides over them, names as in
    cosim.engine.settings), until its DefaultExperiment's stop unless `stop_time` says."""
    from .fmi import loaded
    algorithm, control = system_settings(structure.settings, structure.experiment.step, overrides)
    record, names = recording(structure)
    model_exchange = all(loaded(c.fmu)[0].coSimulation is None for c in structure.components)  # ME FMUs only
    return Plan(structure, algorithm, control, structure.experiment.stop if stop_time is None else stop_time, record,
                names, output_interval(structure.settings), model_exchange=model_exchange)


def run_system(structure: SystemStructure, overrides: Mapping[str, str] | None = None,
               stop_time: float | None = None, out: Path | None = None, *, source: str | None = None,
               progress: bool = False, advice: bool = False, real_time: RealTime | None = None,
               plots: bool = False) -> tuple[np.ndarray, Report]:
    """Runs a system by its own settings (system_plan) and writes its results to `out` as
    <name>.csv, .mat and .log (and with `plots` the page and figure of cosim.engine.page); paced and
    streamed by `real_time` if given. What cannot start (a
    setting, a parameter value, a time that fits no step, an FMU that refuses its values) is an
    SspError naming `source` (the file the system came from; default its name), one line; a run
    that stopped part way raises RunStopped."""
    from .checks import ParameterError
    from .execution import NoStep
    from .fmi import FmuError
    from .settings import SettingsError
    from .ssp import SspError
    where = source or structure.name
    try:
        plan = system_plan(structure, overrides, stop_time)
        if real_time is not None and plan.model_exchange:
            raise SspError(f"{where}: its FMUs are Model Exchange, integrated by one solver as fast as it goes: "
                           "not paced or streamed")
        if real_time is not None:
            plan = replace(plan, real_time=real_time)

        def report(outcome: Outcome, result: np.ndarray) -> Report:
            made = Report.of(outcome)
            if structure.experiment.step_source not in ("", "this project's annotation") and \
                    not (overrides or {}).get("step"):
                made.remarks.append(f"macro step {structure.experiment.step:g} s: {structure.experiment.step_source}")
            return made
        def page(result: np.ndarray, made: Report, outcome: Outcome, folder: Path) -> None:
            from .page import write_page
            write_page(result, made.text(), plan.record, folder, Path(where).stem if source else structure.name)
        return run(plan, out, Path(where).stem if source else structure.name, progress=progress, advice=advice,
                   report=report, files=page if plots else None)
    except (ParameterError, NoStep, SettingsError, FmuError) as error:  # the values, settings or times, before a step
        raise SspError(f"{where}: {error}") from None
