"""docs/guide/getting-started.md as a new user follows it: every `$ cosim ...` command of the page,
in its order, in one empty folder, exits 0 and prints the lines the page shows beneath it (`...`:
more lines there; any number may differ, as the page says), at its start, or, where the page's
output starts with `...`, at its end."""

from __future__ import annotations

import re
import subprocess
import sys

from cosim.engine.artifacts import ROOT

PAGE = ROOT / "docs" / "guide" / "getting-started.md"
NUMBER = re.compile(r"-?\d+(\.\d+)?(e[+-]?\d+)?")


def steps() -> list[tuple[str, list[str]]]:
    """(the command, the lines shown under it) in the page's order."""
    out, command, shown = [], None, []
    for line in PAGE.read_text().splitlines() + [""]:
        if line.startswith("    $ "):
            command, shown = line[6:], []
        elif command is not None and line.startswith("    "):
            shown.append(line[4:])
        elif command is not None:
            out.append((command, shown))
            command = None
    return out


def masked(line: str) -> str:
    return NUMBER.sub("#", line.replace("python -m cosim", "cosim"))


def test_the_page_runs_as_it_says(tmp_path):
    found = steps()
    assert len(found) >= 10 and all(command.startswith("cosim ") for command, _ in found)
    for command, shown in found:
        arguments = [a.replace("examples/", f"{ROOT}/examples/") for a in command.split()[1:]]
        done = subprocess.run([sys.executable, "-m", "cosim", *arguments], cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, (command, done.stderr[-2000:])
        printed = [masked(line) for line in done.stdout.splitlines()]
        expected = [masked(line) for line in shown]
        if expected and expected[0] == "...":
            tail = expected[1:]
            assert printed[-len(tail):] == tail, (command, printed[-len(tail):], tail)
        else:
            head = expected[:expected.index("...")] if "..." in expected else expected
            for want, got in zip(head, printed):  # the copy's path: the page writes it as ...
                assert got == want or ("..." in want and re.fullmatch(re.escape(want).replace(r"\.\.\.", ".*"), got)), \
                    (command, got, want)
            assert len(printed) >= len(head), (command, printed)
