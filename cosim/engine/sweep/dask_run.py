"""Running a sweep's points: grouped into tasks, in this process or on Dask (a LocalCluster, or a
running scheduler), each task's rows written to the results table as it ends."""

from __future__ import annotations

import math
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

from ..errors import InputError
from ..cache import cache_dir
from .bundle import Bundle
from .points import SweepError, Value, column_name, point_key
from .table import ResultTable


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


def evaluate_placed(evaluate, points: Sequence[tuple[str, dict]], bundle: Bundle,
                    blobs: Mapping[str, bytes]) -> list[dict]:
    """A task on a worker: the sweep's files placed in its cache by content (cosim.engine.sweep.
    bundle), the evaluator pointed at them, then the points run."""
    import dataclasses
    return evaluate_task(dataclasses.replace(evaluate, path=str(bundle.place(blobs))), points)


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
    from ..observers import TaskProgress
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
    from distributed import KilledWorker, as_completed
    begin = time.perf_counter()
    with dask.config.set({"distributed.scheduler.allowed-failures": retries}), \
            dask_client(workers, scheduler, dashboard=True, stream=stream) as client:
        dashboard = client.dashboard_link if _has_dashboard(client) else None
        n_workers = max(len(client.scheduler_info()["workers"]), 1)
        startup = time.perf_counter() - begin
        print(f"{name}: {len(todo)} points on {n_workers} Dask workers"
              + (f"; dashboard {dashboard}" if dashboard else ""), file=stream, flush=True)
        size = points_per_task or task_size(len(todo), n_workers)
        # the target and the files it refers to travel by content, once to each worker
        files = evaluate.files([v for _, v in todo]) if hasattr(evaluate, "files") else None
        if files is not None:
            if scheduler is None:
                cache_dir()  # a local cluster's workers share this user's cache: refused here if not private
            bundle, blobs = Bundle.of(Path(evaluate.path), files)
            shipped = client.scatter(blobs, broadcast=True, hash=True)
        tasks = {}
        for start in range(0, len(todo), size):
            chunk = todo[start:start + size]
            key = f"{name}-{chunk[0][0]}"
            future = client.submit(evaluate_task, evaluate, chunk, pure=False, key=key) if files is None else \
                client.submit(evaluate_placed, evaluate, chunk, bundle, shipped, pure=False, key=key)
            tasks[future] = chunk
        for future in as_completed(list(tasks)):
            try:
                rows = future.result()
            except KilledWorker:
                rows = [{"point": k, "status": "failed", "wall": float("nan"),
                         "message": f"its worker died each of the {retries + 1} times the task ran (Dask's "
                                    "allowed-failures); the points of this task were not evaluated"}
                        for k, _ in tasks[future]]
            except Exception as error:  # the task itself could not run (e.g. unpicklable, an untrusted cache)
                text = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
                rows = [{"point": k, "status": "failed", "wall": float("nan"),
                         "message": f"the task failed on the worker: {text}" if isinstance(error, InputError)
                         else f"the task failed on the worker: {type(error).__name__}: {text}"}
                        for k, _ in tasks[future]]
            complete(rows)
        return dashboard, startup


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None, dashboard: bool = False,
                stream=None):
    """A Dask client of a LocalCluster of `workers` processes (None: one per core), one thread each,
    or of a running scheduler at `scheduler`, with Dask's security settings (its configuration:
    distributed.comm.tls.*, which the command line's --tls-* options set). A local cluster's
    processes start with Ctrl-C ignored, so an interrupt is the client's alone (one line). A scheduler
    beyond this machine on an unencrypted address is named as such on `stream` first. The local
    cluster is closed on leaving."""
    import logging
    from distributed import Client, LocalCluster
    stream = stream or sys.stderr
    cluster = None
    if scheduler is None:
        with _interrupts_ignored():  # inherited by every process of the cluster
            # the cluster's own logs only when critical: a worker whose heartbeat races the scheduler's
            # closing logs a traceback at ERROR (CI's fuzz stage saw one), and a task's own failure
            # reaches the client as its exception anyway
            cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0" if dashboard else None,
                                   silence_logs=logging.CRITICAL)
    else:
        exposure = unprotected(scheduler)
        if exposure:
            print(f"warning: {exposure}", file=stream, flush=True)
    try:
        client = Client(cluster if cluster is not None else scheduler, timeout="20s")
    except (OSError, ValueError, TypeError) as error:
        if cluster is not None:
            cluster.close()
        hint = "; its certificates: --tls-ca-file, --tls-cert, --tls-key or Dask's distributed.comm.tls settings" \
            if str(scheduler).startswith("tls://") else ""
        raise SweepError(f"cannot reach the Dask scheduler at {scheduler}: {str(error).splitlines()[0]}{hint}") \
            from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@contextmanager
def _interrupts_ignored():
    """SIGINT ignored while child processes start (they keep it ignored), then restored here."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def unprotected(address: str) -> str | None:
    """What is exposed when a sweep goes to the scheduler at `address`: None for an encrypted one
    (tls://) or one on this machine; otherwise one line saying that the sweep's files and results
    travel unencrypted and anyone who reaches the scheduler can submit work to its workers."""
    protocol, _, rest = address.partition("://") if "://" in address else ("tcp", "", address)
    if protocol in ("tls", "inproc"):
        return None
    host = rest.rsplit(":", 1)[0].strip("[]")
    if _on_this_machine(host):
        return None
    return (f"the Dask scheduler {address} is not on this machine and its connection is neither encrypted nor "
            "authenticated: the sweep's files and results cross the network in the clear, and anyone who reaches "
            "it can run code on its workers; use tls:// with certificates (docs/guide/sweeps.md)")


def _on_this_machine(host: str) -> bool:
    import ipaddress
    import socket
    if host in ("localhost", "") or host == socket.gethostname():
        return True
    try:
        addresses = {info[4][0] for info in socket.getaddrinfo(host, None)}
    except OSError:
        return False
    local = {"127.0.0.1", "::1"}
    try:
        local |= {info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None)}
    except OSError:
        pass
    return all(ipaddress.ip_address(a.split("%")[0]).is_loopback or a in local for a in addresses)


def _has_dashboard(client) -> bool:
    try:
        import bokeh  # noqa: F401  (Dask serves its dashboard only with bokeh)
        return True
    except ImportError:
        return False
