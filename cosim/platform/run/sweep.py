"""`python -m cosim sweep SWEEP.toml`: a scene (or any SSP system) run at many points, on Dask.

A sweep file names its target and its axes, how points are drawn from them and what each point
reports (docs/guide/sweeps.md):

    [sweep]
    scene = "../scenes/meng_eq35.toml"      # or system = "meng.ssp" (paths relative to this file)
    duration = 1.0                          # optional: shorter runs than the target's own
    set = { "coupling.interface_jacobian" = false }   # optional: values every point takes
    sample = "grid"                         # every combination; "zip": the i-th values together;
                                            # "latin-hypercube": `points` points, `seed`
    [[axis]]
    key = "scene.step"                      # a scene key as its file writes it, or for a system a
    values = [5e-4, 1e-3]                   # setting (step, order, ...) or component.parameter
    [[axis]]
    key = 'mechanics.parameters."payload.mass"'
    linspace = [100.0, 400.0, 4]            # or geomspace = [...]; between = [low, high] (sampled)
    [report]
    values = ["tracking_error", "peak_effort", "energy_residual", "steps"]
    outputs = { "pose.z" = ["max", "rms"] } # statistics of recorded columns over the whole run
    [plot]
    report = "tracking_error.z"             # a column of the table, against one axis (a line) or
    x = "scene.step"                        # two (y = ..., a heat map); log_x, log_y

The engine (cosim.engine.sweep) reads the file, distributes and records the points; here the scene
is a target beside the SSP system (`SCENE`), and `ScenePoint` runs one point of it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ...engine.sweep import SYSTEM, Sweep, Target, statistics
from ...engine.sweep import load_sweep as engine_load_sweep
from .accuracy import difference, efforts
from ..ports import DRIVES, LEGS, POSE, per_leg
from ..scene import SceneError, load_scene, shipped

SCENE_REPORTS = {  # report name -> what it adds to a row
    "tracking_error": "largest |pose - pose_ref| per DOF after the first tenth of the run [m, rad]",
    "peak_effort": "largest |torque| (PMSM, N m) or |force| (linear motor, N) of each drive over the whole run",
    "energy_residual": "largest energy residual of a power bond in one macro step [J]",
    "steps": "macro steps taken (and rejected, under step control)",
    "real_time_factor": "simulated time / wall time of the stepping",
    "stepping_wall": "wall time of the stepping alone [s] (without loading and setting up the FMUs)",
    "pose_error": "largest pose difference to the sweep's reference run [m, rad] (advise, trade)",
    "effort_error": "largest drive effort difference to the reference, relative to its peak (advise, trade); "
                    "effort_error_time: when [s]",
    "window_error": "the drive efforts' largest difference to the reference in each window (start-up, each load "
                    "pulse and the 0.2 s after it, steady tracking) relative to their own change there, the worst "
                    "window's (advise); window_error_at: which window",
    "tolerance_ratio": "the efforts' worst window against the shipped scenes' tolerances (2 % of their own change "
                       "through the start-up and each load pulse, 1e-3 N m or 1e-3 of the static leg force in steady "
                       "tracking: cosim.platform.run.accuracy), at most 1 within them (trade); tolerance_ratio_at: which "
                       "window",
}


@dataclass(frozen=True)
class ScenePoint:
    """Runs a scene at one point: `values` are overrides at dotted keys of the scene's document
    (cosim.platform.scene.reader.load_scene). `reference` (a recorded run, for pose_error and
    effort_error) is compared at its own times."""
    path: str
    reports: tuple[str, ...] = ("tracking_error", "energy_residual", "steps")
    outputs: tuple[tuple[str, tuple[str, ...]], ...] = ()
    base: tuple[tuple[str, Any], ...] = ()  # overrides of every point (the sweep's duration)
    reference: np.ndarray | None = field(default=None, compare=False, hash=False)
    checkpoints: tuple[float, ...] | None = None  # pose_error at these times only (as a peer tool reports)

    def columns(self) -> list[str]:
        names = []
        for report in self.reports:
            names += {"tracking_error": [f"tracking_error.{a}" for a in POSE],
                      "peak_effort": per_leg("peak_effort"),
                      "effort_error": ["effort_error", "effort_error_time"],
                      "window_error": ["window_error", "window_error_at"],
                      "tolerance_ratio": ["tolerance_ratio", "tolerance_ratio_at"],
                      "steps": ["steps", "rejected"]}.get(report, [report])
        return names + [f"{s}.{c}" for c, stats in self.outputs for s in stats]

    def recorded(self) -> list[str]:
        """The columns a run of the scene records (what `outputs` may name)."""
        from .compile import scene_record
        return ["time", *scene_record(self.scene({}))[1]]

    def scene(self, values: Mapping[str, Any]):
        # a sweep keeps every core busy with points: each steps on one thread unless an axis says
        return load_scene(self.path, {"coupling.threads": 1, **dict(self.base), **values})

    def files(self, points: Sequence[Mapping[str, Any]] = ()) -> list[Path]:
        """The files the points' scenes read besides the scene file (a trajectory table, drive
        FMUs of the user's own), which travel to the Dask workers by content."""
        variants = [{}, *(p for p in points if any(str(k).endswith(("fmu", "table")) for k in p))]
        found: list[Path] = []
        for values in variants:
            scene = self.scene(values)
            found += [f for f in (scene.table, scene.drive_fmu, *scene.leg_fmus.values()) if f is not None]
        return list(dict.fromkeys(found))

    def check(self, values: Mapping[str, Any]) -> None:
        """Raises SceneError (one line) when the point cannot start: its keys, types and the
        FMUs' modelDescriptions (nothing is instantiated)."""
        from ...engine import ParameterError
        from ...engine.checks import check_parameters
        from .compile import scene_structure
        from .errors import scene_error
        scene = self.scene(values)
        try:
            check_parameters(scene_structure(scene))
        except ParameterError as error:
            raise scene_error(scene, error) from None

    def __call__(self, values: Mapping[str, Any]) -> dict[str, Any]:
        from ...engine.outcome import RunStopped
        from .runner import run_scene
        scene = self.scene(values)
        try:
            result, report = run_scene(scene)
            status, message = "ok", ""
        except RunStopped as failed:
            result, report = failed.result, failed.report
            status, message = ("diverged" if report.diverged else "failed"), report.failure or ""
        effort = DRIVES[scene.drive].outputs[0]
        row: dict[str, Any] = {}
        numbers = report.row()
        for name in self.reports:
            if name == "tracking_error":
                row.update({f"tracking_error.{a}": float(e) for a, e in zip(POSE, report.largest_error)})
            elif name == "peak_effort":
                row.update({f"peak_effort[{k}]": float(np.max(np.abs(result[f"{effort}[{k}]"]))) if len(result)
                            and f"{effort}[{k}]" in result.dtype.names else float("nan") for k in LEGS})
            elif name == "steps":
                row.update(steps=numbers["steps"], rejected=numbers["rejected"])
            elif name in ("energy_residual", "real_time_factor", "stepping_wall"):
                row[name] = numbers[name]
            elif name == "pose_error":
                poses = [f"pose.{a}" for a in POSE]
                if self.checkpoints is None:
                    row["pose_error"] = difference(result, self.reference, poses)
                elif not len(result) or result["time"][-1] < self.checkpoints[-1] - 1e-9:
                    row["pose_error"] = float("inf")
                else:
                    at = np.asarray(self.checkpoints)
                    row["pose_error"] = max(float(np.max(np.abs(np.interp(at, result["time"], result[n])
                                                                - np.interp(at, self.reference["time"],
                                                                            self.reference[n])))) for n in poses)
            elif name == "effort_error":
                names = per_leg(effort)
                mine, theirs = efforts(result, effort), efforts(self.reference, effort)
                peak = max(float(np.max(np.abs(theirs[n]))) for n in names)
                error, when = difference(mine, theirs, names, with_time=True)
                row.update(effort_error=error / peak, effort_error_time=when)
            elif name in ("window_error", "tolerance_ratio"):
                from .accuracy import steady_bound, tolerance_ratio, window_errors, windows
                if not len(result) or result["time"][-1] < self.reference["time"][-1] - 1e-9:
                    row.update({name: float("inf"), f"{name}_at": ""})
                    continue
                found = window_errors(efforts(result, effort), efforts(self.reference, effort), per_leg(effort),
                                      windows(float(self.reference["time"][-1]), scene.pulses))
                if name == "window_error":
                    worst = max(found, key=lambda e: e.relative)
                    row.update(window_error=worst.relative, window_error_at=worst.window)
                else:
                    from .compile import scene_values
                    from .tuning import leg_plants
                    bound = steady_bound(scene.drive, [p.static_force for p in leg_plants(scene_values(scene)[0])])
                    row.update(zip(("tolerance_ratio", "tolerance_ratio_at"), tolerance_ratio(found, bound)))
        row.update(statistics(result, dict(self.outputs)))
        return {**row, "status": status, "message": message}


