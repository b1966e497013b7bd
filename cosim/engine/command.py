"""`python -m cosim run FILE.ssp|FILE.ssd`: any SSP system run with the engine's algorithms.

The coupling and step control come from the SSP's annotation (cosim.engine.ssp) unless the command
line overrides them (`--set name=value`, names as in cosim.engine.settings); the recorded columns
from the annotation's `record` setting, else every connected output as `component.variable`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from .observers import DivergenceMonitor, Progress
from .outcome import Report, RunStopped, execute
from .results import thin, write, write_log
from .settings import output_interval, recorded, system_settings
from .structure import SystemStructure


def recording(structure: SystemStructure) -> tuple[list[tuple[str, str]], list[str]]:
    """What a run of `structure` records: its `record` setting, else every connected output."""
    chosen = recorded(structure.settings)
    if chosen is not None:
        return chosen
    outputs = list(dict.fromkeys(c.source for c in structure.connections))
    return outputs, [f"{c}.{v}" for c, v in outputs]


def run_structure(structure: SystemStructure, overrides: Mapping[str, str] | None = None,
                  stop_time: float | None = None, progress: bool = True,
                  advice: bool = True) -> tuple[np.ndarray, Report]:
    """Runs `structure` with its settings (and the overrides) through the one run path; raises
    RunStopped (its report and partial results) when the run stopped early. progress: a progress
    bar on a terminal; advice: a diverged run probes for a step that holds (both off for a sweep's
    points)."""
    algorithm, control = system_settings(structure.settings, structure.experiment.step, overrides)
    record, names = recording(structure)
    stop = structure.experiment.stop if stop_time is None else stop_time
    outcome = execute(structure, algorithm, control, stop, record, names,
                      observers=[DivergenceMonitor(), *([Progress(structure.name)] if progress else [])], advice=advice)
    result = thin(outcome.result, output_interval(structure.settings))
    report = Report.of(outcome)
    if structure.experiment.step_source not in ("", "this project's annotation") and not (overrides or {}).get("step"):
        report.remarks.append(f"macro step {structure.experiment.step:g} s: {structure.experiment.step_source}")
    if outcome.failure is not None:
        raise RunStopped(report, result, outcome.diverged)
    return result, report


def run_ssp(path: Path, out: Path | None, overrides: Mapping[str, str] | None = None,
            stop_time: float | None = None) -> tuple[np.ndarray, Report]:
    """Reads and runs an SSP system; writes <stem>.csv and .mat to `out` (also when it fails)."""
    from .checks import ParameterError
    from .execution import NoStep
    from .fmi import FmuError
    from .settings import SettingsError
    from .ssp import SspError, read_ssp
    structure = read_ssp(path)
    try:
        result, report = run_structure(structure, overrides, stop_time)
    except (ParameterError, NoStep, SettingsError) as error:  # the SSP's values, settings or times, before a step
        raise SspError(f"{path}: {error}") from None
    except FmuError as error:  # an FMU that rejects the SSP's values when it is set up
        raise SspError(f"{path}: {error}") from None
    except RunStopped as failed:
        if out is not None:
            write(failed.result, out, Path(path).stem)
            write_log(failed.report.messages, out / f"{Path(path).stem}.log")
        raise
    if out is not None:
        write(result, out, Path(path).stem)
        write_log(report.messages, out / f"{Path(path).stem}.log")
    return result, report
