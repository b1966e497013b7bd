"""`cosim validate`: the validation report against the papers, rebuilt (docs/validation.md and its
figures in a checkout)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.artifacts import INSTALLED, ROOT


def add(commands) -> argparse.ArgumentParser:
    validate = commands.add_parser("validate", help="rebuild the validation report against the papers")
    validate.add_argument("--out", type=Path, default=Path("out") if INSTALLED else ROOT / "docs",
                          help="folder of validation.md and figures/ (default: a checkout's docs/; out/ for an "
                          "installed wheel, whose files are not to be written)")
    return validate


def main(args: argparse.Namespace) -> int:
    from ..platform.validation.report import build
    print(f"written: {build(args.out)}")
    return 0
