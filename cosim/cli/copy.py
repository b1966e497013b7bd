"""`cosim copy NAME`: a shipped scene, sweep file or design study copied here to edit (no name:
the shipped ones listed)."""

from __future__ import annotations

import argparse
import difflib
from pathlib import Path

from ..engine.errors import UsageError
from ..engine.files import write_bytes
from .common import unwritable


def add(commands) -> argparse.ArgumentParser:
    copy = commands.add_parser("copy", help="copy a shipped scene, sweep file or study here to edit (no name: "
                               "list them)")
    copy.add_argument("name", nargs="?", help="a shipped scene's, sweep file's or study's name, e.g. meng_eq35")
    copy.add_argument("--to", type=Path, default=Path("."), help="the folder to copy into (default: this one)")
    return copy


def main(args: argparse.Namespace) -> int:
    """Copies a shipped file into --to (never over a file), or lists them."""
    from ..platform.scene import shipped, shipped_scenes
    kinds = {folder: shipped_scenes(folder) for folder in ("scenes", "sweeps", "studies")}
    if args.name is None:
        for folder, names in kinds.items():
            print(f"{folder}: {', '.join(names)}")
        return 0
    source = next((found for folder in kinds if (found := shipped(args.name, folder))), None)
    if source is None:
        near = difflib.get_close_matches(args.name, [n for names in kinds.values() for n in names], 1)
        raise UsageError(f"{args.name!r} is not a shipped scene, sweep file or study"
                         + (f" (did you mean {near[0]!r}?)" if near else " (`cosim copy` lists them)"))
    target = args.to / source.name
    if target.exists():
        raise UsageError(f"{target} exists; copy elsewhere with --to")
    if problem := unwritable(args.to):
        raise UsageError(f"--to {args.to}: {problem}")
    write_bytes(target, source.read_bytes(), "the copy")
    command = {"sweeps": "sweep", "studies": "design"}.get(source.parent.name, "run")
    print(f"copied: {target} (from {source}); run it with `cosim {command} {target}`")
    return 0
