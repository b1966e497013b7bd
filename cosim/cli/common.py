"""What several commands share: where results may go, a run's outcome as a command reports it."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from typing import Callable

from ..engine.errors import UsageError
from ..engine.outcome import Report, RunStopped


def unwritable(folder: Path) -> str | None:
    """Why results could not be written into `folder`, or None; checked before a run (nothing is
    created here), so that nothing computed is lost at its end."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"cannot write results there ({existing} is not a folder)"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot write results there ({existing} is not writable)"
    return None


def seconds(option: str, text: str | None) -> float | None:
    """A command line's duration in seconds (None where it gives none)."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise UsageError(f"{option} {text}: must be a positive finite number of seconds")
    return value


def workers(option: str, count: int | None, what: str) -> int | None:
    """A command line's number of Dask worker processes (0: `what`)."""
    if count is not None and count < 0:
        raise UsageError(f"{option} {count}: must be 0 ({what}) or more")
    return count


def report(run: Callable[[], Report], written: str, out: Path) -> int:
    """Runs `run` (which returns a report); prints the report and what was written (exit 0), or a
    stopped run's report with where its partial results went (exit 1)."""
    try:
        outcome = run()
    except RunStopped as stopped:
        print(stopped.report.text(), file=sys.stderr)
        print(f"partial results up to t = {stopped.report.simulated:g} s written to {out}/", file=sys.stderr)
        return 1
    print(outcome.text())
    print(f"results: {written}")
    return 0
