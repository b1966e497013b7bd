"""Sweeps: many runs of one system, each a point of named values, spread over Dask workers.

A sweep is a list of points (`grid`, `zipped` or `latin_hypercube` over `Axis`es) and an
evaluator: a picklable callable that runs one point and returns its report as a flat dict. The
engine knows nothing of what a point means; `cosim.platform.sweep` evaluates scene points and
`SystemPoint` below evaluates points of any SSP system.

`run_sweep` runs the points on `dask.distributed` (a `LocalCluster` with one single-threaded worker
process per core by default, or an existing scheduler by address), `workers=0` in this process.
Points are grouped into tasks so that short points do not each pay a task's overhead; a worker
loads each FMU once (cosim.engine.fmi.loaded), not once per point. Nothing is lost: a point that
fails is a row with its message; rows are written as their task ends (a Parquet part file each,
renamed into place whole, and a CSV line each); a sweep started again with the same output skips
the points it has; a task whose worker dies is retried on another worker up to `retries` times
(Dask's `distributed.scheduler.allowed-failures`), after which its points are rows that say so.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

Value = Any
STATUS = ("ok", "diverged", "failed")


class SweepError(ValueError):
    """A sweep that cannot start (its file, its output folder): one line."""


# -- points ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Axis:
    """One swept value: `values` (a list, or a linspace or geomspace expanded by the file's
    reader) for a grid or zipped sweep; `between` (low, high) for a Latin-hypercube sample."""
    name: str
    values: tuple = ()
    between: tuple[float, float] | None = None
    line: int = 0  # where the sweep file defines it (0: not from a file)


def grid(axes: Sequence[Axis]) -> list[dict[str, Value]]:
    """Every combination of the axes' values, the last axis varying fastest."""
    return [dict(zip((a.name for a in axes), combo)) for combo in itertools.product(*(a.values for a in axes))]


def zipped(axes: Sequence[Axis]) -> list[dict[str, Value]]:
    """The i-th values of every axis together (all axes the same length)."""
    lengths = {len(a.values) for a in axes}
    if len(lengths) > 1:
        raise SweepError(f"a zipped sweep needs axes of one length, these have {sorted(lengths)}")
    return [dict(zip((a.name for a in axes), combo)) for combo in zip(*(a.values for a in axes))]


def latin_hypercube(axes: Sequence[Axis], points: int, seed: int) -> list[dict[str, Value]]:
    """`points` points whose every axis hits each of `points` equal strata of its range once
    (scipy.stats.qmc.LatinHypercube, reproducible by `seed`). An axis with values instead of a
    range picks among them by stratum."""
    from scipy.stats import qmc
    unit = qmc.LatinHypercube(d=len(axes), seed=seed).random(points)
    out = []
    for row in unit:
        point = {}
        for a, u in zip(axes, row):
            if a.between is not None:
                low, high = a.between
                point[a.name] = float(low + u * (high - low))
            else:
                point[a.name] = a.values[min(int(u * len(a.values)), len(a.values) - 1)]
        out.append(point)
    return out


def column_name(key: str) -> str:
    """A point's name as a table column: the key without quotes ('a."b.c"' -> a.b.c)."""
    return key.replace('"', "").replace("'", "")


