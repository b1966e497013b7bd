"""`python -m cosim sweep SWEEP.toml`: a scene (or any SSP system) run at many points, on Dask.

A sweep file names its target and its axes, how points are drawn from them and what each point
reports (docs in the README's "Sweeps" section):

    [sweep]
    scene = "../scenes/meng_eq35.toml"      # or system = "meng.ssp" (paths relative to this file)
    duration = 1.0                          # optional: shorter runs than the target's own
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

The engine (cosim.engine.sweep) distributes and records the points; `ScenePoint` here runs one.
"""

from __future__ import annotations

import hashlib
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from ..engine.sweep import (STATISTICS, Axis, SweepError, SystemPoint, column_name, grid, latin_hypercube,
                            statistics, zipped)
from .ports import DRIVES, LEGS, POSE, per_leg
from .scene import SceneError, line_of, load_scene

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
}
SYSTEM_REPORTS = ("energy_residual", "steps", "real_time_factor")
SCHEMA = {"": {"sweep", "axis", "report", "plot"},
          "sweep": {"scene", "system", "duration", "sample", "points", "seed", "points_per_task", "retries"},
          "axis": {"key", "values", "linspace", "geomspace", "between"},
          "report": {"values", "outputs"}, "plot": {"report", "x", "y", "log_x", "log_y", "log_color"}}


@dataclass(frozen=True)
class ScenePoint:
    """Runs a scene at one point: `values` are overrides at dotted keys of the scene's document
    (cosim.platform.scene.load_scene). `reference` (a recorded run, for pose_error and
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
                      "steps": ["steps", "rejected"]}.get(report, [report])
        return names + [f"{s}.{c}" for c, stats in self.outputs for s in stats]

    def recorded(self) -> list[str]:
        """The columns a run of the scene records (what `outputs` may name)."""
        from .runner import scene_record
        return ["time", *scene_record(self.scene({}))[1]]

    def scene(self, values: Mapping[str, Any]):
        # a sweep keeps every core busy with points: each steps on one thread unless an axis says
        return load_scene(self.path, {"coupling.threads": 1, **dict(self.base), **values})

    def check(self, values: Mapping[str, Any]) -> None:
        """Raises SceneError (one line) when the point cannot start: its keys, types and the
        FMUs' modelDescriptions (nothing is instantiated)."""
        from ..engine import ParameterError
        from ..engine.checks import check_parameters
        from .runner import scene_error, scene_structure
        scene = self.scene(values)
        try:
            check_parameters(scene_structure(scene))
        except ParameterError as error:
            raise scene_error(scene, error) from None

    def __call__(self, values: Mapping[str, Any]) -> dict[str, Any]:
        from .runner import SceneFailed, run_scene
        scene = self.scene(values)
        try:
            result, report = run_scene(scene, plots=False, progress=False, advice=False)
            status, message = "ok", ""
        except SceneFailed as failed:
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
                peak = max(float(np.max(np.abs(self.reference[n]))) for n in names)
                error, when = difference(result, self.reference, names, with_time=True)
                row.update(effort_error=error / peak, effort_error_time=when)
        row.update(statistics(result, dict(self.outputs)))
        return {**row, "status": status, "message": message}


def difference(result: np.ndarray, reference: np.ndarray, names: Sequence[str], with_time: bool = False):
    """Largest |result - reference| over `names` at the result's own times, the (finer) reference
    interpolated there (and when, with_time); inf when the result stops before the reference does."""
    if not len(result) or result["time"][-1] < reference["time"][-1] - 1e-9:
        return (float("inf"), float("nan")) if with_time else float("inf")
    t = result["time"]
    gap = np.max([np.abs(result[n] - np.interp(t, reference["time"], reference[n])) for n in names], axis=0)
    k = int(np.argmax(gap))
    return (float(gap[k]), float(t[k])) if with_time else float(gap[k])


# -- the sweep file -------------------------------------------------------------------------------

@dataclass
class Sweep:
    path: Path
    name: str
    evaluate: ScenePoint | SystemPoint
    axes: list[Axis]
    points: list[dict[str, Any]]
    signature: str
    points_per_task: int | None = None
    retries: int = 3
    plot: dict | None = None

    @property
    def columns(self) -> list[str]:
        return self.evaluate.columns()


