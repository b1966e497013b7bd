"""The sweep file (`python -m cosim sweep SWEEP.toml`): its target, axes, sampling, reports and
plot, read and checked whole before anything runs, every mistake one line with the file and line.

A target is what the file's [sweep] table names: `system = "x.ssp"` (any SSP system, here), or
an application's own kind (the platform's `scene = "x.toml"`), each a `Target` that says which
reports its points give and makes the evaluator of a point.
"""

from __future__ import annotations

import difflib
import hashlib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..schema import Document, Key, Schema, Table, read
from ..values import REQUIRED, Anything, Choice, Flag, Free, ListOf, Number, Row, Text
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
    what: str = "a file"  # what the sweep file's key of this kind names, for the reference


def schema(targets: Mapping[str, Target]) -> Schema:
    """The sweep file's schema, its [sweep] table naming one of `targets` (kind -> Target)."""
    whole = Number(whole=True)
    return Schema("sweep file", "A sweep file (`cosim sweep FILE`): one target run at many points, on Dask "
                  "(docs/guide/sweeps.md).", (
        Table("", "The file holds the tables below; [sweep] and at least one [[axis]] are required."),
        Table("sweep", "The target and how its points are drawn.", (
            *(Key(kind, Text(path=True), f"the target: {target.what} (relative to this file; or a shipped one's name)")
              for kind, target in targets.items()),
            Key("duration", Number("s", 0, above=True), "every point's run this long instead of the target's own"),
            Key("set", Free("key = value"), "values every point takes, under the axes' own (keys as the axes')"),
            Key("sample", Choice(("grid", "zip", "latin-hypercube")), "every combination of the axes' values, their "
                "i-th values together, or `points` points of a Latin hypercube", "grid"),
            Key("points", Number(low=1, whole=True), "a Latin-hypercube sweep's number of points"),
            Key("seed", whole, "a Latin-hypercube sweep's seed", 0),
            Key("points_per_task", Number(low=1, whole=True), "points per Dask task (default: about four tasks per "
                "worker)"),
            Key("retries", Number(low=0, whole=True), "times a task whose worker died is run again", 3)), required=True),
        Table("axis", "One swept key and its values: exactly one of values, linspace, geomspace or between.", (
            Key("key", Text(), "what the axis sets: " + "; ".join(f"{kind}: {target.keys}" for kind, target in
                                                                  targets.items()), REQUIRED),
            Key("values", ListOf(Anything(), least=1), "the values, as the key takes them"),
            Key("linspace", Row((Number(), Number(), Number(low=1, whole=True))), "[start, stop, count]: evenly "
                "spaced"),
            Key("geomspace", Row((Number(low=0, above=True), Number(low=0, above=True), Number(low=1, whole=True))),
                "[start, stop, count]: evenly spaced in the logarithm"),
            Key("between", Row((Number(), Number())), "[low, high]: sampled (sample = \"latin-hypercube\")")),
              many=True),
        Table("report", "What each point's row reports besides its axes.", (
            Key("values", ListOf(Text()), "the target's reports by name (below); default: the target's own choice"),
            Key("outputs", Free("column = [statistics]"), "statistics of recorded columns over the run: "
                + ", ".join(STATISTICS)))),
        Table("plot", "A figure of one column of the table against one axis (a line) or two (a heat map).", (
            Key("report", Text(), "the column shown", REQUIRED),
            Key("x", Text(), "the axis along x", REQUIRED),
            Key("y", Text(), "a second axis along y (a heat map)"),
            Key("log_x", Flag(), "a logarithmic x axis", False),
            Key("log_y", Flag(), "a logarithmic y axis", False),
            Key("log_color", Flag(), "a logarithmic colour scale", False))),
    ), SweepError)


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

    def run(self, out: Path, workers: int | None = None, scheduler: str | None = None, progress: bool = True):
        """Runs every point not yet in `out` (cosim.engine.sweep.run_sweep) and returns the outcome."""
        from .dask_run import run_sweep
        return run_sweep(self.name, self.points, self.evaluate, self.columns, Path(out), self.signature,
                         workers=workers, scheduler=scheduler, points_per_task=self.points_per_task,
                         retries=self.retries, progress=progress)