def point_key(values: Mapping[str, Value]) -> str:
    """A point's identity: a hash of its values (names sorted; floats by their exact repr)."""
    text = json.dumps({k: repr(v) if isinstance(v, float) else v for k, v in sorted(values.items())}, sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


# -- evaluating points ----------------------------------------------------------------------------

def statistics(result: np.ndarray, wanted: Mapping[str, Sequence[str]]) -> dict[str, float]:
    """Statistics of recorded columns over the whole run: max, min, max_abs, mean, rms, final."""
    functions = {"max": np.max, "min": np.min, "max_abs": lambda v: np.max(np.abs(v)), "mean": np.mean,
                 "rms": lambda v: np.sqrt(np.mean(np.square(v))), "final": lambda v: v[-1]}
    out = {}
    for column, stats in wanted.items():
        for stat in stats:
            values = result[column] if len(result) else np.array([np.nan])
            out[f"{stat}.{column}"] = float(functions[stat](values))
    return out


STATISTICS = ("max", "min", "max_abs", "mean", "rms", "final")


@dataclass(frozen=True)
class SystemPoint:
    """Evaluates a point of an SSP system: names without a dot are the engine's settings
    (algorithm, order, step, ...: cosim.engine.settings), `component.parameter` a parameter value.
    Reports: steps, rejected, energy_residual, real_time_factor and the statistics asked for."""
    path: str
    stop_time: float | None = None
    outputs: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def columns(self) -> list[str]:
        return ["steps", "rejected", "energy_residual", "real_time_factor",
                *[f"{s}.{c}" for c, stats in self.outputs for s in stats]]

    def structure(self):
        from .ssp import read_ssp
        return read_ssp(Path(self.path))

    def recorded(self) -> list[str]:
        """The columns a run records (what `outputs` may name)."""
        from .command import recording
        return ["time", *recording(self.structure())[1]]

    def check(self, values: Mapping[str, Value]) -> None:
        """Raises ValueError (one line) when a point's names or values cannot run."""
        from .checks import check_parameters
        from .settings import system_settings
        structure = self._with(self.structure(), values)
        system_settings(structure.settings, structure.experiment.step, self._settings(values))
        check_parameters(structure)

    @staticmethod
    def _settings(values: Mapping[str, Value]) -> dict[str, str]:
        # a sweep keeps every core busy with points: each steps on one thread unless an axis says
        return {"threads": "1", **{k: str(v) for k, v in values.items() if "." not in k}}

    @staticmethod
    def _with(structure, values: Mapping[str, Value]):
        from .structure import with_parameters
        names = {c.name for c in structure.components}
        parameters: dict[str, dict] = {}
        for key, value in values.items():
            if "." in key:
                component, variable = key.split(".", 1)
                if component not in names:
                    raise ValueError(f"{key!r}: no component {component!r} (components: {', '.join(sorted(names))})")
                parameters.setdefault(component, {})[variable] = value
        return with_parameters(structure, parameters)

    def __call__(self, values: Mapping[str, Value]) -> dict[str, Value]:
        from .command import run_structure
        from .outcome import RunStopped
        structure = self._with(self.structure(), values)
        try:
            result, report = run_structure(structure, self._settings(values), self.stop_time, progress=False,
                                           advice=False)
            status, message = "ok", ""
        except RunStopped as failed:
            result, report = failed.result, failed.report
            status, message = ("diverged" if failed.diverged else "failed"), str(failed)
        numbers = report.row()
        row = {key: numbers[key] for key in ("steps", "rejected", "energy_residual", "real_time_factor")}
        return {**row, **statistics(result, dict(self.outputs)), "status": status, "message": message}


def evaluate_task(evaluate: Callable[[Mapping[str, Value]], dict], points: Sequence[tuple[str, dict]]) -> list[dict]:
    """Runs a task's points one after another; whatever a point raises is its row's message."""
    rows = []
    for key, values in points:
        start = time.perf_counter()
        try:
            row = dict(evaluate(values))
        except Exception as error:  # a point's failure is its row, never the sweep's end
            text = str(error).strip().splitlines()[0] if str(error).strip() else ""
            user = isinstance(error, (ValueError, RuntimeError))  # a value or a run that failed: its own words
            row = {"status": "failed", "message": text if user and text else f"{type(error).__name__}: {text}"}
        row.setdefault("status", "ok")
        row.setdefault("message", "")
        row["point"], row["wall"] = key, time.perf_counter() - start
        rows.append(row)
    return rows


# -- the table ------------------------------------------------------------------------------------

class ResultTable:
    """The sweep's rows on disk: <out>/<name>.parts/part-*.parquet (the source of truth: each
    written whole, then renamed into place), <name>.csv appended as rows arrive, and
    <name>.parquet, the whole table in the points' order, written at the end (and the CSV
    rewritten in that order). `done` holds the keys already there."""

    def __init__(self, out: Path, name: str, axes: Sequence[str], columns: Sequence[str], signature: str):
        import pyarrow as pa
        self.out, self.name = Path(out), name
        self.parts = self.out / f"{name}.parts"
        self.axes = [column_name(a) for a in axes]
        self.columns = ["point", *self.axes, "status", "message", *columns, "wall"]
        self.csv = self.out / f"{name}.csv"
        self.parquet = self.out / f"{name}.parquet"
        self._pa = pa
        self.parts.mkdir(parents=True, exist_ok=True)
        signature_file = self.parts / "signature"
        if signature_file.exists() and signature_file.read_text() != signature:
            raise SweepError(f"{self.parts} holds the results of another sweep (its target, duration, axes' names or "
                             "reports differ): remove the folder or choose another --out")
        signature_file.write_text(signature)
        self.rows = self._read_parts()
        self.done = {row["point"] for row in self.rows}
        self._write_csv(self.rows)  # rebuilt from the parts: a line cut off by an interruption is gone
        self._count = len(list(self.parts.glob("part-*.parquet")))

    def _read_parts(self) -> list[dict]:
        import pyarrow.parquet as pq
        rows = []
        for part in sorted(self.parts.glob("part-*.parquet")):
            rows += pq.read_table(part).to_pylist()
        return rows

    def _write_csv(self, rows: list[dict], append: bool = False) -> None:
        import csv
        with open(self.csv, "a" if append else "w", newline="") as f:
            writer = csv.DictWriter(f, self.columns, extrasaction="ignore")
            if not append:
                writer.writeheader()
            for row in rows:
                writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})

    def _arrow(self, rows: list[dict]):
        pa = self._pa
        fields = []
        for name in self.columns:
            values = [row.get(name) for row in rows]
            known = [v for v in values if v is not None]
            if name in ("point", "status", "message") or any(isinstance(v, str) for v in known):
                kind = pa.string()
                values = [None if v is None else str(v) for v in values]
            elif known and all(isinstance(v, bool) for v in known):
                kind = pa.bool_()
            elif known and len(known) == len(values) and all(
                    isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in known):
                kind = pa.int64()
            else:
                kind = pa.float64()
                values = [float("nan") if v is None else float(v) for v in values]
            fields.append(pa.array(values, type=kind))
        return pa.Table.from_arrays(fields, names=self.columns)

    def add(self, rows: list[dict]) -> None:
        import pyarrow.parquet as pq
        rows = [row for row in rows if row["point"] not in self.done]
        if not rows:
            return
        part = self.parts / f"part-{self._count:06d}.parquet"
        temporary = part.with_suffix(".tmp")
        pq.write_table(self._arrow(rows), temporary)
        os.replace(temporary, part)
        self._count += 1
        self._write_csv(rows, append=True)
        self.rows += rows
        self.done |= {row["point"] for row in rows}

    def finish(self, order: Sequence[str]) -> list[dict]:
        """Writes <name>.parquet and rewrites <name>.csv: the rows of the points `order` names, in
        that order (as they arrived until now); returns them."""
        import pyarrow.parquet as pq
        by_key = {row["point"]: row for row in self.rows}
        rows = [by_key[k] for k in order if k in by_key]
        if rows:
            temporary = self.parquet.with_suffix(".tmp")
            pq.write_table(self._arrow(rows), temporary)
            os.replace(temporary, self.parquet)
        self._write_csv(rows)
        return rows


