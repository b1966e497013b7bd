"""One FMU as a system (`cosim run FILE.fmu`, `cosim.simulate("x.fmu")`): a Co-Simulation FMU (FMI
2.0 or 3.0) run alone by the same engine as any SSP system, its parameters and inputs at their start
values, every Real output recorded under its own name; its DefaultExperiment gives the start, the stop
and the step (a run's settings, `--set step=...`, and `--duration` over them). A Model Exchange FMU
(FMI 2.0; such as `cosim export SCENE --fmu FILE --me`) is integrated by CVODE instead
(cosim.engine.monolithic), its outputs on the same grid. What cannot be run (no such file, not an
FMU, neither interface, no output) is one line, an SspError naming the file."""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

from .errors import SspError
from .settings import output_settings
from .structure import Component, Experiment, SystemStructure

DEFAULT_STEPS = 1000  # macro steps over the experiment where the FMU gives no step size


def fmu_system(path: str | Path) -> SystemStructure:
    """The system of one Co-Simulation FMU: a component named as its model identifier."""
    from .fmi import loaded
    path = Path(path)
    if not path.is_file():
        raise SspError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise SspError(f"{path}: not an FMU (an FMU is a zip archive with a modelDescription.xml)")
    try:
        description = loaded(path)[0]
    except Exception as error:  # fmpy's reasons: no modelDescription.xml, invalid XML, ...
        raise SspError(f"{path}: not an FMU that can be read: {str(error).splitlines()[0] if str(error) else error!r}") \
            from None
    if description.coSimulation is None and description.modelExchange is None:
        raise SspError(f"{path}: the FMU declares neither Co-Simulation nor Model Exchange")
    outputs = [v.name for v in description.modelVariables if v.causality == "output" and v.type == "Real"]
    if not outputs:
        raise SspError(f"{path}: the FMU has no Real output to record")
    unrecordable = [n for n in outputs if any(c.isspace() or c == "=" for c in n)]
    if unrecordable:
        raise SspError(f"{path}: output '{unrecordable[0]}' has a name this run cannot record (white space or '=')")
    name = (description.coSimulation or description.modelExchange).modelIdentifier
    experiment = description.defaultExperiment
    start = _number(experiment.startTime if experiment else None, 0.0)
    stop = _number(experiment.stopTime if experiment else None, start + 1.0)
    if not stop > start:
        raise SspError(f"{path}: its DefaultExperiment stops at {stop:g} s, not after its start {start:g} s")
    given = _number(experiment.stepSize if experiment else None, math.nan)
    step = given if given > 0 else (stop - start) / DEFAULT_STEPS
    source = "the FMU's DefaultExperiment" if given > 0 else f"a {DEFAULT_STEPS}th of the FMU's DefaultExperiment"
    structure = SystemStructure(name, [Component(name, path)], [], experiment=Experiment(start, stop, step, source))
    # alone, it has no inputs to couple: its steps taken as they come (order 0: no start-up iteration,
    # which needs fmi2GetFMUstate, as a system FMU does not offer)
    structure.settings = {**output_settings([(name, n) for n in outputs], outputs), "order": "0"}
    return structure


def _number(text, default: float) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return default
    return value if math.isfinite(value) else default