def load_sweep(path: str | Path, targets: Mapping[str, Target]) -> Sweep:
    """Reads and checks a sweep file whose [sweep] names one of `targets` (kind -> Target: the SSP
    target "system" here, an application's own beside it); every mistake is a SweepError naming
    the file and line."""
    doc = read(schema(targets), path)
    path = doc.path
    named = [k for k in targets if k in doc.table("sweep")]
    if len(named) != 1:
        raise doc.fail("sweep", "needs exactly one of " + " or ".join(f'{k} = "..."' for k in targets))
    kind = named[0]
    given = doc.value("sweep", kind)
    target = (path.parent / given).resolve()
    if not target.is_file() and targets[kind].named is not None:
        target = targets[kind].named(given) or target
    if not target.is_file():
        raise doc.fail(f"sweep.{kind}", "no such file (relative to the sweep file's folder)", given)
    sample = doc.value("sweep", "sample")
    axes = [_axis(doc, k, sample) for k in range(len(doc.entries("axis")))]
    if not axes:
        raise doc.fail("sweep", "needs at least one [[axis]] with key = \"...\" and its values")
    names = [a.name for a in axes]
    if len(set(map(column_name, names))) < len(names):
        twice = next(n for n in names if [column_name(m) for m in names].count(column_name(n)) > 1)
        raise doc.fail(f"axis[{len(names)}].key", "the same key as another axis", twice)
    if sample == "latin-hypercube":
        if doc.value("sweep", "points") is None:
            raise doc.fail("sweep.points", "is missing: a Latin-hypercube sweep needs points = a whole number >= 1")
        points = latin_hypercube(axes, int(doc.value("sweep", "points")), int(doc.value("sweep", "seed")))
    else:
        try:
            points = grid(axes) if sample == "grid" else zipped(axes)
        except SweepError as error:
            raise doc.fail("sweep.sample", str(error), sample) from None

    target_kind = targets[kind]
    wanted, outputs = _reports(doc, target_kind)
    duration, fixed = doc.value("sweep", "duration"), doc.value("sweep", "set", {})
    evaluate = target_kind.point(target, tuple(wanted), tuple((c, tuple(s)) for c, s in outputs.items()),
                                 float(duration) if duration is not None else None, tuple(fixed.items()))
    _check_points(doc, evaluate, axes, points, target_kind.errors)
    recorded = evaluate.recorded()
    for column in outputs:
        if column not in recorded:
            near = difflib.get_close_matches(column, recorded, 1)
            raise doc.fail("report.outputs", f"names {column!r}, which the run does not record"
                           + (f" (did you mean {near[0]!r}?)" if near else f" (recorded: {', '.join(recorded[:12])}, ...)"))
    plot = doc.table("plot") or None
    columns = {column_name(n) for n in names} | set(evaluate.columns())
    for key in ("report", "x", "y"):
        if plot is not None and key in plot and column_name(str(plot[key])) not in columns:
            raise doc.fail(f"plot.{key}", f"is not a column of the table (axes: {', '.join(map(column_name, names))}; "
                           f"reports: {', '.join(evaluate.columns()[:8])}...)", plot[key])
    digest = hashlib.sha1()
    digest.update(target.read_bytes())
    digest.update(repr((kind, duration, sorted(fixed.items(), key=str), [column_name(n) for n in names],
                        evaluate.columns())).encode())
    return Sweep(path, path.stem, evaluate, axes, points, digest.hexdigest(), doc.value("sweep", "points_per_task"),
                 doc.value("sweep", "retries"), plot, dict(target_kind.units))


def _reports(doc: Document, target: Target) -> tuple[list[str], dict[str, list[str]]]:
    """[report]: the target's reports by name (its default ones where none are named) and the
    statistics of recorded columns."""
    wanted = doc.value("report", "values", list(target.default_reports))
    known = [k for k in target.reports if k not in target.internal]
    for name in wanted:
        if name not in known:
            raise doc.fail("report.values", f"has {name!r}: known reports are {', '.join(known)}", wanted)
    outputs = doc.value("report", "outputs", {})
    for column, stats in outputs.items():
        if not isinstance(stats, list) or not stats or not all(s in STATISTICS for s in stats):
            raise doc.fail("report.outputs", f"has {column!r} = {stats!r}: statistics are {', '.join(STATISTICS)}")
    return wanted, outputs


def _axis(doc: Document, k: int, sample: str) -> Axis:
    """The k-th [[axis]] (0 the first): its key and values, or its range for a Latin hypercube."""
    entry, where = doc.entries("axis")[k], f"axis[{k + 1}]"
    key, line = entry["key"], doc.line(where)
    forms = [f for f in ("values", "linspace", "geomspace", "between") if f in entry]
    if len(forms) != 1:
        raise doc.fail(where, "needs one of values, linspace, geomspace or between"
                       + (f", not {' and '.join(forms)}" if forms else ""))
    form, spec = forms[0], entry[forms[0]]
    if form == "values":
        return Axis(key, tuple(spec), line=line)
    if form in ("linspace", "geomspace"):
        values = getattr(np, form)(float(spec[0]), float(spec[1]), int(spec[2]))
        return Axis(key, tuple(float(v) for v in values), line=line)
    if not spec[0] < spec[1]:
        raise doc.fail(f"{where}.between", "needs low < high", spec)
    if sample != "latin-hypercube":
        raise doc.fail(f"{where}.between", "is for sample = 'latin-hypercube'; give values, linspace or geomspace "
                       "for a grid", spec)
    return Axis(key, (), between=(float(spec[0]), float(spec[1])), line=line)


def _check_points(doc: Document, evaluate, axes: list[Axis], points: list[dict],
                  errors: tuple[type[Exception], ...]) -> None:
    """The target as it is, then each axis at the first point's value: a wrong key or a value the
    target cannot take is named at its axis' line before anything runs. (Other points' values
    are checked when they run: a point that cannot start is a row with its message.)"""
    try:
        evaluate.check({})
    except (*errors, KeyError) as error:
        reason = re.sub(r"^\S+?:\d+: ", "", str(error).strip("'\""))
        raise doc.fail("sweep.set" if doc.value("sweep", "set") else "sweep",
                       f": the sweep's target cannot run as it is: {reason}") from None
    first = points[0] if points else {}
    for k, axis in enumerate(axes, start=1):
        value = first.get(axis.name)
        try:
            evaluate.check({axis.name: value})
        except (*errors, KeyError) as error:
            reason = re.sub(r"^\S+?:\d+: ", "", str(error).strip("'\""))
            raise doc.fail(f"axis[{k}].key", f"with the value {value!r}: {reason}", axis.name) from None
