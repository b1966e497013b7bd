"""Runs a scene: compiles it into the platform's system structure and settings, runs that on the
engine, reports, and writes the results.

An FMU failure stops the run with a message naming the instance, the call and the time; the
results up to the last good communication point are written all the same.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...engine import Experiment, FmuError, NoStep, ParameterError, Progress, RunFailed, SystemStructure
from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.outcome import Outcome, Report, RunStopped
from ...engine.results import thin, write as write_results, write_log
from ...engine.settings import output_settings, to_strings
from ..scene.parameter_sets import drive_set, scene_mechanics
from ..ports import DRIVES, LEGS, POSE, per_leg
from ...engine.schema import line_of
from ..scene import Scene, SceneError
from ..scene.signals import scene_trajectory
from ..core import LayoutImpossible, SingularPose
from ..report.plots import units
from .system import columns, platform_structure, run
from .tuning import SizingError, check_limit, check_sizing, design, hold_currents, leg_plants, summary


@dataclass
class RunReport(Report):
    """A scene's run report: the engine's, with the tracking error, the designed gains, where the
    interactive report was written and whether the coupling diverged."""
    largest_error: np.ndarray = field(default_factory=lambda: np.zeros(0))  # per DOF, after the first tenth
    tuning: str | None = None  # the gains designed for the plant (tuning = "auto")
    html: Path | None = None  # the interactive report, when plots were drawn
    diverged: bool = False  # the failure is the divergence monitor's verdict
    # against the run's converged twin (run_scene(twin=True)): per window (start-up, each load pulse
    # with the 0.2 s after it, steady tracking) the pose's and the efforts' largest difference
    windows: list = field(default_factory=list)  # (window, pose error, effort error, effort error / own change)

    @property
    def scene(self) -> str:
        return self.name

    def measured(self) -> list[str]:
        if not len(self.largest_error):
            return []
        lines = ["largest tracking error after the first tenth: " + ", ".join(
            f"{a} {e:.2e}" for a, e in zip(POSE, self.largest_error))]
        if self.windows:
            lines.append("against the converged twin (the scene at a 16th of its step throughout), per window: " +
                         "; ".join(f"{name}: pose {pose:.1e}, efforts {effort:.1e} ({100 * relative:.2f} % of their "
                                   "change)" for name, pose, effort, relative in self.windows))
        return lines

    def notes(self) -> list[str]:
        return [*self.remarks, *([self.tuning] if self.tuning else [])]


class SceneFailed(RunStopped):
    """A scene's run that stopped early: its report and the results up to then."""

    def __init__(self, report: RunReport, result: np.ndarray):
        super().__init__(report, result, report.diverged)


# the paper's figures that a scene's plots correspond to, per parameter set
FIGURES = {"meng2010": ("as Meng et al. 2010, Fig 7", "as Meng et al. 2010, Fig 8"),
           "sumnu2015": ("as Sumnu 2015, Section 5.3", "as Sumnu 2015, Section 5.3")}


def drive_fmus(scene: Scene) -> list[Path]:
    """Per leg, the drive FMU: the user's where the scene names one, ours for its kind otherwise."""
    return [scene.leg_fmu(leg) or fmu_path(DRIVES[scene.drive].fmu) for leg in LEGS]


def scene_record(scene: Scene) -> tuple[list[tuple[str, str]], list[str]]:
    """What the scene records: its [outputs], or by default the drive kind's effort, flow and
    current (the current where every leg's drive FMU has it)."""
    if scene.outputs_drive is not None:
        drive_outputs = scene.outputs_drive
    else:
        has = [variables(fmu) for fmu in set(drive_fmus(scene))]
        drive_outputs = [n for n in DRIVES[scene.drive].outputs if all(n in found for found in has)]
    return columns(scene.drive, scene.outputs_mechanics, drive_outputs, applied=scene.interface_jacobian)


def scene_values(scene: Scene) -> tuple[dict, dict]:
    """The mechanics' and our drives' parameter values: the platform's set, the drive set (a
    drive sized for this platform), then the scene's own, which win."""
    drive_values = drive_set(scene.drive_set)[0] if scene.drive_set else {}
    mechanics_values = scene_mechanics(scene.parameter_set, scene.mass_set, scene.drive_set, scene.mechanics_parameters)
    return mechanics_values, {**drive_values, **(scene.drive_parameters if scene.drive_fmu is None else {})}


