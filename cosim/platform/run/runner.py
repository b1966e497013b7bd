"""Runs a scene: its system and plan (cosim.platform.run.compile) through the engine's one run path
(cosim.engine.run.run), reported with the tracking error, the designed gains and the notes on the
user's drives, and, with a folder, written with its plots and interactive report.

An FMU failure stops the run with a message naming the instance, the call and the time; the
results up to the last good communication point are written all the same (RunStopped carries
them and the report).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ...engine.outcome import Outcome, Report
from ...engine.run import Plan, run
from ...engine.settings import FixedStep, control_name
from ..core import gravity_of
from ..perception import (CHANNELS, TWIST, Perceived, perceive, platform_motion, quality, quality_lines,
                          second_opinion, vehicle_motion)
from ..ports import DRIVES, POSE, per_leg
from ..report.limits import result_excursion_lines
from ..report.plots import units
from ..scene import Scene, SceneError
from .alone import check_workspace
from .envelope import GUARD_KINDS, GUARD_OUTPUTS, held_line
from .compile import CompiledScene, compile_scene, run_label
from .errors import BUILD_ERRORS, scene_error

# the paper's figures that a scene's plots correspond to, per parameter set
FIGURES = {"meng2010": ("as Meng et al. 2010, Fig 7", "as Meng et al. 2010, Fig 8"),
           "sumnu2015": ("as Sumnu 2015, Section 5.3", "as Sumnu 2015, Section 5.3")}


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
    perceived: Perceived | None = None  # a cueing scene's: vehicle and platform as the occupant feels them
    channels: list = field(default_factory=list)  # its quality per channel, cues by kind (perception.quality)

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


def run_scene(scene: Scene, out: Path | None = None, plots: bool = False, progress: bool = False,
              advice: bool = False, twin: bool = False,
              adapt: Callable[[CompiledScene], tuple[Plan, str | None]] | None = None) -> tuple[np.ndarray, RunReport]:
    """Runs `scene`; returns the results (fmpy convention) and the report. Writes CSV, .mat, the
    log and (plots) the figures and the interactive report to `out` if given. Raises SceneError
    for a mistake found when the system is built or started, RunStopped (with the partial
    results, also written) when an FMU fails or the coupling diverges. progress: a bar on a
    terminal; advice: a diverged run probes for a step that holds (all three off unless asked:
    the command line asks); twin: the report judges the run against its converged twin, window by
    window. adapt: the compiled scene's plan made over (a run in real time:
    cosim.platform.realtime.real_time_plan), with what the run says of it before it starts (None:
    nothing). The scene is compiled once (compile_scene); the report and plots read that."""
    try:
        compiled = compile_scene(scene)
        plan, notes = compiled.plan, compiled.notes
        if adapt is not None:  # (a cueing scene's reference is held by the cueing FMU's own guard: compile.py)
            plan, remark = adapt(compiled)
            if remark:
                notes = [*notes, remark]
                if progress:  # the command line: before the run starts
                    print(f"note: {remark}", flush=True)
        if scene.vehicle is not None and not plan.model_exchange and not isinstance(plan.control, FixedStep):
            raise SceneError(f"{scene.document.where('coupling.step_control')}: a guarded reference takes fixed steps, "
                             "held within its envelope at each (a cueing scene's: the cueing FMU's guard); the step "
                             f"control '{control_name(plan.control)}' chooses its steps as it goes: set step_control = "
                             "fixed")
        guarded = plan.real_time is not None and plan.real_time.live is not None and plan.real_time.live.guarded
        if not guarded:  # (a guard holds it) before the run, not when the mechanics stops part way
            check_workspace(scene, compiled.mechanics)

        def report(outcome: Outcome, result: np.ndarray) -> RunReport:
            made = scene_report(compiled, result, outcome)
            made.remarks += notes
            if twin and outcome.failure is None and len(result) > 1:
                made.windows = twin_windows(scene, result)
            return made

        def figures(result: np.ndarray, made: RunReport, outcome: Outcome, folder: Path) -> None:
            if plots and len(result) > 1:
                made.html = write_figures(compiled, result, made, outcome, folder)
        return run(plan, out, scene.path.stem, progress=progress, advice=advice, report=report, files=figures)
    except BUILD_ERRORS as error:  # before a step: the scene's values, step or outputs
        mapped = scene_error(scene, error)
        if mapped is None:
            raise
        raise mapped from None


def scene_report(compiled: CompiledScene, result: np.ndarray, outcome: Outcome) -> RunReport:
    """The run's report, its tracking error taken over the (thinned) results after the first tenth."""
    scene = compiled.scene
    late = result["time"] >= 0.1 * scene.duration
    errors = np.array([np.abs(result[f"pose.{a}"] - result[f"pose_ref.{a}"])[late].max() if late.any() else np.nan
                       for a in POSE])
    report = RunReport.of(outcome, simulated=float(result["time"][-1]) if len(result) else 0.0, largest_error=errors,
                          tuning=compiled.tuning, diverged=outcome.diverged)
    report.name = run_label(scene)  # what was run, not only what the scene is called
    if len(result) > 1:
        report.remarks += result_excursion_lines(compiled.mechanics, result)
    if scene.fmi == 3 and scene.algorithm.order > 0:
        report.remarks.append("FMI 3.0: FMI 3.0 has no input derivatives; the master gives each input's rate and "
                              "curvature through the FMUs' own inputs fmi.rate.* and fmi.curvature.*, so the run "
                              "couples as on the FMI 2.0 FMUs, at the scene's step")
    if scene.vehicle is not None and len(result) and GUARD_OUTPUTS[0] in result.dtype.names:
        held = held_line({kind: int(result[name][-1]) for kind, name in zip(GUARD_KINDS, GUARD_OUTPUTS)})
        report.remarks += [held] if held else []  # (the cueing FMU's own guard: compile.guarded_cueing)
    if scene.vehicle is not None and len(result) > 1:
        report.remarks.append(tilt_line(scene, result))
        if len(result) > 3:
            report.perceived = perceived_motion(scene, compiled.mechanics, result)
            report.channels = quality(report.perceived)
            report.remarks += quality_lines(report.channels)
            report.remarks.append("perceived error by a second model (Reid and Nahon 1985's otoliths and canals, "
                                  f"the same thresholds): {second_opinion(report.perceived):.3f}")
    return report


