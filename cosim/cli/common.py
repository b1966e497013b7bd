"""What several commands share: where results may go, a run's outcome as a command reports it."""

from __future__ import annotations

import argparse
import math
import os
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Iterator

from ..engine.errors import UsageError

if TYPE_CHECKING:
    from ..engine.outcome import Report


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


def seconds(option: str, text: str | None, what: str = "must be a positive finite number of seconds") -> float | None:
    """A command line's duration in seconds, or another positive finite number (`what` says what a
    wrong one should have been); None where it gives none."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise UsageError(f"{option} {text}: {what}")
    return value


def add_cluster(parser: argparse.ArgumentParser, what: str, default: int | None, scheduler: bool = True) -> None:
    """--workers (Dask worker processes of a local cluster for `what`; default None: one per core)
    and, with `scheduler`, --scheduler (a running one's address instead)."""
    parser.add_argument("--workers", type=int, default=default, help=f"Dask worker processes for {what} (default: "
                        + ("one per core" if default is None else f"{default}") + "; 0: in this process)")
    if scheduler:
        parser.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tls://host:8786 (tcp:// "
                            "for one on this machine: unencrypted)")
        for option, what in (("--tls-ca-file", "the certificate authority that signed the scheduler's and the "
                              "workers' certificates"), ("--tls-cert", "this client's certificate"),
                             ("--tls-key", "this client's private key")):
            parser.add_argument(option, type=Path, help=f"for a tls:// scheduler: {what} (default: Dask's "
                                "distributed.comm.tls configuration)")


@contextmanager
def security(args: argparse.Namespace) -> Iterator[None]:
    """Dask's TLS settings as the command line gives them (over Dask's own configuration), for
    the command's connections to a scheduler."""
    given = {key: str(value) for key, value in (("distributed.comm.tls.ca-file", args.tls_ca_file),
                                                ("distributed.comm.tls.client.cert", args.tls_cert),
                                                ("distributed.comm.tls.client.key", args.tls_key)) if value}
    for option, value in (("--tls-ca-file", args.tls_ca_file), ("--tls-cert", args.tls_cert),
                          ("--tls-key", args.tls_key)):
        if value is not None and not value.is_file():
            raise UsageError(f"{option} {value}: no such file")
    if given and not str(args.scheduler or "").startswith("tls://"):
        raise UsageError("--tls-ca-file, --tls-cert and --tls-key are for a tls:// scheduler (--scheduler tls://...)")
    import dask
    with dask.config.set(given):
        yield


def workers(args: argparse.Namespace) -> int | None:
    """The command line's number of Dask worker processes (None: one per core, 0: in this process)."""
    if args.workers is not None and args.workers < 0:
        raise UsageError(f"--workers {args.workers}: must be 0 (in this process) or more")
    return args.workers


def report(run: Callable[[], Report], written: str, out: Path) -> int:
    """Runs `run` (which returns a report); prints the report and what was written (exit 0), or a
    stopped run's report with where its partial results went (exit 1)."""
    from ..engine.outcome import RunStopped
    try:
        outcome = run()
    except RunStopped as stopped:
        print(stopped.report.text(), file=sys.stderr)
        print(f"partial results up to t = {stopped.report.simulated:g} s written to {out}/", file=sys.stderr)
        return 1
    print(outcome.text())
    print(f"results: {written}")
    return 0