def scene_design(scene: Scene) -> tuple[list[dict], str | None, list[str]]:
    """Per leg, the drive parameters, with a summary of the designed gains and notes on the
    drives of the user's own. Our drives: designed for the platform (tuning = "auto"), or the
    defaults with the PMSM starting to hold its leg (initial.current_q from the static load,
    unless the scene gives it). A drive FMU of the user's own keeps its own parameters (the
    scene's [drive.parameters] where it is the [drive] FMU, and its leg's). Raises SceneError when
    a drive cannot hold its leg (sizing: ours always, a user's by its continuous_limit)."""
    mechanics_values, ours = scene_values(scene)
    plants = leg_plants(mechanics_values)
    legs = [{**({} if leg in scene.leg_fmus else scene.drive_parameters if scene.drive_fmu else ours),
             **scene.leg_parameters.get(leg, {})} for leg in LEGS]
    own = [k for k, leg in enumerate(LEGS) if scene.leg_fmu(leg) is None]
    try:
        for k in own:
            check_sizing(scene.drive, [plants[k]], legs[k], leg=k + 1)
    except SizingError as error:
        raise SceneError(f"{scene.path}:{scene.document.line('drive.kind')}: drive.kind = "
                         f"{scene.drive!r} on {scene.parameter_set}: {error}") from None
    notes, unchecked = user_drive_notes(scene), []
    for k, leg in enumerate(LEGS):
        fmu = scene.leg_fmu(leg)
        if fmu is None:
            continue
        if leg not in scene.continuous_limit:
            unchecked.append(leg)
            continue
        name = scene.continuous_limit[leg]
        limit = float(legs[k].get(name, variables(fmu)[name].start))
        try:
            check_limit(scene.drive, plants[k], limit, f"{fmu.name}'s {name}", leg)
        except SizingError as error:
            table = f"drive.leg.{leg}" if scene.document.value(f"drive.leg.{leg}", "continuous_limit") else "drive"
            raise SceneError(f"{scene.path}:{scene.document.line(f'{table}.continuous_limit')}: {error}") from None
    if unchecked:
        notes.append(f"sizing not checked for legs {', '.join(map(str, unchecked))}: name the parameter that holds "
                     "the drive's continuous torque or force with drive.continuous_limit")
    if scene.tuning != "auto" or not own:
        if scene.drive == "pmsm":
            for k in own:
                if "initial.current_q" not in legs[k]:
                    legs[k]["initial.current_q"] = hold_currents([plants[k]], legs[k])[0]
        return legs, None, notes
    designed = [design(scene.drive, [plants[k]], legs[k])[0] for k in own]
    for k, values in zip(own, designed):
        legs[k] = values
    return legs, summary(scene.drive, designed), notes


def user_drive_notes(scene: Scene) -> list[str]:
    """For the run report: each drive FMU of the user's own, its tool, legs, what fmpy's
    validation says of it and what the master does not do with it."""
    from ..scene.drive_fmu import inspect
    notes = []
    for fmu in dict.fromkeys(f for f in (scene.leg_fmu(leg) for leg in LEGS) if f is not None):
        drive = inspect(fmu)
        legs = [leg for leg in LEGS if scene.leg_fmu(leg) == fmu]
        limits = drive.limits(scene.interface_jacobian)
        notes.append(f"drive FMU {drive.name} ({drive.model}, {drive.tool}) on legs {', '.join(map(str, legs))}"
                     + (f"; switched off: {'; '.join(limits)}" if limits else ""))
        notes += [f"{drive.name}: fmpy's validation: {problem}" for problem in drive.problems]
    return notes


def scene_structure(scene: Scene, designed: list[dict] | None = None) -> SystemStructure:
    """The scene as a system: FMUs, parameter values, connections, power bonds, experiment, and
    the settings (algorithm, step control, recorded outputs) as the SSP annotation carries them.
    designed: the drives' parameters per leg if scene_design was already called."""
    mechanics_values, _ = scene_values(scene)
    if designed is None:
        designed = scene_design(scene)[0]
    structure = platform_structure(scene.drive, mechanics_values, {}, scene_trajectory(scene), leg_values=designed,
                                   name=scene.path.stem, experiment=Experiment(0.0, scene.duration, scene.step),
                                   interface_jacobian=scene.interface_jacobian, drive_fmus=drive_fmus(scene))
    algorithm, control = scene.algorithm, scene.control
    structure.settings = {**to_strings(algorithm, control), **output_settings(*scene_record(scene),
                                                                               scene.output_interval)}
    return structure