# -- running --------------------------------------------------------------------------------------

@dataclass
class SweepOutcome:
    rows: list[dict]            # every point's row, in the order of the points
    ran: int                    # points run by this call
    skipped: int                # points found done in the output folder
    failed: int                 # rows whose status is not "ok" (this call's and earlier)
    dashboard: str | None = None
    files: list[Path] = field(default_factory=list)
    wall: float = 0.0           # [s] this call, start to end
    startup: float = 0.0        # [s] of it starting or reaching the cluster


def task_size(points: int, workers: int) -> int:
    """Points per task: about eight tasks per worker, so the last tasks balance the load, and
    never more than 32 points in one task (they are written when the task ends)."""
    return max(1, min(32, math.ceil(points / (8 * max(workers, 1)))))


def run_sweep(name: str, points: Sequence[Mapping[str, Value]], evaluate: Callable, columns: Sequence[str],
              out: Path, signature: str = "", workers: int | None = None, scheduler: str | None = None,
              points_per_task: int | None = None, retries: int = 3, progress: bool = True,
              stream=None) -> SweepOutcome:
    """Runs every point not yet in `out` and returns all rows (see the module's docstring).
    workers: worker processes of a LocalCluster (None: one per core; 0: no Dask, this process);
    scheduler: the address of a running Dask scheduler instead ('tcp://host:8786')."""
    from .observers import TaskProgress
    begin = time.perf_counter()
    stream = stream or sys.stderr
    axes = list(dict.fromkeys(k for p in points for k in p))
    keyed = [(point_key(p), dict(p)) for p in points]
    if len({k for k, _ in keyed}) < len(keyed):
        raise SweepError("the sweep has the same point more than once")
    table = ResultTable(out, name, axes, columns, signature)
    todo = [(k, v) for k, v in keyed if k not in table.done]
    skipped = len(keyed) - len(todo)
    if skipped:
        print(f"{name}: {skipped} of {len(keyed)} points already in {table.parts}, running the other {len(todo)}",
              file=stream)
    values_of = dict(keyed)

    def complete(rows: list[dict]) -> None:
        for row in rows:
            row.update({column_name(a): values_of[row["point"]].get(a) for a in axes})
        table.add(rows)
        if bar is not None:
            bar.advance(count=len(rows),
                        failed=sum(r["status"] != "ok" for r in rows))

    bar = TaskProgress(name, len(todo), stream=stream) if progress and todo else None
    dashboard, startup = None, 0.0
    if todo and workers == 0 and scheduler is None:
        size = points_per_task or task_size(len(todo), 1)
        for start in range(0, len(todo), size):
            complete(evaluate_task(evaluate, todo[start:start + size]))
    elif todo:
        dashboard, startup = _run_on_dask(name, todo, evaluate, complete, workers, scheduler, points_per_task, retries,
                                          stream)
    rows = table.finish([k for k, _ in keyed])
    return SweepOutcome(rows, len(todo), skipped, sum(r["status"] != "ok" for r in rows), dashboard,
                        [table.parquet, table.csv], time.perf_counter() - begin, startup)


