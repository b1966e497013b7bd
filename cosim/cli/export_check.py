"""`cosim export-check SYSTEM.ssp`: the step each other tool gets for any SSP system (one of ours,
a user's own, a peer's demo), measured as `cosim export` measures a scene's: each tool's master
(cosim.engine.tools) run in our engine at the system's step and each half of it, against the
system's own coupling at a 16th of its step, every recorded output within 2 % of its own range;
the table printed and, unless --dry-run, the steps written into the archive where each tool takes
them."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.errors import UsageError


def add(commands) -> argparse.ArgumentParser:
    check = commands.add_parser("export-check", help="measure the step each other tool gets for an SSP system and "
                                "write it into the archive")
    check.add_argument("system", type=Path, help="an SSP 1.0 archive (.ssp)")
    check.add_argument("--dry-run", action="store_true", help="print the table, leave the archive as it is")
    return check


def main(args: argparse.Namespace) -> int:
    from ..engine.outcome import RunStopped
    from ..engine.ssp import read_ssp, write_tool_steps
    from ..engine.tools import FIT_TOLERANCE, FLOOR, SYSTEM_HEADER, TOOL_MASTERS, check_system, fmi3_lines, system_row
    from .common import unwritable
    if args.system.suffix.lower() != ".ssp":
        raise UsageError(f"export-check {args.system}: an SSP archive (.ssp) is needed")
    if not args.dry_run and (problem := unwritable(args.system.parent)):
        raise UsageError(f"export-check {args.system}: {problem}")
    structure = read_ssp(args.system)
    try:
        duration, steps = check_system(structure)
    except RunStopped as failure:
        print(f"error: {args.system}: the system's own coupling at a 16th of its step did not run through the "
              f"probe, so nothing can be measured against it: {failure}")
        return 1
    print(f"the step each tool gets, measured by its master in our engine over the first {duration:g} s against "
          f"the system's own coupling at a 16th of its step ({structure.experiment.step:g} s; every recorded output "
          f"within {FIT_TOLERANCE:.0%} of its own range), halving down to 1/{FLOOR}:")
    print("\n".join([*SYSTEM_HEADER, *(system_row(s) for s in steps)]))
    if len(steps) < len(TOOL_MASTERS):  # a system of FMI 3.0 FMUs
        print("\n".join(fmi3_lines()))
    if not args.dry_run:
        write_tool_steps(args.system, [(s.master.tool, s.step, s.within) for s in steps], structure.experiment.step)
        print(f"written: the steps into {args.system} (OMSimulator's system annotation, the OSP annotation's base "
              f"step, each tool's cosim:ToolStep)")
    return 0
