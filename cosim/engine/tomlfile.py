"""Where a key stands in a TOML file: the line a one-line error names (scenes, sweep files)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path


def line_of(text: str, table: str, key: str) -> int:
    """The line (1-based) on which `key` stands inside [table] (or its header; also inside an
    inline table there), the first line naming it anywhere else, or 0."""
    assignment = re.compile(r'(^|[{,\s])"?' + re.escape(key) + r'"?\s*=')
    current, found = "", 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if line.startswith("["):
            current = line.strip("[]").strip()
            if current == (f"{table}.{key}" if table else key):
                return number
            continue
        if assignment.search(line):
            if current == table:
                return number
            found = found or number
    return found


def read(path: Path, what: str, error: type[Exception]) -> tuple[str, dict]:
    """A TOML file's text and document; `error` (one line naming the file) if it is missing, not
    readable as text or not valid TOML. `what` names the kind of file ("sweep file")."""
    if not path.is_file():
        raise error(f"{path}: no such {what}")
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as problem:
        raise error(f"{path}: cannot be read: {problem}") from None
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as problem:
        raise error(f"{path}: not valid TOML: {problem}") from None