def _run_on_dask(name, todo, evaluate, complete, workers, scheduler, points_per_task, retries,
                 stream) -> tuple[str | None, float]:
    """Runs the points on Dask; returns the dashboard's address and the seconds it took to start
    (or reach) the cluster."""
    import dask
    begin = time.perf_counter()
    from distributed import Client, KilledWorker, LocalCluster, as_completed
    with dask.config.set({"distributed.scheduler.allowed-failures": retries}):
        cluster = None
        if scheduler is None:
            import logging
            cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
        try:
            client = Client(cluster if cluster is not None else scheduler, timeout="20s")
        except OSError as error:
            if cluster is not None:
                cluster.close()
            raise SweepError(f"cannot reach the Dask scheduler at {scheduler}: {error}") from None
        try:
            dashboard = client.dashboard_link if _has_dashboard(client) else None
            n_workers = max(len(client.scheduler_info()["workers"]), 1)
            startup = time.perf_counter() - begin
            print(f"{name}: {len(todo)} points on {n_workers} Dask workers"
                  + (f"; dashboard {dashboard}" if dashboard else ""), file=stream, flush=True)
            size = points_per_task or task_size(len(todo), n_workers)
            tasks = {}
            for start in range(0, len(todo), size):
                chunk = todo[start:start + size]
                tasks[client.submit(evaluate_task, evaluate, chunk, pure=False, key=f"{name}-{chunk[0][0]}")] = chunk
            for future in as_completed(list(tasks)):
                try:
                    rows = future.result()
                except KilledWorker:
                    rows = [{"point": k, "status": "failed", "wall": float("nan"),
                             "message": f"its worker died each of the {retries + 1} times the task ran (Dask's "
                                        "allowed-failures); the points of this task were not evaluated"}
                            for k, _ in tasks[future]]
                except Exception as error:  # the task itself could not run (e.g. unpicklable)
                    rows = [{"point": k, "status": "failed", "wall": float("nan"),
                             "message": f"the task failed on the worker: {type(error).__name__}: {error}"}
                            for k, _ in tasks[future]]
                complete(rows)
            return dashboard, startup
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


def _has_dashboard(client) -> bool:
    try:
        import bokeh  # noqa: F401  (Dask serves its dashboard only with bokeh)
        return True
    except ImportError:
        return False
