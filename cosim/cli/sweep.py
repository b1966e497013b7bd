"""`cosim sweep SWEEP.toml`: a scene or SSP system run at many points on Dask, its rows written as
Parquet and CSV (and a plot), a sweep interrupted resumed where it stopped."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import add_cluster, security, workers


def add(commands) -> argparse.ArgumentParser:
    sweep = commands.add_parser("sweep", help="run a scene or SSP system at many points, on Dask (docs/guide/sweeps.md)")
    sweep.add_argument("sweep", type=Path, help="the sweep file (TOML)")
    add_cluster(sweep, "the points", None)
    sweep.add_argument("--out", type=Path, default=Path("out"), help="folder for <sweep>.parquet, .csv and .png")
    return sweep


SHOWN, MESSAGE = 10, 400  # the points not ok listed, and the characters of each one's message shown


def main(args: argparse.Namespace) -> int:
    from ..engine.sweep import column_name, plot_sweep
    from ..platform.run.sweep import load_sweep
    count = workers(args)
    sweep = load_sweep(args.sweep)
    try:
        with security(args):
            outcome = sweep.run(args.out, count, args.scheduler)
    except KeyboardInterrupt:
        print(f"interrupted: the points finished so far are in {args.out}/{args.sweep.stem}.parts; run the same "
              "command again to run only the others", file=sys.stderr)
        return 130
    kinds = {s: sum(r["status"] == s for r in outcome.rows) for s in ("ok", "diverged", "failed")}
    print(f"{sweep.name}: {len(outcome.rows)} points ({outcome.ran} run now, {outcome.skipped} found done): "
          + ", ".join(f"{n} {s}" for s, n in kinds.items() if n))
    import textwrap
    unfinished = [r for r in outcome.rows if r["status"] != "ok"]
    shown = unfinished if len(unfinished) <= SHOWN + 2 else unfinished[:SHOWN]  # never "1 more" for one line
    for row in shown:  # each message whole, or cut at a word with "..." past MESSAGE characters
        print(f"  {row['status']}: {', '.join(f'{a.name}={row[column_name(a.name)]!r}' for a in sweep.axes)}: "
              f"{textwrap.shorten(str(row['message']), MESSAGE, placeholder=' ...')}")
    if len(shown) < len(unfinished):
        print(f"  ... and {len(unfinished) - len(shown)} more not ok, each with its whole message in the results "
              "table")
    written = [*outcome.files]
    if sweep.plot is not None:
        written.append(plot_sweep(outcome.rows, sweep.plot, args.out / f"{sweep.name}.png", sweep.name, sweep.units))
    print("results: " + ", ".join(str(f) for f in written))
    return 0