def load_sweep(path: str | Path) -> Sweep:
    """Reads and checks a sweep file; every mistake is a SweepError naming the file and line."""
    path = Path(path)
    if not path.is_file():
        raise SweepError(f"{path}: no such sweep file")
    text = path.read_text()
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SweepError(f"{path}: not valid TOML: {error}") from None
    axis_lines = [n for n, line in enumerate(text.splitlines(), 1) if line.split("#")[0].strip() == "[[axis]]"]

    def fail(table: str, key: str, problem: str, line: int | None = None) -> SweepError:
        return SweepError(f"{path}:{line if line is not None else line_of(text, table, key)}: "
                          f"'{table + '.' if table else ''}{key}' {problem}")

    for table, allowed in SCHEMA.items():
        entries = data if table == "" else data.get(table, {})
        for entry in (entries if isinstance(entries, list) else [entries]):
            if not isinstance(entry, dict):
                raise fail("", table, "must be a table" if table != "axis" else "must be [[axis]] tables")
            for key in entry:
                if key not in allowed:
                    line = axis_lines[0] if table == "axis" and axis_lines else None
                    raise fail(table, key, f"is not a known key (known here: {', '.join(sorted(allowed))})", line)
    sweep, report = data.get("sweep", {}), data.get("report", {})
    targets = [k for k in ("scene", "system") if k in sweep]
    if len(targets) != 1:
        raise SweepError(f"{path}:{line_of(text, '', 'sweep')}: [sweep] needs exactly one of scene = \"...\" or "
                         "system = \"....ssp\"")
    kind = targets[0]
    target = (path.parent / str(sweep[kind])).resolve()
    if not target.is_file():
        raise fail("sweep", kind, f"= {sweep[kind]!r}: no such file (relative to the sweep file's folder)")
    duration = sweep.get("duration")
    if duration is not None and (isinstance(duration, bool) or not isinstance(duration, (int, float))
                                 or not duration > 0 or duration == float("inf")):
        raise fail("sweep", "duration", f"= {duration!r} must be a positive number of seconds")

    axes = []
    raw_axes = data.get("axis", [])
    if not raw_axes:
        raise SweepError(f"{path}: a sweep needs at least one [[axis]] with key = \"...\" and its values")
    sample = sweep.get("sample", "grid")
    if sample not in ("grid", "zip", "latin-hypercube"):
        raise fail("sweep", "sample", f"= {sample!r}: use 'grid', 'zip' or 'latin-hypercube'")
    for number, entry in enumerate(raw_axes):
        line = axis_lines[number] if number < len(axis_lines) else 0
        key = entry.get("key")
        if not isinstance(key, str) or not key:
            raise SweepError(f"{path}:{line}: [[axis]] needs key = \"...\" (a scene key, a setting or "
                             "component.parameter)")
        forms = [f for f in ("values", "linspace", "geomspace", "between") if f in entry]
        if len(forms) != 1:
            raise SweepError(f"{path}:{line}: axis {key!r} needs one of values, linspace, geomspace or between")
        form, spec = forms[0], entry[forms[0]]
        if form == "values":
            if not isinstance(spec, list) or not spec:
                raise SweepError(f"{path}:{line}: axis {key!r}: values must be a non-empty list")
            axes.append(Axis(key, tuple(spec), line=line))
        elif form in ("linspace", "geomspace"):
            if (not isinstance(spec, list) or len(spec) != 3 or not all(isinstance(v, (int, float)) and not isinstance(
                    v, bool) for v in spec) or not (isinstance(spec[2], int) and spec[2] >= 1)
                    or (form == "geomspace" and not (spec[0] > 0 and spec[1] > 0))):
                raise SweepError(f"{path}:{line}: axis {key!r}: {form} = [start, stop, count] with a whole count >= 1"
                                 + (" and positive ends" if form == "geomspace" else ""))
            values = getattr(np, form)(float(spec[0]), float(spec[1]), int(spec[2]))
            axes.append(Axis(key, tuple(float(v) for v in values), line=line))
        else:
            if (not isinstance(spec, list) or len(spec) != 2 or not all(isinstance(v, (int, float)) and not isinstance(
                    v, bool) for v in spec) or not spec[0] < spec[1]):
                raise SweepError(f"{path}:{line}: axis {key!r}: between = [low, high] with low < high")
            if sample != "latin-hypercube":
                raise SweepError(f"{path}:{line}: axis {key!r}: between = [...] is for sample = 'latin-hypercube'; "
                                 "give values, linspace or geomspace for a grid")
            axes.append(Axis(key, (), between=(float(spec[0]), float(spec[1])), line=line))
    names = [a.name for a in axes]
    if len(set(map(column_name, names))) < len(names):
        raise SweepError(f"{path}: an axis key appears twice")
    if sample == "latin-hypercube":
        count, seed = sweep.get("points"), sweep.get("seed", 0)
        if not isinstance(count, int) or isinstance(count, bool) or count < 1:
            raise fail("sweep", "points", f"= {count!r}: a Latin-hypercube sweep needs points = a whole number >= 1")
        if not isinstance(seed, int) or isinstance(seed, bool):
            raise fail("sweep", "seed", f"= {seed!r} must be a whole number")
        points = latin_hypercube(axes, count, seed)
    else:
        try:
            points = grid(axes) if sample == "grid" else zipped(axes)
        except SweepError as error:
            raise fail("sweep", "sample", f"= 'zip': {error}") from None
    for key in ("points_per_task", "retries"):
        value = sweep.get(key)
        if value is not None and (not isinstance(value, int) or isinstance(value, bool) or value < (1 if key ==
                                                                                                      "points_per_task" else 0)):
            raise fail("sweep", key, f"= {value!r} must be a whole number >= {1 if key == 'points_per_task' else 0}")

    wanted = report.get("values", ["tracking_error", "energy_residual", "steps"] if kind == "scene"
                        else list(SYSTEM_REPORTS))
    known = list(SCENE_REPORTS) if kind == "scene" else list(SYSTEM_REPORTS)
    if not isinstance(wanted, list) or not all(isinstance(v, str) for v in wanted):
        raise fail("report", "values", "must be a list of report names")
    for name in wanted:
        if name not in known or name in ("pose_error", "effort_error"):
            names = [k for k in known if k not in ("pose_error", "effort_error")]
            raise fail("report", "values", f"has {name!r}: known reports are {', '.join(names)}")
    outputs = report.get("outputs", {})
    if not isinstance(outputs, dict):
        raise fail("report", "outputs", "must be a table of column = [statistics]")
    for column, stats in outputs.items():
        if not isinstance(stats, list) or not stats or not all(s in STATISTICS for s in stats):
            raise fail("report", "outputs", f"{column!r} = {stats!r}: statistics are {', '.join(STATISTICS)}")
    output_spec = tuple((c, tuple(s)) for c, s in outputs.items())

    if kind == "scene":
        base = (("scene.duration", float(duration)),) if duration is not None else ()
        evaluate: ScenePoint | SystemPoint = ScenePoint(str(target), tuple(wanted), output_spec, base)
    else:
        evaluate = SystemPoint(str(target), float(duration) if duration is not None else None, output_spec)
    _check_points(path, text, evaluate, axes, points)
    recorded = evaluate.recorded()
    for column in outputs:
        if column not in recorded:
            import difflib
            near = difflib.get_close_matches(column, recorded, 1)
            raise fail("report", "outputs", f"names {column!r}, which the run does not record"
                       + (f" (did you mean {near[0]!r}?)" if near else f" (recorded: {', '.join(recorded[:12])}, ...)"))

    plot = data.get("plot")
    columns = {column_name(n) for n in names} | set(evaluate.columns())
    if plot is not None:
        for key in ("report", "x", "y"):
            if key in plot and column_name(str(plot[key])) not in columns:
                raise fail("plot", key, f"= {plot[key]!r} is not a column of the table (axes: "
                           f"{', '.join(column_name(n) for n in names)}; reports: {', '.join(evaluate.columns()[:8])}...)")
        if "report" not in plot or "x" not in plot:
            raise SweepError(f"{path}:{line_of(text, '', 'plot')}: [plot] needs report = \"column\" and x = \"axis\"")
    digest = hashlib.sha1()
    digest.update(target.read_bytes())
    digest.update(repr((kind, duration, [column_name(n) for n in names], evaluate.columns())).encode())
    return Sweep(path, path.stem, evaluate, axes, points, digest.hexdigest(), sweep.get("points_per_task"),
                 sweep.get("retries", 3), plot)


