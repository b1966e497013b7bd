"""What other FMI tools do with an exported system: each tool's co-simulation master and our
engine's emulation of it, an Algorithm taken at a fixed step with no finer start; and the step
each tool gets, measured with these emulations (largest_steps: the scene's step halved until the
tool's master holds the tolerances). The platform's export measures with its own judge (the pose,
the drive efforts per window: cosim.platform.run.portable); any SSP system (`cosim export-check`)
with check_system's: every recorded output within FIT_TOLERANCE of its own range.
The tools stage of the test command (tests/platform/test_export_tools.py) holds the emulations to
the tools themselves on every shipped scene: Ecos and fmpy.ssp bit for bit, libcosim and
OMSimulator (b3cd458, from ../shared/peers) to round-off at the steps the export wrote."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Protocol, Sequence

import numpy as np

from .settings import Algorithm, FixedStep
from .structure import SystemStructure


@dataclass(frozen=True)
class ToolMaster:
    tool: str
    master: str            # what its master does, in words
    algorithm: Algorithm   # our engine's emulation of it
    where: str             # where the export writes the step it measured for the tool
    loads_fmi3: bool       # runs a system of FMI 3.0 FMUs (False: no step is measured for it there)
    fmi3: str              # what is known of it and FMI 3.0 FMUs, in words


TOOL_MASTERS = (
    ToolMaster("OMSimulator", "oms-ma: fixed step, Jacobi, inputs held, outputs that feed through read again",
               Algorithm("jacobi", 0, feedthrough=True), "the system's oms:FixedStepMaster stepSize",
               True, "runs them (OMSimulator b3cd458: every shipped scene's FMI 3.0 export within its tolerances "
               "at the step written, in the test command's tools stage)"),
    ToolMaster("libcosim", "fixed-step algorithm: Jacobi, inputs held",
               Algorithm("jacobi", 0, initial_sweeps=0), "the OSP annotation's baseStepSize (and an OSP "
               "configuration's BaseStepSize)",
               False, "does not load them (libcosimpy 0.0.6 refuses such an archive)"),
    ToolMaster("Ecos", "fixed step: Jacobi, inputs held", Algorithm("jacobi", 0, initial_sweeps=0),
               "our annotation's cosim:ToolStep (Ecos runs at the step it is given)",
               True, "runs them (ecospy 0.7.2, tests/platform/test_export_tools.py)"),
    ToolMaster("fmpy.ssp", "fixed step: Jacobi, inputs held, every connection 0 over the first step",
               Algorithm("jacobi", 0, initial_sweeps=0, zero_start=True),
               "our annotation's cosim:ToolStep (fmpy.ssp runs at the step it is given)",
               False, "does not load them (fmpy 0.3.32's simulate_ssp instantiates every FMU as FMI 1.0 or 2.0)"),
)


def fmi3_lines() -> list[str]:
    """What the export says of each tool and a system of FMI 3.0 FMUs."""
    return [f"note: FMI 3.0 FMUs: {m.tool} {m.fmi3}" + ("" if m.loads_fmi3 else "; no step measured for it")
            for m in TOOL_MASTERS]

FLOOR = 64  # the finest step tried: the system's step / FLOOR
CONVERGED = 16  # the converged run: the system's own coupling at its step / CONVERGED
PROBE = 2.0  # [s] how long check_system runs a system (at most its experiment)
FIT_TOLERANCE = 0.02  # a recorded output's largest error, of its own range over the probe


class Judged(Protocol):
    """How a run at a step does: within the tolerances, and how far off (at most 1: within)."""
    @property
    def within(self) -> bool: ...

    @property
    def ratio(self) -> float: ...


@dataclass(frozen=True)
class ToolStep:
    """The step measured for one tool, and how its master does there (judged by the platform's
    judge for a scene, by fit for any system)."""
    master: ToolMaster
    step: float
    judgement: Judged
    wall: float  # [s] our engine's stepping of the probe at that step

    @property
    def within(self) -> bool:
        return self.judgement.within

    @property
    def ratio(self) -> float:
        return self.judgement.ratio


def largest_steps(step: float, attempt: Callable[[ToolMaster, float], ToolStep], fmi3: bool = False) -> list[ToolStep]:
    """Per tool of TOOL_MASTERS (for a system of FMI 3.0 FMUs, `fmi3`, those that load them), the
    largest of `step` / 2^k (down to FLOOR) at which `attempt` (the tool's master run at that step,
    judged) holds, or the trial that came closest (the least ratio, then the largest step). Tools
    with the same master are run once."""
    found: dict[Algorithm, ToolStep] = {}
    out = []
    for master in (m for m in TOOL_MASTERS if m.loads_fmi3 or not fmi3):
        if master.algorithm not in found:
            tried = []
            divisor = 1
            while divisor <= FLOOR:
                tried.append(attempt(master, step / divisor))
                if tried[-1].within:
                    break
                divisor *= 2
            found[master.algorithm] = tried[-1] if tried[-1].within else min(tried, key=lambda t: (t.ratio, -t.step))
        out.append(replace(found[master.algorithm], master=master))
    return out


@dataclass(frozen=True)
class Fit:
    """A run of any system against its converged run: per recorded output the largest difference
    (at the run's times, the converged run interpolated) over FIT_TOLERANCE of the output's own range
    there; the worst output's ratio and name (at most 1: within)."""
    ratio: float
    worst: str

    @property
    def within(self) -> bool:
        return self.ratio <= 1.0


def fit(result: np.ndarray, reference: np.ndarray, names: Sequence[str]) -> Fit:
    if not len(result) or result["time"][-1] < reference["time"][-1] - 1e-9:
        return Fit(float("inf"), "the run stopped early")
    ratios = []
    for name in names:
        expected = np.interp(result["time"], reference["time"], reference[name])
        scale = float(np.ptp(reference[name])) or max(float(np.abs(reference[name]).max()), 1e-12)
        ratios.append((float(np.abs(result[name] - expected).max()) / (FIT_TOLERANCE * scale), name))
    return Fit(*max(ratios, default=(0.0, "")))


def system_row(measured: ToolStep) -> str:
    """A row of export-check's table: the tool, its master, the step written, the verdict, the worst
    output's error against its tolerance, our wall time at that step."""
    verdict = "within the tolerance" if measured.within else (
        f"none within the tolerance down to 1/{FLOOR} of the system's step: the closest")
    return (f"| {measured.master.tool} | {measured.master.master} | {measured.step * 1e3:.4g} ms | {verdict} | "
            f"{measured.ratio:.2f} ({measured.judgement.worst}) | {measured.wall:.2f} s |")


SYSTEM_HEADER = ["| tool | its master | step written | | worst output's error / tolerance | our wall at that step |",
                 "|---|---|---|---|---|---|"]


def check_system(structure: SystemStructure) -> tuple[float, list[ToolStep]]:
    """Any system's step per tool: each tool's master run in our engine over the first PROBE
    seconds (at most the experiment), against the system's own coupling at a CONVERGED-th of its
    step, judged by fit over what the system records (its `record` setting, else every connected
    output); for a system with FMI 3.0 FMUs, the tools that load them. Returns the probe's duration
    and the steps."""
    from .fmi import loaded
    from .outcome import RunStopped
    from .run import Plan, recording, run
    from .settings import system_settings
    record, names = recording(structure)
    duration = min(PROBE, structure.experiment.stop - structure.experiment.start)
    step = structure.experiment.step
    algorithm, _ = system_settings(structure.settings, step)
    clock = structure.components[0].name
    converged, _ = run(Plan(structure, algorithm, FixedStep(step / CONVERGED), duration, record, names, clock=clock,
                            divergence=None))  # a run that stops raises: nothing to measure against

    def attempt(master: ToolMaster, at: float) -> ToolStep:
        try:
            result, report = run(Plan(structure, master.algorithm, FixedStep(at), duration, record, names, clock=clock,
                                      divergence=None))
        except RunStopped as stopped:
            result, report = stopped.result, stopped.report
        return ToolStep(master, at, fit(result, converged, names), report.wall)

    fmi3 = any(str(loaded(c.fmu)[0].fmiVersion).startswith("3") for c in structure.components)
    return duration, largest_steps(step, attempt, fmi3)


# about what OMSimulator's CSV result file takes per value it writes (its numbers print 12 significant
# digits, a separator between them): what an export says of the file's size
OMSIMULATOR_BYTES_PER_VALUE = 15.0


def omsimulator_script(archive: Path, record: Sequence[tuple[str, str]], interval: float, stop: float) -> Path:
    """Beside an SSP archive, the Lua script that runs it in OMSimulator recording only `record`
    (component, variable) every `interval` seconds of simulated time until `stop` into
    <archive>_omsimulator.csv (OMSimulator records every signal at every communication point
    otherwise, and reads no result filter from an SSP): `OMSimulator <archive>.lua` in the archive's
    folder. Returns its path."""
    import re
    from .files import write_text
    archive = Path(archive)
    pattern = "|".join(re.escape(f"{c}.{v}") for c, v in record)  # (component.variable, under the model's systems)
    lua = "\n".join([
        f"-- {archive.name} in OMSimulator, recording only the {len(record)} outputs the run reports, every "
        f"{interval:g} s: OMSimulator {archive.stem}.lua",
        f'model, status = oms_importFile("{archive.name}")',
        f'oms_setResultFile(model, "{archive.stem}_omsimulator.csv", 1000)',
        'oms_removeSignalsFromResults(model, ".*")',
        f'oms_addSignalsToResults(model, "^[^.]+\\\\.[^.]+\\\\.([^.]+\\\\.)?({_lua(pattern)})$")',
        f"oms_setLoggingInterval(model, {interval!r})",
        f"oms_setStopTime(model, {stop!r})",
        "oms_instantiate(model)", "oms_initialize(model)", "oms_simulate(model)", "oms_terminate(model)",
        "oms_delete(model)", ""])
    return write_text(archive.with_suffix(".lua"), lua, "the OMSimulator script")


def omsimulator_bytes_per_second(record: Sequence[tuple[str, str]], interval: float) -> float:
    """About how large the script's result file grows per simulated second [bytes]: b3cd458
    writes each logged point twice (before and after the step that reaches it)."""
    return 2 * (len(record) + 1) * OMSIMULATOR_BYTES_PER_VALUE / interval


def _lua(text: str) -> str:
    """A string for a Lua double-quoted literal."""
    return text.replace("\\", "\\\\").replace('"', '\\"')
