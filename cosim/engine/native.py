"""Native libraries seen through ctypes, checked against the build they come from.

A ctypes Structure is a copy of a C struct; nothing in ctypes notices when the two drift apart (a
field added in C, a stale build), and the fields are then read at the wrong offsets. Each library
publishes its structs' layout (fmu/common/struct_layout.h: one entry per field with its offset and
size, one per struct with its size); `check_layout` compares every field of the Python copies with
it when the library is loaded and refuses a mismatch with one line.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Sequence


class LayoutError(RuntimeError):
    """A library's structs differ from their ctypes copies (a build older or newer than the code)."""


class _Entry(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char_p), ("offset", ctypes.c_size_t), ("size", ctypes.c_size_t)]


def published_layout(library: ctypes.CDLL, symbol: str) -> dict[str, tuple[int, int]]:
    """The layout table a library publishes through `symbol` (a function returning the table):
    {"Struct": (0, size), "Struct.field": (offset, size)}."""
    function = getattr(library, symbol)
    function.argtypes, function.restype = [], ctypes.POINTER(_Entry)
    table, out, k = function(), {}, 0
    while table[k].name is not None:
        out[table[k].name.decode()] = (table[k].offset, table[k].size)
        k += 1
    return out


def python_layout(structure: type[ctypes.Structure], name: str | None = None) -> dict[str, tuple[int, int]]:
    """The same table for a ctypes Structure (under the C struct's `name`)."""
    name = name or structure.__name__
    out = {name: (0, ctypes.sizeof(structure))}
    for field, _ in structure._fields_:
        descriptor = getattr(structure, field)
        out[f"{name}.{field}"] = (descriptor.offset, descriptor.size)
    return out


def check_layout(library: ctypes.CDLL, symbol: str, path: Path | str,
                 structures: Sequence[tuple[type[ctypes.Structure], str]]) -> None:
    """Raises LayoutError unless every (ctypes Structure, C name) pair matches the library's
    published layout field by field (names, offsets, sizes) and struct by struct (sizes)."""
    published = published_layout(library, symbol)
    for structure, name in structures:
        ours = python_layout(structure, name)
        theirs = {key: value for key, value in published.items() if key == name or key.startswith(name + ".")}
        if ours == theirs:
            continue
        differing = sorted(set(ours) ^ set(theirs)) or sorted(k for k in ours if ours[k] != theirs[k])
        key = differing[0]
        if key not in theirs or key not in ours:
            detail = f"{key}: {'not in C' if key not in theirs else 'not in Python'}"
        else:
            detail = f"{key}: (offset, size) {theirs[key]} in C, {ours[key]} in Python"
        raise LayoutError(f"{Path(path).name} does not match its Python binding ({detail}): "
                          "rebuild with `bash scripts/setup.sh`, or update the binding")
