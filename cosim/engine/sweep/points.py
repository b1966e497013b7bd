"""A sweep's points: axes of named values, drawn as a grid, zipped or a Latin hypercube, and each
point's identity (a hash of its values) and column names."""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from ..errors import InputError

Value = Any


class SweepError(InputError):
    """A sweep that cannot start (its file, its output folder): one line."""


# -- points ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Axis:
    """One swept value: `values` (a list, or a linspace or geomspace expanded by the file's
    reader) for a grid or zipped sweep; `between` (low, high) for a Latin-hypercube sample."""
    name: str
    values: tuple = ()
    between: tuple[float, float] | None = None
    line: int = 0  # where the sweep file defines it (0: not from a file)


def grid(axes: Sequence[Axis]) -> list[dict[str, Value]]:
    """Every combination of the axes' values, the last axis varying fastest."""
    return [dict(zip((a.name for a in axes), combo)) for combo in itertools.product(*(a.values for a in axes))]


def zipped(axes: Sequence[Axis]) -> list[dict[str, Value]]:
    """The i-th values of every axis together (all axes the same length)."""
    lengths = {len(a.values) for a in axes}
    if len(lengths) > 1:
        raise SweepError(f"a zipped sweep needs axes of one length, these have {sorted(lengths)}")
    return [dict(zip((a.name for a in axes), combo)) for combo in zip(*(a.values for a in axes))]


def latin_hypercube(axes: Sequence[Axis], points: int, seed: int) -> list[dict[str, Value]]:
    """`points` points whose every axis hits each of `points` equal strata of its range once
    (scipy.stats.qmc.LatinHypercube, reproducible by `seed`). An axis with values instead of a
    range picks among them by stratum."""
    from scipy.stats import qmc
    unit = qmc.LatinHypercube(d=len(axes), seed=seed).random(points)
    out = []
    for row in unit:
        point = {}
        for a, u in zip(axes, row):
            if a.between is not None:
                low, high = a.between
                point[a.name] = float(low + u * (high - low))
            else:
                point[a.name] = a.values[min(int(u * len(a.values)), len(a.values) - 1)]
        out.append(point)
    return out


def column_name(key: str) -> str:
    """A point's name as a table column: the key without quotes ('a."b.c"' -> a.b.c)."""
    return key.replace('"', "").replace("'", "")


def point_key(values: Mapping[str, Value]) -> str:
    """A point's identity: a hash of its values (names sorted; floats by their exact repr)."""
    text = json.dumps({k: repr(v) if isinstance(v, float) else v for k, v in sorted(values.items())}, sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:16]