def scene_key(component: str, variable: str) -> tuple[str, str]:
    """The scene table and key that a component's parameter comes from."""
    if component == "mechanics":
        return "mechanics.parameters", variable
    if component == "trajectory":
        if variable.startswith("load."):
            return "load", "pulses"
        if variable.startswith("table."):
            return "trajectory", "table"
        dof, rest = variable.split(".", 1)
        return f"trajectory.{dof}", {"sine": "sines", "step": "steps", "ramp": "ramps"}.get(rest.split("[")[0], rest)
    return "drive.parameters", variable


def located(scene: Scene, component: str, variable: str) -> str:
    """'file:line: table.key' for a component's parameter (file:0 when the scene does not set it,
    the value then comes from the parameter set or the FMU's default)."""
    table, key = scene_key(component, variable)
    line = line_of(scene.text, table, key)
    if table.endswith(".parameters"):
        shown = f'{table}."{key}"'
    elif table == "load":
        shown = f"load.pulses ({variable})"
    else:  # x.sine[1].amplitude -> trajectory.x.sines[1].amplitude
        rest = variable.split(".", 1)[1]
        item = re.match(r"(sine|step|ramp)\[(\d+)\]\.(\w+)$", rest)
        shown = f"{table}.{item.group(1)}s[{item.group(2)}].{item.group(3)}" if item else f"{table}.{rest}"
    return f"{scene.path}:{line}: {shown}" + ("" if line else f" (from parameter set {scene.parameter_set})")


def scene_error(scene: Scene, error: Exception) -> SceneError | None:
    """A one-line SceneError with the scene's file and line for a user error found when the
    system is built or started, or None for anything else (a bug)."""
    if isinstance(error, ParameterError):
        return SceneError(f"{located(scene, error.component, error.variable)} = {error.value!r}: {error.reason} "
                          f"({error.fmu})")
    if isinstance(error, FmuError) and error.call.startswith(("fmi2Instantiate", "fmi2Set", "fmi2Enter", "fmi2Exit",
                                                             "fmi2Setup")):
        detail = "; ".join(m.text for m in error.messages) or "the FMU logged no reason"
        named = re.search(r"'([^']+)'", detail)  # the variable the FMU names, if it is one of its variables
        fmu = {"trajectory": fmu_path("trajectory"), "mechanics": fmu_path("mechanics")}.get(
            error.instance) or drive_fmus(scene)[int(error.instance[-1]) - 1]
        known = named is not None and named.group(1) in variables(fmu)
        where = located(scene, error.instance, named.group(1)) if known else f"{scene.path}"
        return SceneError(f"{where}: rejected by {error.instance}: {detail}")
    if isinstance(error, NoStep):
        return SceneError(f"{scene.path}:{scene.document.line('scene.step')}: scene.step = "
                          f"{scene.step:g} s, duration {scene.duration:g} s: {error}")
    if isinstance(error, (LayoutImpossible, SingularPose)):  # the platform the scene asks for, at its start pose
        return SceneError(f"{scene.path}:{scene.document.line('mechanics.parameters')}: the platform "
                          f"of [mechanics] at its start pose: {error}")
    if isinstance(error, KeyError) and "no variable" in str(error):  # a recorded output the FMU lacks
        names = set(scene.outputs_mechanics)
        key = "mechanics" if any(f"'{n}'" in str(error) for n in names) else "drive"
        return SceneError(f"{scene.path}:{scene.document.line(f'outputs.{key}')}: 'outputs.{key}': "
                          f"{error.args[0]}")
    return None


