"""Results in fmpy's convention (a numpy structured array with `time` and named float columns),
written as CSV and as MATLAB .mat (one variable per column)."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

import numpy as np

from .files import replacing, write_bytes, write_text


def thin(result: np.ndarray, interval: float | None) -> np.ndarray:
    """The rows nearest to every `interval` seconds (and the last), or all rows."""
    if not interval or len(result) < 2:
        return result
    t = result["time"]
    grid = np.arange(t[0], t[-1] + 1e-9, interval)
    keep = np.unique(np.minimum(np.searchsorted(t, grid - 1e-9), len(t) - 1))
    return result[np.union1d(keep, [len(t) - 1])]


def write_csv(result: np.ndarray, path: Path) -> Path:
    """Every value with 17 significant digits (a float's round trip), one header line of names
    (formatted in C: cosim/engine/kernel/csv.c), written whole or not at all (cosim.engine.files)."""
    from .kernel import library
    names = result.dtype.names
    columns = np.column_stack([result[n] for n in names]) if len(result) else np.zeros((0, len(names)))
    needed = 25 * columns.size + sum(len(n) + 1 for n in names)  # at most 24 characters a value, and its comma
    table = np.ascontiguousarray(columns, dtype=np.float64)
    flat = table.reshape(-1) if table.size else np.zeros(1)
    with replacing(path, "the results", needed) as temporary:
        if library().table_write_csv(str(temporary).encode(), ",".join(names).encode(),
                                     flat.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), *table.shape) != 0:
            code = ctypes.get_errno()
            raise OSError(code, os.strerror(code) if code else "cannot write", str(temporary))
    return Path(path)


def mat_name(name: str) -> str:
    """A MATLAB-safe variable name (pose.x -> pose_x, torque[1] -> torque_1)."""
    return name.replace(".", "_").replace("[", "_").replace("]", "")


def _element(kind: int, data: bytes) -> bytes:
    """A MAT-file data element: type, byte count, data padded to 8 bytes."""
    return np.array([kind, len(data)], "<u4").tobytes() + data + b"\0" * (-len(data) % 8)


def write_mat(result: np.ndarray, path: Path) -> Path:
    """MATLAB level-5 .mat, one double column vector per result column (what scipy.io.savemat
    writes, without importing scipy: the format is a header and one miMATRIX element a variable)."""
    MI_INT8, MI_INT32, MI_UINT32, MI_DOUBLE, MI_MATRIX, MX_DOUBLE_CLASS = 1, 5, 6, 9, 14, 6
    header = b"MATLAB 5.0 MAT-file, written by cosim".ljust(116, b" ") + b"\0" * 8 + \
        np.array([0x0100], "<u2").tobytes() + b"IM"
    parts = [header]
    for name in result.dtype.names:
        column = np.ascontiguousarray(result[name], dtype="<f8")
        body = (_element(MI_UINT32, np.array([MX_DOUBLE_CLASS, 0], "<u4").tobytes())
                + _element(MI_INT32, np.array([len(column), 1], "<i4").tobytes())
                + _element(MI_INT8, mat_name(name).encode("ascii"))
                + _element(MI_DOUBLE, column.tobytes()))
        parts.append(_element(MI_MATRIX, body))
    return write_bytes(path, b"".join(parts), "the results")


def write_log(messages, path: Path) -> Path:
    """Everything the FMUs logged, as CSV: step_start (the communication point at which the call
    that logged it began) [s], instance, status, category, message."""
    import csv
    import io
    text = io.StringIO(newline="")
    writer = csv.writer(text)
    writer.writerow(["step_start", "instance", "status", "category", "message"])
    for instance, m in messages:
        writer.writerow([repr(m.time), instance, m.status, m.category, m.text])
    return write_text(path, text.getvalue(), "the FMUs' log")


def message_kinds(messages, status: str = "warning") -> list[tuple[int, str]]:
    """(count, kind) of the messages of one status, most frequent first; a kind is the message
    with its numbers and leading time taken out, per FMU (instances numbered alike count together)."""
    import re
    from collections import Counter
    number = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
    counts = Counter()
    for instance, m in messages:
        if m.status == status:
            text = re.sub(r"^t = [^:]*: ", "", m.text)
            counts[f"{re.sub(r'[0-9]+$', '', instance)}: {number.sub('#', text)}"] += 1
    return [(n, kind) for kind, n in counts.most_common()]


def read_results(path: str | Path) -> np.ndarray:
    """A run's results as a structured array: its CSV (ours, or any whose first column is `time`
    and whose rows are numbers), or the one CSV of an output folder (`cosim run --out`). A file that
    cannot be read so is one line naming it (UsageError)."""
    import pyarrow as pa
    import pyarrow.csv
    from .errors import UsageError
    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob("*.csv"))
        if len(found) != 1:
            raise UsageError(f"{path}: an output folder holds one run's CSV; here {len(found) or 'none'}"
                             + (f" ({', '.join(f.name for f in found)}): name the CSV" if found else ""))
        path = found[0]
    if not path.is_file():
        raise UsageError(f"{path}: no such file or folder")
    try:
        table = pyarrow.csv.read_csv(path)
    except (pa.ArrowInvalid, OSError, UnicodeDecodeError) as error:
        raise UsageError(f"{path}: not a results CSV ({str(error).splitlines()[0]})") from None
    names = table.column_names
    if not names or names[0] != "time":
        raise UsageError(f"{path}: not a results CSV: its first column is {names[0] if names else 'missing'!r}, not "
                         "'time'")
    bad = [n for n in names if not (pa.types.is_floating(table[n].type) or pa.types.is_integer(table[n].type))]
    if bad or len(set(names)) != len(names):
        raise UsageError(f"{path}: not a results CSV: column {bad[0] if bad else 'names'!r} "
                         + ("holds other than numbers" if bad else "repeat"))
    out = np.zeros(table.num_rows, dtype=[(n, float) for n in names])
    for name in names:
        out[name] = table[name].to_numpy(zero_copy_only=False).astype(float)
    if table.num_rows < 2 or np.any(np.diff(out["time"]) < 0):
        raise UsageError(f"{path}: not a results CSV: " + ("fewer than two rows" if table.num_rows < 2 else
                                                           "its times go back"))
    return out
