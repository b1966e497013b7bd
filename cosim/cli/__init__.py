"""The command line, `cosim` (or `python -m cosim`): one module per command, each adding its own
parser (`add`) and running it (`main`); this module builds the parser from them, prints the usage
of every command (generated from their parsers) and turns what a command raises into its exit
code:

- 0: done; 1: a run that stopped part way (its report, and its partial results written);
- 2: a mistake in the input (an InputError, or an install without its data): one line, `error: ...`;
- 3: a bug in this program: its traceback and a line that says so; 130: interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
from pathlib import Path

from ..engine.artifacts import ArtifactMissing
from ..engine.errors import InputError, UsageError
from . import advise, compare, copy, design, export, run, stream, sweep, tune, validate, view
from .export import export_check
from .common import unwritable

COMMANDS = (run, compare, export, export_check, view, validate, advise, sweep, design, tune, copy, stream)


def parser() -> argparse.ArgumentParser:
    """The whole command line: a sub-parser per command, each from its module; `cosim --help`
    ends with every command's usage, generated from them."""
    prog = "cosim" if Path(sys.argv[0]).name == "cosim" else "python -m cosim"  # the console script, or -m
    top = argparse.ArgumentParser(prog=prog, description="Stewart platform co-simulation",
                                  formatter_class=argparse.RawDescriptionHelpFormatter)
    top.add_argument("--version", action=Version, nargs=0, help="print the version and exit")
    commands = top.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add(commands).set_defaults(main=command.main)
    top.epilog = "usage of each command:\n" + "\n".join(
        "  " + " ".join(sub.format_usage().split())[len("usage: "):] for sub in subcommands(top).values())
    return top


class Version(argparse.Action):
    """--version, its metadata read only when asked (importlib.metadata loads email and socket)."""

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"{parser.prog} {version()}")
        parser.exit()


def version() -> str:
    """The installed package's version (its metadata: pyproject.toml's), 'unknown' where it is not
    installed."""
    from importlib.metadata import PackageNotFoundError, version as installed
    try:
        return installed("stewart-cosim")
    except PackageNotFoundError:
        return "unknown (not installed)"


def subcommands(top: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """Each command's parser by its name."""
    return next(a.choices for a in top._actions if isinstance(a, argparse._SubParsersAction))


def main(argv: list[str] | None = None) -> int:
    """Runs one command; returns its exit code (see the module's docstring)."""
    try:
        args = parser().parse_args(argv)
        out = getattr(args, "out", None)
        if out is not None and (problem := unwritable(out)):
            raise UsageError(f"--out {out}: {problem}")
        code = args.main(args)
        sys.stdout.flush()  # here, where a closed pipe can still be told apart
        return code
    except BrokenPipeError:  # the reader of the output went away (`cosim run ... | head -1`): as `cat` does
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (InputError, ArtifactMissing) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception:  # anything else is ours to fix, not the user's
        traceback.print_exc()
        print("internal error: the traceback above is a bug in cosim, not a mistake in your input; please "
              "report it with the command you ran", file=sys.stderr)
        return 3


def main_exit() -> None:
    """The `cosim` console script: the same command line as `python -m cosim`."""
    sys.exit(main())
