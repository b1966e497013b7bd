"""Observers of an execution: they record, monitor and report, and never advance the system.

Each gets `start(execution)` once, then `batch(execution, batch)` after every kernel call with the
rows and bond energies of the steps just taken (cosim.engine.kernel.Batch). An observer that wants
the run stopped sets `stop` to an exception; the execution raises it with the results so far.
"""

from __future__ import annotations

import math
import sys
import time
from typing import TYPE_CHECKING, Sequence

import numpy as np

if TYPE_CHECKING:
    from .execution import Execution
    from .kernel import Batch


class Observer:
    stop: Exception | None = None

    def start(self, execution: "Execution") -> None:
        pass

    def batch(self, execution: "Execution", batch: "Batch") -> None:
        pass

    def finish(self, execution: "Execution") -> None:
        """After the run, whether it finished or failed."""


class RecordFull(RuntimeError):
    """The record reached its memory budget (an adaptive step that collapsed, a run too long for
    this machine): stopped at `time` with the rows so far."""

    def __init__(self, message: str, time: float):
        super().__init__(message)
        self.time = time


class Recorder(Observer):
    """Every accepted step's row (time and the recorded columns) into fmpy's result convention: a
    numpy structured array with `time` and one named float column per recorded variable. Past
    `budget` bytes of rows it stops the run (RecordFull) and keeps what it has."""

    def __init__(self, names: Sequence[str], budget: float = math.inf):
        if len(set(names)) != len(names):
            raise ValueError(f"recorded column names must be unique: {list(names)}")
        self.names, self.budget = list(names), budget
        self.dtype = np.dtype([(name, "<f8") for name in self.names])
        self._parts: list[np.ndarray] = []
        self.rows = 0

    def add(self, rows: np.ndarray) -> None:
        self._parts.append(np.array(rows, dtype=float, ndmin=2))
        self.rows += len(self._parts[-1])

    def batch(self, execution: "Execution", batch: "Batch") -> None:
        self.add(batch.rows)
        size = 8.0 * self.rows * len(self.names)
        if size > self.budget and self.stop is None and len(batch.rows):
            self.stop = RecordFull(
                f"the run stopped at t = {batch.rows[-1, 0]:.6g} s: its record reached {self.rows:.3g} rows of "
                f"{len(self.names)} columns ({size / 2 ** 30:.3g} GiB), half of this machine's memory; an adaptive "
                "step that shrank to its minimum does this: raise the minimum step, shorten the run or record "
                "fewer outputs", batch.rows[-1, 0])

    def result(self) -> np.ndarray:
        rows = np.ascontiguousarray(np.concatenate(self._parts) if self._parts else np.zeros((0, len(self.names))))
        return rows.view(self.dtype).reshape(len(rows))


class Progress(Observer):
    """A bar on a terminal once a run takes longer than `after` seconds; otherwise a line every
    `every` seconds (log files and CI)."""

    def __init__(self, label: str = "run", after: float = 1.0, every: float = 5.0, stream=None):
        self.label, self.after, self.every = label, after, every
        self.stream = stream or sys.stderr
        self._shown = False

    def start(self, execution: "Execution") -> None:
        self._start = self._last = time.perf_counter()
        self._t0, self._t1 = execution.start_time, execution.stop_time

    def batch(self, execution: "Execution", batch: "Batch") -> None:
        if not len(batch.rows):
            return
        now = time.perf_counter()
        fraction = min(1.0, (batch.rows[-1, 0] - self._t0) / max(self._t1 - self._t0, 1e-300))
        if self.stream.isatty():
            if now - self._start > self.after:
                done = int(40 * fraction)
                print(f"\r{self.label} [{'#' * done}{'.' * (40 - done)}] {100 * fraction:3.0f} %", end="",
                      file=self.stream, flush=True)
                self._shown = True
        elif now - self._last > self.every:
            self._last = now
            print(f"{self.label}: {100 * fraction:.0f} % (t = {batch.rows[-1, 0]:.4g} s, {now - self._start:.0f} s wall)",
                  file=self.stream, flush=True)

    def finish(self, execution: "Execution") -> None:
        if self._shown:
            print(file=self.stream, flush=True)
            self._shown = False


class Diverged(RuntimeError):
    """The coupling diverged: the message says when, how much, at which bond, and what to try."""

    def __init__(self, message: str, time: float):
        super().__init__(message)
        self.time = time


