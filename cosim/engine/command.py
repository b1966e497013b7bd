"""`python -m cosim run FILE.ssp|FILE.ssd`: any SSP system run with the engine's algorithms.

The coupling and step control come from the SSP's annotation (cosim.engine.ssp) unless the command
line overrides them (`--set name=value`, names as in cosim.engine.settings); the recorded columns
from the annotation's `record` setting, else every connected output as `component.variable`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

from .execution import Execution, RunFailed
from .advice import advice_text
from .observers import DivergenceMonitor, Diverged, Progress
from .settings import FixedStep
from .results import message_kinds, thin, write, write_log
from .settings import from_strings
from .structure import SystemStructure


@dataclass
class SystemReport:
    name: str
    macro_steps: int
    rejected: int
    simulated: float
    wall: float
    fmi_seconds: float
    largest_energy_residual: float
    warnings: int
    failure: str | None = None
    messages: list = field(default_factory=list)  # (instance, LogMessage) of everything logged

    def text(self) -> str:
        rtf = self.simulated / self.wall if self.wall > 0 else float("inf")
        lines = [f"{self.name}: {self.simulated:g} s simulated in {self.wall:.2f} s wall, {self.macro_steps} macro steps"
                 f" ({self.rejected} rejected), real-time factor {rtf:.1f}, "
                 f"{100 * (1 - self.fmi_seconds / self.wall) if self.wall > 0 else 0:.0f} % of the wall time in the "
                 f"master outside the FMUs", f"largest energy residual of a power bond in one step: "
                 f"{self.largest_energy_residual:.2e} J"]
        if self.warnings:
            kinds = "; ".join(f"{n} x {kind}" for n, kind in message_kinds(self.messages)[:3])
            lines.append(f"{self.warnings} warnings from the FMUs ({kinds})")
        if self.failure:
            lines.append(f"FAILED: {self.failure}")
        return "\n".join(lines)


def recording(structure: SystemStructure) -> tuple[list[tuple[str, str]], list[str]]:
    """What a run of `structure` records: its `record` setting ('component.variable=name ...'),
    else every connected output."""
    text = structure.settings.get("record")
    if text:
        pairs = [item.split("=", 1) for item in str(text).split()]
        record = [tuple(source.split(".", 1)) for source, _ in pairs]
        return record, [name for _, name in pairs]
    outputs = list(dict.fromkeys(c.source for c in structure.connections))
    return outputs, [f"{c}.{v}" for c, v in outputs]


def run_structure(structure: SystemStructure, overrides: Mapping[str, str] | None = None,
                  stop_time: float | None = None, progress: bool = True,
                  advice: bool = True) -> tuple[np.ndarray, SystemReport]:
    """Runs `structure` with its settings (and the overrides); raises RunFailed with .report.
    progress: a progress bar on a terminal; advice: a diverged run probes for a step that holds
    (both off for a sweep's points)."""
    settings = {k: str(v) for k, v in structure.settings.items() if k not in ("record", "output_interval")}
    settings.update(overrides or {})
    algorithm, control = from_strings(settings, structure.experiment.step)
    record, names = recording(structure)
    stop = structure.experiment.stop if stop_time is None else stop_time
    execution = Execution(structure, algorithm, control, record, names)
    start = time.perf_counter()
    failure = None
    try:
        result = execution.run(stop, [DivergenceMonitor(), *([Progress(structure.name)] if progress else [])])
    except RunFailed as failed:
        result, failure = failed.result, failed
    wall = time.perf_counter() - start
    if failure is not None and advice and isinstance(failure.error, Diverged) and isinstance(control, FixedStep):
        failure = RunFailed(Diverged(f"{failure}; " + advice_text(structure, algorithm, control.step,
                                                                    failure.error.time, stop), failure.error.time),
                            failure.result)
    report = SystemReport(structure.name, len(execution.steps), execution.rejected,
                          float(result["time"][-1] - result["time"][0]) if len(result) else 0.0, wall,
                          execution.fmi_seconds, float(np.max(execution.energy_residuals, initial=0.0)),
                          len(execution.messages("warning")), str(failure) if failure else None,
                          execution.messages())
    execution.free()
    interval = structure.settings.get("output_interval")
    result = thin(result, float(interval) if interval else None)
    if failure is not None:
        failure.report, failure.result = report, result
        raise failure
    return result, report


def run_ssp(path: Path, out: Path | None, overrides: Mapping[str, str] | None = None,
            stop_time: float | None = None) -> tuple[np.ndarray, SystemReport]:
    """Reads and runs an SSP system; writes <stem>.csv and .mat to `out` (also when it fails)."""
    from .checks import ParameterError
    from .execution import NoStep
    from .fmi import FmuError
    from .ssp import SspError, read_ssp
    structure = read_ssp(path)
    try:
        result, report = run_structure(structure, overrides, stop_time)
    except (ParameterError, NoStep) as error:  # the SSP's values or times, before a single step
        raise SspError(f"{path}: {error}") from None
    except FmuError as error:  # an FMU that rejects the SSP's values when it is set up
        raise SspError(f"{path}: {error}") from None
    except RunFailed as failed:
        if out is not None:
            write(failed.result, out, Path(path).stem)
            write_log(failed.report.messages, out / f"{Path(path).stem}.log")
        raise
    if out is not None:
        write(result, out, Path(path).stem)
        write_log(report.messages, out / f"{Path(path).stem}.log")
    return result, report
