"""Runs a scene: builds the platform system it describes, steps it, reports, and writes results.

An FMU failure stops the run with a message naming the instance, the call and the time; the
results up to the last good communication point are written all the same.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import results
from .parameter_sets import mechanics_start_values
from .scene import Scene, SceneError, line_of
from .coupling import AdaptiveStep, EnergyStep
from .signals import scene_trajectory
from .system import PlatformSystem, RunFailed, StepControl

DRIVE_OUTPUTS = {"pmsm": ("torque", "speed", "current.q"), "linear": ("force", "velocity", "current")}


@dataclass
class RunReport:
    scene: str
    macro_steps: int
    simulated: float
    wall: float
    fmi_seconds: float
    largest_error: np.ndarray  # per DOF, after the first tenth of the run
    largest_energy_residual: float  # [J] over the power bonds, per macro step
    warnings: list[str]
    failure: str | None = None
    rejected_steps: int = 0
    step_control: str = "fixed"

    @property
    def real_time_factor(self) -> float:
        return self.simulated / self.wall

    @property
    def master_share(self) -> float:
        return 1.0 - self.fmi_seconds / self.wall

    def text(self) -> str:
        steps = f"{self.macro_steps} macro steps" + (f" ({self.step_control} step control, {self.rejected_steps} rejected)"
                                                     if self.step_control != "fixed" else "")
        lines = [f"{self.scene}: {self.simulated:g} s simulated in {self.wall:.2f} s wall, {steps}, "
                 f"real-time factor {self.real_time_factor:.1f}, {100 * self.master_share:.0f} % of the wall time in the "
                 f"master outside the FMUs", f"largest energy residual of a power bond in one step: "
                 f"{self.largest_energy_residual:.2e} J"]
        if len(self.largest_error):
            lines.append("largest tracking error after the first tenth: " + ", ".join(
                f"{a} {e:.2e}" for a, e in zip(("x", "y", "z", "roll", "pitch", "yaw"), self.largest_error)))
        if self.warnings:
            lines.append(f"{len(self.warnings)} warnings from the FMUs, first: {self.warnings[0]}")
        if self.failure:
            lines.append(f"FAILED: {self.failure}")
        return "\n".join(lines)


class SceneFailed(RuntimeError):
    def __init__(self, report: RunReport, result: np.ndarray):
        super().__init__(report.failure)
        self.report, self.result = report, result


def _progress_bar(start: float):
    def show(fraction: float) -> None:
        if time.perf_counter() - start > 2.0 and sys.stderr.isatty():
            done = int(40 * fraction)
            print(f"\r[{'#' * done}{'.' * (40 - done)}] {100 * fraction:3.0f} %", end="", file=sys.stderr, flush=True)
    return show


def step_control(scene: Scene, system: PlatformSystem) -> StepControl | None:
    """The scene's macro-step controller, or None for its fixed step. Step doubling measures the
    error on the mechanics' outputs to the drives (leg angles and speeds, or lengths and velocities)."""
    bounds = dict(rtol=scene.rtol, h_initial=scene.step, h_min=scene.h_min, h_max=scene.h_max)
    if scene.step_control == "doubling":
        return AdaptiveStep(system.algorithm, atol={"mechanics": scene.atol or 1e-3}, **bounds)
    if scene.step_control == "energy":
        return EnergyStep(system.algorithm, atol=scene.atol or 1e-4, **bounds)
    return None


def run_scene(scene: Scene, out: Path | None = None, plots: bool = True) -> tuple[np.ndarray, RunReport]:
    """Runs `scene`; returns the results (fmpy convention) and the report. Writes CSV, .mat and
    plots to `out` if given. Raises SceneFailed (with the partial results, also written) when an
    FMU fails."""
    mechanics_values = {**mechanics_start_values(scene.parameter_set, scene.mass_set), **scene.mechanics_parameters}
    system = PlatformSystem(scene.drive, mechanics_values, scene.drive_parameters, scene.order, scene.algorithm,
                            scene_trajectory(scene))
    control = step_control(scene, system)
    effort, speed, current = DRIVE_OUTPUTS[scene.drive]
    drive_outputs = scene.outputs_drive if scene.outputs_drive is not None else [effort, speed, current]
    try:
        system.record(scene.outputs_mechanics, drive_outputs)
    except KeyError as error:
        system.free()
        key = "mechanics" if any(f"'{n}'" in str(error) for n in scene.outputs_mechanics) else "drive"
        raise SceneError(f"{scene.path}:{line_of(scene.path.read_text(), 'outputs', key)}: 'outputs.{key}': "
                         f"{error.args[0]}") from None
    start = time.perf_counter()
    failure = None
    try:
        rows = system.run(scene.duration, scene.step, control, _progress_bar(start))
    except RunFailed as failed:
        rows, failure = failed.result, str(failed)
    wall = time.perf_counter() - start
    if sys.stderr.isatty() and wall > 2.0:
        print(file=sys.stderr)
    if scene.output_interval and len(rows) > 1:
        grid = np.arange(rows[0, 0], rows[-1, 0] + 1e-9, scene.output_interval)
        keep = np.unique(np.minimum(np.searchsorted(rows[:, 0], grid - 1e-9), len(rows) - 1))
        rows = rows[np.union1d(keep, [len(rows) - 1])]
    result = results.structured(rows, system.column_names)
    warnings = [m.text for i in system.coupling.instances.values() for m in i.messages if m.status == "warning"]
    fmi_seconds = system.fmi_seconds
    residuals = system.algorithm.energy_residuals
    system.free()

    late = result["time"] >= 0.1 * scene.duration
    errors = np.array([np.abs(result[f"pose.{a}"] - result[f"pose_ref.{a}"])[late].max() if late.any() else np.nan
                       for a in ("x", "y", "z", "roll", "pitch", "yaw")])
    report = RunReport(scene.name, len(result) - 1, float(result["time"][-1]), wall, fmi_seconds, errors,
                       max(residuals, default=0.0), warnings, failure, control.rejected if control else 0,
                       scene.step_control)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        stem = scene.path.stem
        results.write_csv(result, out / f"{stem}.csv")
        results.write_mat(result, out / f"{stem}.mat")
        if plots and len(result) > 1:
            results.plot_tracking(result, out / f"{stem}_tracking.png", scene.name)
            if {effort, speed} <= set(drive_outputs):
                results.plot_drives(result, out / f"{stem}_drives.png", scene.name, effort, speed)
    if failure:
        raise SceneFailed(report, result)
    return result, report