def _check_points(path: Path, text: str, evaluate, axes: list[Axis], points: list[dict]) -> None:
    """The target as it is, then each axis at the first point's value: a wrong key or a value the
    target cannot take is named at its axis' line before anything runs. (Other points' values
    are checked when they run: a point that cannot start is a row with its message.)"""
    try:
        evaluate.check({})
    except (SceneError, ValueError) as error:
        raise SweepError(f"{path}: the sweep's target cannot run as it is: {error}") from None
    first = points[0] if points else {}
    for axis in axes:
        value = first.get(axis.name)
        try:
            evaluate.check({axis.name: value})
        except (SceneError, ValueError, KeyError) as error:
            reason = re.sub(r"^\S+?:\d+: ", "", str(error).strip("'\""))
            raise SweepError(f"{path}:{axis.line}: axis {axis.name!r} = {value!r}: {reason}") from None


# -- the plot -------------------------------------------------------------------------------------

UNITS = {"scene.step": "s", "scene.duration": "s", "energy_residual": "J", "real_time_factor": "-",
         "tracking_error.x": "m", "tracking_error.y": "m", "tracking_error.z": "m", "tracking_error.roll": "rad",
         "tracking_error.pitch": "rad", "tracking_error.yaw": "rad", "steps": "-", "pose_error": "m, rad",
         "effort_error": "of the peak"}


