"""The sweep file (`python -m cosim sweep SWEEP.toml`): its target, axes, sampling, reports and
plot, read and checked whole before anything runs, every mistake one line with the file and line.

A target is what the file's [sweep] table names: `system = "x.ssp"` (any SSP system, here), or
an application's own kind (the platform's `scene = "x.toml"`), each a `Target` that says which
reports its points give and makes the evaluator of a point.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..tomlfile import line_of, read
from .points import Axis, SweepError, column_name, grid, latin_hypercube, zipped
from .table import STATISTICS


@dataclass(frozen=True)
class Target:
    """A kind of sweep target: `reports` (name -> what it adds to a row), the ones a file gets
    when it names none, `internal` ones a file may not ask for (they need a reference run), units
    of its columns (for plots), what an axis key is (for messages), the exceptions a point that
    cannot start raises, and `point(target file, reports, outputs, duration, fixed)`: the evaluator
    (fixed: the [sweep] table's `set`, values every point takes, under the axes' own); `named`
    finds a target the application ships by its name (a scene's), where no file of that name is."""
    reports: Mapping[str, str]
    default_reports: tuple[str, ...]
    point: Callable[..., Any]
    keys: str
    units: Mapping[str, str] = field(default_factory=dict)
    internal: tuple[str, ...] = ()
    errors: tuple[type[Exception], ...] = (ValueError,)
    named: Callable[[str], Path | None] | None = None


SCHEMA = {"": {"sweep", "axis", "report", "plot"},
          "sweep": {"duration", "set", "sample", "points", "seed", "points_per_task", "retries"},  # and the targets'
          "axis": {"key", "values", "linspace", "geomspace", "between"},
          "report": {"values", "outputs"}, "plot": {"report", "x", "y", "log_x", "log_y", "log_color"}}


@dataclass
class Sweep:
    path: Path
    name: str
    evaluate: Any  # the target's evaluator of one point (picklable: it travels to the workers)
    axes: list[Axis]
    points: list[dict[str, Any]]
    signature: str
    points_per_task: int | None = None
    retries: int = 3
    plot: dict | None = None
    units: dict[str, str] = field(default_factory=dict)

    @property
    def columns(self) -> list[str]:
        return self.evaluate.columns()


def load_sweep(path: str | Path, targets: Mapping[str, Target]) -> Sweep:
    """Reads and checks a sweep file whose [sweep] names one of `targets` (kind -> Target: the SSP
    target "system" here, an application's own beside it); every mistake is a SweepError naming
    the file and line."""
    path = Path(path)
    text, data = read(path, "sweep file", SweepError)
    axis_lines = [n for n, line in enumerate(text.splitlines(), 1) if line.split("#")[0].strip() == "[[axis]]"]

    def fail(table: str, key: str, problem: str, line: int | None = None) -> SweepError:
        return SweepError(f"{path}:{line if line is not None else line_of(text, table, key)}: "
                          f"'{table + '.' if table else ''}{key}' {problem}")

    for table, allowed in {**SCHEMA, "sweep": SCHEMA["sweep"] | set(targets)}.items():
        entries = data if table == "" else data.get(table, {})
        for entry in (entries if isinstance(entries, list) else [entries]):
            if not isinstance(entry, dict):
                raise fail("", table, "must be a table" if table != "axis" else "must be [[axis]] tables")
            for key in entry:
                if key not in allowed:
                    line = axis_lines[0] if table == "axis" and axis_lines else None
                    raise fail(table, key, f"is not a known key (known here: {', '.join(sorted(allowed))})", line)
    sweep, report = data.get("sweep", {}), data.get("report", {})
    named = [k for k in targets if k in sweep]
    if len(named) != 1:
        raise SweepError(f"{path}:{line_of(text, '', 'sweep')}: [sweep] needs exactly one of "
                         + " or ".join(f'{k} = "..."' for k in targets))
    kind = named[0]
    target_kind = targets[kind]
    target = (path.parent / str(sweep[kind])).resolve()
    if not target.is_file() and target_kind.named is not None:
        target = target_kind.named(str(sweep[kind])) or target
    if not target.is_file():
        raise fail("sweep", kind, f"= {sweep[kind]!r}: no such file (relative to the sweep file's folder)")
    duration = sweep.get("duration")
    if duration is not None and (isinstance(duration, bool) or not isinstance(duration, (int, float))
                                 or not duration > 0 or duration == float("inf")):
        raise fail("sweep", "duration", f"= {duration!r} must be a positive number of seconds")

    fixed = sweep.get("set", {})
    if not isinstance(fixed, dict):
        raise fail("sweep", "set", f"= {fixed!r} must be a table of key = value that every point takes")
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
            raise SweepError(f"{path}:{line}: [[axis]] needs key = \"...\" ({target_kind.keys})")
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

    wanted = report.get("values", list(target_kind.default_reports))
    known = [k for k in target_kind.reports if k not in target_kind.internal]
    if not isinstance(wanted, list) or not all(isinstance(v, str) for v in wanted):
        raise fail("report", "values", "must be a list of report names")
    for name in wanted:
        if name not in known:
            raise fail("report", "values", f"has {name!r}: known reports are {', '.join(known)}")
    outputs = report.get("outputs", {})
    if not isinstance(outputs, dict):
        raise fail("report", "outputs", "must be a table of column = [statistics]")
    for column, stats in outputs.items():
        if not isinstance(stats, list) or not stats or not all(s in STATISTICS for s in stats):
            raise fail("report", "outputs", f"{column!r} = {stats!r}: statistics are {', '.join(STATISTICS)}")
    output_spec = tuple((c, tuple(s)) for c, s in outputs.items())

    evaluate = target_kind.point(target, tuple(wanted), output_spec, float(duration) if duration is not None else None,
                                 tuple(fixed.items()))
    _check_points(path, text, evaluate, axes, points, target_kind.errors, line_of(text, "sweep", "set"))
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
    digest.update(repr((kind, duration, sorted(fixed.items(), key=str), [column_name(n) for n in names],
                        evaluate.columns())).encode())
    return Sweep(path, path.stem, evaluate, axes, points, digest.hexdigest(), sweep.get("points_per_task"),
                 sweep.get("retries", 3), plot, dict(target_kind.units))


def _check_points(path: Path, text: str, evaluate, axes: list[Axis], points: list[dict],
                  errors: tuple[type[Exception], ...], fixed_line: int = 0) -> None:
    """The target as it is, then each axis at the first point's value: a wrong key or a value the
    target cannot take is named at its axis' line before anything runs. (Other points' values
    are checked when they run: a point that cannot start is a row with its message.)"""
    try:
        evaluate.check({})
    except (*errors, KeyError) as error:
        reason = re.sub(r"^\S+?:\d+: ", "", str(error).strip("'\""))
        where = f"{path}:{fixed_line}: [sweep] set:" if fixed_line else f"{path}:"
        raise SweepError(f"{where} the sweep's target cannot run as it is: {reason}") from None
    first = points[0] if points else {}
    for axis in axes:
        value = first.get(axis.name)
        try:
            evaluate.check({axis.name: value})
        except (*errors, KeyError) as error:
            reason = re.sub(r"^\S+?:\d+: ", "", str(error).strip("'\""))
            raise SweepError(f"{path}:{axis.line}: axis {axis.name!r} = {value!r}: {reason}") from None