def perceived_motion(scene: Scene, mechanics_values: dict, result: np.ndarray) -> Perceived:
    """A cueing scene's vehicle and platform motion at the occupant's head ([cueing] head) and
    what the occupant perceives of each (cosim.platform.perception), on the platform of these
    mechanics values."""
    gravity = gravity_of(mechanics_values)
    times = result["time"]
    keep = np.r_[True, np.diff(times) > 0]
    poses = np.column_stack([result[f"pose.{a}"] for a in POSE])[keep]
    twist = np.column_stack([result[n] for n in TWIST])[keep]
    taken = np.column_stack([result[f"vehicle.{c}"] for c in CHANNELS])[keep]
    vehicle = vehicle_motion(taken[:, :3], taken[:, 3:], float(np.linalg.norm(gravity)))
    return perceive(times[keep], vehicle, platform_motion(times[keep], poses, twist, np.array(scene.head), gravity))


def cueing_value(scene: Scene, name: str) -> float:
    """A cueing scene's value of a cueing FMU parameter: its [cueing.parameters] or the FMU's start."""
    from ...engine.artifacts import fmu_path
    from ...engine.checks import variables
    return float(scene.cueing_parameters.get(name, variables(fmu_path("cueing"))[name].start))


def tilt_rates(result: np.ndarray, pitch_measure: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A cueing run's tilt: times, the commanded tilt vector's rate (the cueing FMU's tilt.roll and
    tilt.pitch) and the realised one (the simulated platform's roll and pitch less the rest of the
    reference: pose - (pose_ref - tilt)), each |(roll', pitch_measure * pitch')| [rad/s] (pitch in
    roll's measure where pitch has a rate limit of its own), by differences in time."""
    t = result["time"]
    keep = np.r_[True, np.diff(t) > 0]
    t = t[keep]
    commanded = np.column_stack([result[f"tilt.{a}"][keep] for a in ("roll", "pitch")])
    realised = np.column_stack([(result[f"pose.{a}"] - result[f"pose_ref.{a}"] + result[f"tilt.{a}"])[keep]
                                for a in ("roll", "pitch")])
    measure = np.array([1.0, pitch_measure])
    rate = [np.hypot(*(np.gradient(angles, t, axis=0) * measure).T) for angles in (commanded, realised)]
    return t, rate[0], rate[1]


def tilt_line(scene: Scene, result: np.ndarray) -> str:
    """What the tilt coordination of a scene's motion cueing did: its largest roll and pitch, and
    the tilt vector's peak rate (pitch in roll's measure where tilt.pitch_rate_limit gives it a limit
    of its own), commanded and as the simulated platform realised it, against the limit (below which
    the semicircular canals do not notice it), with the time the platform turned faster."""
    limit, pitch_limit = cueing_value(scene, "tilt.rate_limit"), cueing_value(scene, "tilt.pitch_rate_limit")
    largest = [np.abs(result[f"tilt.{a}"]).max() for a in ("roll", "pitch")]
    t, commanded, realised = tilt_rates(result, limit / pitch_limit if pitch_limit > 0.0 else 1.0)
    over = float(np.sum(np.diff(t)[realised[1:] > limit * 1.05])) if len(t) > 1 else 0.0
    own = (f"; pitch's {np.degrees(pitch_limit):.2f} deg/s, its rate counted at {limit / pitch_limit:.3g} of itself"
           if pitch_limit > 0.0 else "")
    return (f"motion cueing: tilt up to {np.degrees(largest[0]):.2f} deg in roll and {np.degrees(largest[1]):.2f} deg "
            f"in pitch, the tilt vector turning at most {np.degrees(commanded.max()):.2f} deg/s as commanded and "
            f"{np.degrees(realised.max()):.2f} deg/s as the platform realised it (its limit "
            f"{np.degrees(limit):.2f} deg/s{own}" + (f"; the platform beyond it by more than 5 % for {over:.2f} s)" if over
                                                      else ")"))


def write_figures(compiled: CompiledScene, result: np.ndarray, report: RunReport, outcome: Outcome,
                  folder: Path) -> Path:
    """The tracking and drive plots (like the paper's figures) and the interactive report, which
    this returns."""
    scene = compiled.scene
    from ..report.html import write_report
    from ..report.plots import plot_drives, plot_perception, plot_tracking
    effort, speed = DRIVES[scene.drive].outputs[:2]
    if scene.interface_jacobian:  # the legs feel the drives' efforts corrected by their slopes: plot what they feel
        effort = f"{effort}_applied"
    tracking, drives = FIGURES.get(scene.parameter_set, ("", ""))
    impacts = sorted({(p.start, p.end) for p in scene.pulses})
    label = run_label(scene)
    plot_tracking(result, folder / f"{scene.path.stem}_tracking.png", label, tracking, impacts)
    if report.perceived is not None:
        plot_perception(report.perceived, folder / f"{scene.path.stem}_perception.png",
                        f"{label}: vehicle and platform as the occupant perceives them")
    if {f"{effort}[1]", f"{speed}[1]"} <= set(result.dtype.names):
        plot_drives(result, folder / f"{scene.path.stem}_drives.png", label, effort, speed, units(scene.drive),
                    drives, impacts)
    return write_report(folder / f"{scene.path.stem}.html", scene, result, report, outcome.messages,
                        outcome.bond_residuals, compiled.mechanics)


def twin_windows(scene: Scene, result: np.ndarray) -> list[tuple[str, float, float, float]]:
    """The run against its converged twin (converged_twin: the same scene at a 16th of its step
    throughout, no finer start, no edge windows): per window (cosim.platform.run.accuracy) the pose's largest
    difference [m, rad] and the drive efforts' (as the legs feel them), absolute and against their
    own change there."""
    from .accuracy import converged_twin, efforts, window_errors, windows
    twin = converged_twin(scene)
    reference, _ = run_scene(twin)
    effort = DRIVES[scene.drive].effort[0]
    spans = windows(float(min(result["time"][-1], reference["time"][-1])), scene.pulses)
    poses = {e.window: e.error for e in window_errors(result, reference, [f"pose.{a}" for a in POSE], spans)}
    return [(e.window, poses.get(e.window, float("nan")), e.error, e.relative)
            for e in window_errors(efforts(result, effort), efforts(reference, effort), per_leg(effort), spans)]