class DivergenceMonitor(Observer):
    """Watches a run for a diverging coupling. Over each window of macro steps it compares the power
    bonds' energy residual (energy created or lost by the coupling) with the energy the bonds
    carried. A stable coupling stays far below a percent (the Meng scene at 1 ms: 0.1 %); one that
    oscillates at the macro step's Nyquist frequency or grows is at 10 % and more (the Meng scene
    at 2 ms: 10-20 %, its torques chattering at the current limit while the pose still looks
    right). `ratio` is the threshold, `windows` how many windows in a row must exceed it.
    Strategy-independent: it only sees per-step, per-bond energies."""

    def __init__(self, ratio: float = 0.05, window: int = 50, windows: int = 2, floor: float = 1e-6):
        self.window, self.ratio, self.windows = window, ratio, windows
        self.floor = floor  # [J] per window: below it nothing is carried and nothing is judged
        self._count = 0
        self._exceeded = 0
        self.ratios: list[float] = []  # per completed window
        self.message: str | None = None
        self.time: float | None = None

    def start(self, execution: "Execution") -> None:
        self.bond_names, self.step = execution.bond_names, execution.control.step
        self._residual = np.zeros(len(self.bond_names))
        self._transferred = np.zeros(len(self.bond_names))
        self.active = execution.control_name == "fixed" and bool(self.bond_names)

    def batch(self, execution: "Execution", batch: "Batch") -> None:
        if self.active:
            self.add_batch(batch.rows[:, 0], batch.bond_energy)
            if self.message and self.stop is None:
                self.stop = Diverged(self.message, self.time)

    def add_batch(self, times: np.ndarray, bond_energy: np.ndarray) -> None:
        """Steps ending at times (n), bond_energy (n x bonds x (residual, transferred)), summed
        window by window with numpy (this runs once per batch of the native loop)."""
        residual, transferred = np.abs(bond_energy[:, :, 0]), bond_energy[:, :, 1]
        i = 0
        while i < len(times) and self.message is None:
            take = min(self.window - self._count, len(times) - i)
            self._residual += residual[i:i + take].sum(axis=0)
            self._transferred += transferred[i:i + take].sum(axis=0)
            self._count += take
            i += take
            if self._count == self.window:
                self._close_window(float(times[i - 1]))

    def _close_window(self, t: float) -> None:
        carried = float(self._transferred.sum())
        ratio = float(self._residual.sum()) / max(carried, self.floor) if carried > self.floor else 0.0
        self.ratios.append(ratio)
        self._exceeded = self._exceeded + 1 if ratio > self.ratio else 0
        if self._exceeded >= self.windows and self.message is None:
            worst = int(np.argmax(self._residual))
            start = max(0.0, t - self.windows * self.window * self.step)
            self.time = start
            self.message = (
                f"the coupling diverged from about t = {start:.3f} s: over the last {self.window} macro steps the "
                f"power bonds' energy residual was {100 * ratio:.0f} % of the energy they carried (a stable coupling "
                f"stays under 1 %), worst at {self.bond_names[worst]}: the macro step {self.step * 1e3:g} ms is too "
                f"large for this system")
        self._residual[:] = 0.0
        self._transferred[:] = 0.0
        self._count = 0


class TaskProgress:
    """Progress over a known number of tasks (probes of a study, points of a sweep, sections of a
    report): a bar with the failures and the estimated time left on a terminal, otherwise a line
    every `every` seconds and one at the end."""

    def __init__(self, label: str, total: int | None, every: float = 5.0, stream=None):
        """total: the number of tasks, or None when it is not known beforehand (then a count)."""
        self.label, self.total, self.every = label, total, every
        self.stream = stream or sys.stderr
        self.done = self.failed = 0
        self._start = self._last = time.perf_counter()

    def _left(self, now: float) -> str:
        if not self.done or self.done >= self.total:
            return ""
        return f", about {(now - self._start) / self.done * (self.total - self.done):.0f} s left"

    def advance(self, what: str = "", count: int = 1, failed: int = 0) -> None:
        """`count` more tasks done, `failed` of them failed."""
        self.done += count
        self.failed += failed
        now = time.perf_counter()
        terminal = self.stream.isatty()
        if self.total is None:
            if now - self._last >= self.every or terminal:
                self._last = now
                print(f"{chr(13) if terminal else ''}{self.label}: {self.done} done ({what[:40]}), "
                      f"{now - self._start:.0f} s", end="" if terminal else "\n", file=self.stream, flush=True)
            return
        failures = f", {self.failed} failed" if self.failed else ""
        if terminal:
            filled = int(30 * self.done / max(self.total, 1))
            print(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total}{failures}"
                  f"{self._left(now)} {what[:30]:<30}", end="" if self.done < self.total else "\n", file=self.stream,
                  flush=True)
        elif now - self._last >= self.every or self.done >= self.total:
            self._last = now
            print(f"{self.label}: {self.done}/{self.total} done{failures}{f' ({what})' if what else ''}, "
                  f"{now - self._start:.0f} s"
                  f"{self._left(now)}", file=self.stream, flush=True)

    def finish(self, what: str = "") -> None:
        """The tasks ended: before `total` (a search that converged early), says so; a count's or a
        bar's line on a terminal ended."""
        if self.total is None:  # a count: its line ended on a terminal
            if self.stream.isatty() and self.done:
                print(file=self.stream, flush=True)
            return
        if self.done >= self.total:
            return
        end_bar = "\n" if self.stream.isatty() and self.done else ""
        print(f"{end_bar}{self.label}: {self.done} done{f' ({what})' if what else ''}, fewer than the most "
              f"({self.total}): converged, {time.perf_counter() - self._start:.0f} s", file=self.stream, flush=True)
