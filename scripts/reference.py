"""Writes docs/reference/: the reference of every key of the files a user writes and of the run
settings, generated from their schemas, and of the command line, generated from its parsers.

    .venv/bin/python scripts/reference.py          rewrite the pages
    .venv/bin/python scripts/reference.py --check  exit 1 if a page differs from what it generates

tests/test_reference.py holds the pages equal to what this writes."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "docs" / "reference"


def pages() -> dict[str, str]:
    """Page name -> its Markdown."""
    from cosim.cli import parser, subcommands
    from cosim.engine.schema import reference
    from cosim.engine.settings import SCHEMA as SETTINGS
    from cosim.engine.sweep.file import schema as sweep_schema
    from cosim.platform.run.sweep import TARGETS
    from cosim.platform.design.spec.schema import SCHEMA as STUDY
    from cosim.platform.scene.schema import SCHEMA as SCENE
    reports = ["## What a point reports", "", "`[report] values` names these, per target (the row also has "
               "the point's axes, `status` and `message`):", ""]
    for kind, target in TARGETS.items():
        reports += [f"### {kind}", "", "| report | meaning |", "|---|---|"]
        reports += [f"| `{name}` | " + what.replace("|", "\\|")
                    + (" (internal: advise and the trade ask for it)" if name in target.internal else "")
                    + (" (by default)" if name in target.default_reports else "") + " |"
                    for name, what in target.reports.items()]
        reports.append("")
    out = {"scene.md": reference(SCENE, "Scene files"), "study.md": reference(STUDY, "Design studies"),
           "settings.md": reference(SETTINGS, "Run settings"),
           "sweep.md": reference(sweep_schema(TARGETS), "Sweep files") + "\n" + "\n".join(reports).rstrip() + "\n"}
    top = parser()
    lines = ["# The command line", "", "<!-- generated from the parsers by scripts/reference.py; do not edit -->", "",
             "`cosim COMMAND ...` (or `python -m cosim COMMAND ...`); exit codes: 0 done, 1 a run that stopped part "
             "way (its partial results written), 2 a mistake in the input (one line), 3 a bug in cosim (a "
             "traceback), 130 interrupted.", ""]
    for name, sub in subcommands(top).items():
        sub.prog = f"cosim {name}"
        lines += [f"## cosim {name}", "", "```text", sub.format_help().rstrip(), "```", ""]
    out["cli.md"] = "\n".join(lines).rstrip() + "\n"
    return out


def main() -> int:
    check = "--check" in sys.argv[1:]
    stale = []
    for name, text in pages().items():
        path = FOLDER / name
        if check:
            if not path.is_file() or path.read_text() != text:
                stale.append(str(path.relative_to(ROOT)))
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
    if stale:
        print(f"out of date (run `.venv/bin/python scripts/reference.py`): {', '.join(stale)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
