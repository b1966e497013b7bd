"""A TOML file read whole, for the readers not yet on a schema (cosim.engine.schema)."""

from __future__ import annotations

import tomllib
from pathlib import Path

from .schema import line_of

__all__ = ["line_of", "read"]


def read(path: Path, what: str, error: type[Exception]) -> tuple[str, dict]:
    """A TOML file's text and document; `error` (one line naming the file) if it is missing, not
    readable as text or not valid TOML. `what` names the kind of file ("study file")."""
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
