"""The types of a value in a file a user writes (cosim.engine.schema declares the keys): each says
whether a value is of it (`problem`: None, or why not), what it is in words (`describe`, for
errors and the reference pages) and, for the settings given as text, how to read it (`parse`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


class _Required:
    def __repr__(self) -> str:
        return "required"


REQUIRED: Any = _Required()  # a key's default when the file must give it


# -- the types of a value ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Number:
    """A finite number within [low, high] (either end open with `above` / `below`, `whole` for
    whole numbers)."""
    unit: str = ""
    low: float | None = None
    high: float | None = None
    above: bool = False
    below: bool = False
    whole: bool = False

    def problem(self, value: Any) -> str | None:
        if isinstance(value, bool) or not isinstance(value, int if self.whole else (int, float)):
            return f"must be {self.describe()}"
        if not math.isfinite(value):
            return f"must be a finite {'whole number' if self.whole else 'number'}"
        too_low = self.low is not None and (value <= self.low if self.above else value < self.low)
        too_high = self.high is not None and (value >= self.high if self.below else value > self.high)
        return f"must be {self.describe()}" if too_low or too_high or (self.whole and value != int(value)) else None

    def describe(self) -> str:
        noun = "whole number" if self.whole else "number"
        if self.low is not None and self.high is not None:
            return f"a {noun} in {'(' if self.above else '['}{self.low:g}, {self.high:g}{')' if self.below else ']'}"
        if self.low == 0:
            return f"a {'positive' if self.above else 'non-negative'} {noun}"
        if self.low is not None:
            return f"a {noun} {'>' if self.above else '>='} {self.low:g}"
        if self.high is not None:
            return f"a {noun} {'<' if self.below else '<='} {self.high:g}"
        return f"a {noun}"

    def parse(self, text: str) -> float | int:
        """From a setting's text (an SSP annotation, the command line)."""
        value = float(text)
        return int(value) if self.whole and value == int(value) else value


@dataclass(frozen=True)
class Flag:
    """true or false."""

    def problem(self, value: Any) -> str | None:
        return None if isinstance(value, bool) else "must be true or false"

    def describe(self) -> str:
        return "true or false"

    def parse(self, text: str) -> bool:
        if text not in ("true", "false"):
            raise ValueError(f"{text!r}: true or false")
        return text == "true"


@dataclass(frozen=True)
class Text:
    """A non-empty text (a name, or a file's path: `path`, relative to the file that names it)."""
    path: bool = False

    def problem(self, value: Any) -> str | None:
        return None if isinstance(value, str) and value else f"must be {self.describe()}"

    def describe(self) -> str:
        return "a file's path (text)" if self.path else "text"

    def parse(self, text: str) -> str:
        return text


@dataclass(frozen=True)
class Choice:
    """One of a few values."""
    options: tuple

    def problem(self, value: Any) -> str | None:
        same_type = [o for o in self.options if type(o) is type(value)]
        return None if value in same_type else f"use {self.describe()}"

    def describe(self) -> str:
        shown = [repr(o) for o in self.options]
        return shown[0] if len(shown) == 1 else ", ".join(shown[:-1]) + " or " + shown[-1]

    def parse(self, text: str) -> Any:
        for option in self.options:
            if str(option) == text:
                return option
        raise ValueError(f"{text!r}: {self.describe()}")


@dataclass(frozen=True)
class Either:
    """A value of one of these types."""
    types: tuple

    def problem(self, value: Any) -> str | None:
        problems = [t.problem(value) for t in self.types]
        return None if any(p is None for p in problems) else f"must be {self.describe()}"

    def describe(self) -> str:
        return " or ".join(t.describe() for t in self.types)


@dataclass(frozen=True)
class Row:
    """A list of a fixed length, a type per place (`[start, stop, count]`)."""
    types: tuple

    def problem(self, value: Any) -> str | None:
        if not isinstance(value, list) or len(value) != len(self.types) or \
                any(t.problem(v) is not None for t, v in zip(self.types, value)):
            return f"must be {self.describe()}"
        return None

    def describe(self) -> str:
        return "[" + ", ".join(t.describe() for t in self.types) + "]"


@dataclass(frozen=True)
class ListOf:
    """A list of values of one type, `least` to `most` of them."""
    type: Any
    least: int = 0
    most: int | None = None

    def problem(self, value: Any) -> str | None:
        if not isinstance(value, list) or len(value) < self.least or (self.most is not None and len(value) > self.most) \
                or any(self.type.problem(v) is not None for v in value):
            return f"must be {self.describe()}"
        return None

    def describe(self) -> str:
        count = f"{self.least} to {self.most}" if self.most is not None else f"at least {self.least}" if self.least \
            else "any number of"
        return f"a list of {count} ({self.type.describe()})"


@dataclass(frozen=True)
class Anything:
    """Any TOML value (an axis' values: whatever the key they go to takes)."""

    def problem(self, value: Any) -> str | None:
        return None

    def describe(self) -> str:
        return "any value"


@dataclass(frozen=True)
class Free:
    """A table of names and values that the application checks (`what` says what they are)."""
    what: str

    def problem(self, value: Any) -> str | None:
        return None if isinstance(value, dict) else f"must be a table of {self.what}"

    def describe(self) -> str:
        return f"a table of {self.what}"


@dataclass(frozen=True)
class Items:
    """A list of inline tables with keys of their own (at most `most`)."""
    keys: tuple  # the entries' keys (cosim.engine.schema.Key)
    most: int | None = None

    def problem(self, value: Any) -> str | None:
        return None if isinstance(value, list) else f"must be {self.describe()}"

    def describe(self) -> str:
        return f"a list of inline tables {{{', '.join(k.name for k in self.keys)}}}" + \
            (f", at most {self.most}" if self.most is not None else "")