def label(column: str) -> str:
    """An axis label: the column and its unit where the table knows it."""
    unit = UNITS.get(column) or ("N m or N" if column.startswith("peak_effort") else None)
    return f"{column} [{unit}]" if unit else column


def _outline():
    from matplotlib import patheffects
    return patheffects.withStroke(linewidth=2, foreground="black")


def plot_sweep(rows: list[dict], spec: dict, path: Path, title: str) -> Path:
    """The chosen report against one axis (a line, failed points marked at the bottom) or two
    (a heat map on a grid, coloured points otherwise)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .results import save_figure
    report, x_name, y_name = (column_name(str(spec[k])) if k in spec else None for k in ("report", "x", "y"))
    ok = [r for r in rows if r["status"] == "ok" and np.isfinite(r.get(report, np.nan))]
    bad = [r for r in rows if r not in ok]
    fig, ax = plt.subplots(figsize=(8, 5))
    if y_name is None:
        ok.sort(key=lambda r: r[x_name])
        ax.plot([r[x_name] for r in ok], [r[report] for r in ok], "o-", ms=4, label="ran")
        if bad:
            bottom = min((r[report] for r in ok), default=1.0)
            ax.plot([r[x_name] for r in bad], [bottom] * len(bad), "rx", ms=8,
                    label=f"diverged or failed ({len(bad)})")
        ax.set(xlabel=label(x_name), ylabel=label(report))
        if spec.get("log_y"):
            ax.set_yscale("log")
        ax.legend()
    else:
        xs, ys = sorted({r[x_name] for r in rows}), sorted({r[y_name] for r in rows})
        if len(xs) * len(ys) == len(rows):  # a grid: a heat map, failed cells blank
            z = np.full((len(ys), len(xs)), np.nan)
            for r in ok:
                z[ys.index(r[y_name]), xs.index(r[x_name])] = r[report]
            from matplotlib.colors import LogNorm
            norm = LogNorm() if spec.get("log_color") and np.nanmin(z, initial=np.inf) > 0 else None
            image = ax.pcolormesh(np.arange(len(xs) + 1), np.arange(len(ys) + 1), z, shading="flat", norm=norm)
            ax.set_xticks(np.arange(len(xs)) + 0.5, [f"{v:g}" if isinstance(v, float) else str(v) for v in xs])
            ax.set_yticks(np.arange(len(ys)) + 0.5, [f"{v:g}" if isinstance(v, float) else str(v) for v in ys])
            for r in ok:
                ax.text(xs.index(r[x_name]) + 0.5, ys.index(r[y_name]) + 0.5, f"{r[report]:.3g}", ha="center",
                        va="center", fontsize=8, color="white", path_effects=[_outline()])
            for r in bad:
                ax.text(xs.index(r[x_name]) + 0.5, ys.index(r[y_name]) + 0.5, r["status"], ha="center", va="center",
                        fontsize=7, color="red")
        else:
            image = ax.scatter([r[x_name] for r in ok], [r[y_name] for r in ok], c=[r[report] for r in ok], s=30)
            if bad:
                ax.plot([r[x_name] for r in bad], [r[y_name] for r in bad], "rx", label="diverged or failed")
                ax.legend()
        fig.colorbar(image, ax=ax, label=label(report))
        ax.set(xlabel=label(x_name), ylabel=label(y_name))
    if spec.get("log_x") and y_name is None:
        ax.set_xscale("log")
    ax.set_title(title)
    if y_name is None:
        ax.grid(True, alpha=0.3)
    else:
        ax.grid(False)
    save_figure(fig, path)
    return path