# -- the sweep file: the scene as a target beside the SSP system ----------------------------------

def _scene_point(target: Path, reports: tuple[str, ...], outputs: tuple, duration: float | None,
                 fixed: tuple = ()) -> ScenePoint:
    return ScenePoint(str(target), reports, outputs,
                      (*((("scene.duration", duration),) if duration is not None else ()), *fixed))


SCENE = Target(SCENE_REPORTS, ("tracking_error", "energy_residual", "steps"), _scene_point,
               "a scene key as its file writes it, e.g. scene.step or mechanics.parameters.\"platform.mass\"",
               units={"scene.step": "s", "scene.duration": "s", "energy_residual": "J", "real_time_factor": "-",
                      **{f"tracking_error.{a}": "m" if a in "xyz" else "rad" for a in POSE}, "steps": "-",
                      "pose_error": "m, rad", "effort_error": "of the peak", "peak_effort": "N m or N",
                      "stepping_wall": "s"},
               internal=("pose_error", "effort_error", "window_error", "tolerance_ratio"), errors=(SceneError, ValueError),
               named=shipped, what="a scene")
TARGETS = {"scene": SCENE, "system": SYSTEM}


def load_sweep(path: str | Path) -> Sweep:
    """Reads and checks a sweep file whose target is a scene or an SSP system (see the module's
    docstring), or a shipped sweep file by its name (`meng_coupling`); every mistake is a
    SweepError naming the file and line."""
    if not Path(path).exists():
        path = shipped(str(path), "sweeps") or path
    return engine_load_sweep(path, TARGETS)
