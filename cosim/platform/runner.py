"""Runs a scene: compiles it into the platform's system structure and settings, runs that on the
engine, reports, and writes the results.

An FMU failure stops the run with a message naming the instance, the call and the time; the
results up to the last good communication point are written all the same.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine import (Algorithm, EnergyControl, Experiment, FixedStep, Progress, RunFailed, StepControl,
                      StepDoubling, SystemStructure)
from ..engine.results import thin, write as write_results
from ..engine.settings import control_name, to_strings
from .parameter_sets import mechanics_start_values
from .ports import DRIVES, POSE
from .scene import Scene, SceneError, line_of
from .signals import scene_trajectory
from .system import Run, columns, default_algorithm, platform_structure, run


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


def scene_settings(scene: Scene) -> tuple[Algorithm, StepControl]:
    """The scene's coupling algorithm and macro-step control. Step doubling measures the error on
    the mechanics' outputs to the drives (leg angles and speeds, or lengths and velocities)."""
    algorithm = default_algorithm(scene.drive, scene.algorithm, scene.order)
    bounds = dict(step=scene.step, rtol=scene.rtol, h_min=scene.h_min, h_max=scene.h_max)
    if scene.step_control == "doubling":
        return algorithm, StepDoubling(atol={"mechanics": scene.atol or 1e-3}, **bounds)
    if scene.step_control == "energy":
        return algorithm, EnergyControl(atol=scene.atol or 1e-4, **bounds)
    return algorithm, FixedStep(scene.step)


def scene_record(scene: Scene) -> tuple[list[tuple[str, str]], list[str]]:
    drive_outputs = scene.outputs_drive if scene.outputs_drive is not None else list(DRIVES[scene.drive].outputs)
    return columns(scene.drive, scene.outputs_mechanics, drive_outputs)


def scene_structure(scene: Scene) -> SystemStructure:
    """The scene as a system: FMUs, parameter values, connections, power bonds, experiment, and
    the settings (algorithm, step control, recorded outputs) as the SSP annotation carries them."""
    mechanics_values = {**mechanics_start_values(scene.parameter_set, scene.mass_set), **scene.mechanics_parameters}
    structure = platform_structure(scene.drive, mechanics_values, scene.drive_parameters, scene_trajectory(scene),
                                   name=scene.path.stem, experiment=Experiment(0.0, scene.duration, scene.step))
    algorithm, control = scene_settings(scene)
    structure.settings = to_strings(algorithm, control)
    record, names = scene_record(scene)
    structure.settings["record"] = " ".join(f"{c}.{v}={n}" for (c, v), n in zip(record, names))
    if scene.output_interval:
        structure.settings["output_interval"] = repr(scene.output_interval)
    return structure


def run_scene(scene: Scene, out: Path | None = None, plots: bool = True) -> tuple[np.ndarray, RunReport]:
    """Runs `scene`; returns the results (fmpy convention) and the report. Writes CSV, .mat and
    plots to `out` if given. Raises SceneFailed (with the partial results, also written) when an
    FMU fails or the coupling diverges."""
    structure = scene_structure(scene)
    algorithm, control = scene_settings(scene)
    record = scene_record(scene)
    progress = Progress(scene.name)
    try:
        outcome = run(structure, algorithm, control, scene.duration, record, observers=[progress])
        failure = None
    except RunFailed as failed:  # system.run attaches the partial run
        outcome, failure = failed.run, str(failed)
    except KeyError as error:  # a recorded output that the FMU does not have
        names = set(scene.outputs_mechanics)
        key = "mechanics" if any(f"'{n}'" in str(error) for n in names) else "drive"
        raise SceneError(f"{scene.path}:{line_of(scene.path.read_text(), 'outputs', key)}: 'outputs.{key}': "
                         f"{error.args[0]}") from None
    result = thin(outcome.result, scene.output_interval)
    report = scene_report(scene, result, outcome, failure, control_name(control))
    if out is not None:
        write_results(result, out, scene.path.stem)
        effort, speed = DRIVES[scene.drive].outputs[:2]
        if plots and len(result) > 1:
            from . import results
            results.plot_tracking(result, out / f"{scene.path.stem}_tracking.png", scene.name)
            if {f"{effort}[1]", f"{speed}[1]"} <= set(result.dtype.names):
                results.plot_drives(result, out / f"{scene.path.stem}_drives.png", scene.name, effort, speed)
    if failure:
        raise SceneFailed(report, result)
    return result, report


def scene_report(scene: Scene, result: np.ndarray, outcome: Run, failure: str | None, control: str) -> RunReport:
    late = result["time"] >= 0.1 * scene.duration
    errors = np.array([np.abs(result[f"pose.{a}"] - result[f"pose_ref.{a}"])[late].max() if late.any() else np.nan
                       for a in POSE])
    return RunReport(scene.name, len(outcome.steps), float(result["time"][-1]), outcome.wall, outcome.fmi_seconds,
                     errors, float(np.max(outcome.energy_residuals, initial=0.0)), outcome.warnings, failure,
                     outcome.rejected, control)