def twin_windows(scene: Scene, result: np.ndarray) -> list[tuple[str, float, float, float]]:
    """The run against its converged twin, the same scene at a 16th of its step throughout (no
    finer start, no edge windows): per window (cosim.platform.run.accuracy) the pose's largest
    difference [m, rad] and the drive efforts' (as the legs feel them), absolute and against their
    own change there."""
    from .accuracy import window_errors, windows
    from .accuracy import efforts
    twin = scene.changed({"scene.step": scene.step / 16, "coupling.startup_time": 0.0, "coupling.edge_time": 0.0,
                          "coupling.step_control": "fixed"})
    reference, _ = run_scene(twin, progress=False, advice=False)
    effort = DRIVES[scene.drive].effort[0]
    spans = windows(float(min(result["time"][-1], reference["time"][-1])), scene.pulses)
    poses = {e.window: e.error for e in window_errors(result, reference, [f"pose.{a}" for a in POSE], spans)}
    return [(e.window, poses.get(e.window, float("nan")), e.error, e.relative)
            for e in window_errors(efforts(result, effort), efforts(reference, effort), per_leg(effort), spans)]


def run_scene(scene: Scene, out: Path | None = None, plots: bool = True, progress: bool = True,
              advice: bool = True, twin: bool = False) -> tuple[np.ndarray, RunReport]:
    """Runs `scene`; returns the results (fmpy convention) and the report. Writes CSV, .mat and
    plots to `out` if given. Raises SceneFailed (with the partial results, also written) when an
    FMU fails or the coupling diverges. progress: a bar on a terminal; advice: a diverged run
    probes for a step that holds (both off for a sweep's points); twin: the report judges the run
    against its converged twin, window by window (twin_windows)."""
    algorithm, control = scene.algorithm, scene.control
    record = scene_record(scene)
    try:
        designed, tuning, drive_notes = scene_design(scene)
        structure = scene_structure(scene, designed)
        outcome = run(structure, algorithm, control, scene.duration, record,
                      observers=[Progress(scene.name)] if progress else [], advice=advice)
    except RunFailed as failed:  # the partial run comes with it
        outcome = failed.outcome
    except (ParameterError, FmuError, NoStep, KeyError, LayoutImpossible, SingularPose) as error:  # before a step
        mapped = scene_error(scene, error)
        if mapped is None:
            raise
        raise mapped from None
    result = thin(outcome.result, scene.output_interval)
    report = scene_report(scene, result, outcome, tuning)
    report.remarks += drive_notes
    if twin and outcome.failure is None and len(result) > 1:
        report.windows = twin_windows(scene, result)
    if out is not None:
        write_results(result, out, scene.path.stem)
        report.log = out / f"{scene.path.stem}.log"
        write_log(outcome.messages, report.log)
        effort, speed = DRIVES[scene.drive].outputs[:2]
        if scene.interface_jacobian:  # the legs feel the drives' efforts corrected by their slopes: plot what they feel
            effort = f"{effort}_applied"
        if plots and len(result) > 1:
            from ..report.plots import plot_drives, plot_tracking
            tracking, drives = FIGURES.get(scene.parameter_set, ("", ""))
            impacts = sorted({(p.start, p.end) for p in scene.pulses})
            plot_tracking(result, out / f"{scene.path.stem}_tracking.png", scene.name, tracking, impacts)
            if {f"{effort}[1]", f"{speed}[1]"} <= set(result.dtype.names):
                plot_drives(result, out / f"{scene.path.stem}_drives.png", scene.name, effort, speed,
                                    units(scene.drive), drives, impacts)
            from ..report.html import write_report
            report.html = write_report(out / f"{scene.path.stem}.html", scene, result, report, outcome.messages,
                                       outcome.bond_residuals, scene_values(scene)[0])
    if outcome.failure is not None:
        raise SceneFailed(report, result)
    return result, report


def scene_report(scene: Scene, result: np.ndarray, outcome: Outcome, tuning: str | None = None) -> RunReport:
    """The run's report, its tracking error taken over the (thinned) results after the first tenth."""
    late = result["time"] >= 0.1 * scene.duration
    errors = np.array([np.abs(result[f"pose.{a}"] - result[f"pose_ref.{a}"])[late].max() if late.any() else np.nan
                       for a in POSE])
    report = RunReport.of(outcome, simulated=float(result["time"][-1]) if len(result) else 0.0, largest_error=errors,
                          tuning=tuning, diverged=outcome.diverged)
    report.name = scene.name
    return report
