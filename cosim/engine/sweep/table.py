"""A sweep's results table on disk: Parquet parts written whole as tasks end (the source of
truth), a CSV appended row by row, and the whole table in the points' order at the end."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ..files import appending, replacing, write_text
from .points import SweepError, column_name


def statistics(result: np.ndarray, wanted: Mapping[str, Sequence[str]]) -> dict[str, float]:
    """Statistics of recorded columns over the whole run: max, min, max_abs, mean, rms, final."""
    functions = {"max": np.max, "min": np.min, "max_abs": lambda v: np.max(np.abs(v)), "mean": np.mean,
                 "rms": lambda v: np.sqrt(np.mean(np.square(v))), "final": lambda v: v[-1]}
    out = {}
    for column, stats in wanted.items():
        for stat in stats:
            values = result[column] if len(result) else np.array([np.nan])
            out[f"{stat}.{column}"] = float(functions[stat](values))
    return out


STATISTICS = ("max", "min", "max_abs", "mean", "rms", "final")


class ResultTable:
    """The sweep's rows on disk: <out>/<name>.parts/part-*.parquet (the source of truth: each
    written whole, then renamed into place), <name>.csv appended as rows arrive, and
    <name>.parquet, the whole table in the points' order, written at the end (and the CSV
    rewritten in that order). `done` holds the keys already there."""

    def __init__(self, out: Path, name: str, axes: Sequence[str], columns: Sequence[str], signature: str):
        import pyarrow as pa
        self.out, self.name = Path(out), name
        self.parts = self.out / f"{name}.parts"
        self.axes = [column_name(a) for a in axes]
        self.columns = ["point", *self.axes, "status", "message", *columns, "wall"]
        self.csv = self.out / f"{name}.csv"
        self.parquet = self.out / f"{name}.parquet"
        self._pa = pa
        signature_file = self.parts / "signature"
        if signature_file.exists() and signature_file.read_text() != signature:
            raise SweepError(f"{self.parts} holds the results of another sweep (its target, duration, axes' names or "
                             "reports differ): remove the folder or choose another --out")
        write_text(signature_file, signature, "the sweep's signature")
        self.rows = self._read_parts()
        self.done = {row["point"] for row in self.rows}
        self._write_csv(self.rows)  # rebuilt from the parts: a line cut off by an interruption is gone
        self._count = len(list(self.parts.glob("part-*.parquet")))

    def _read_parts(self) -> list[dict]:
        import pyarrow.parquet as pq
        rows = []
        for part in sorted(self.parts.glob("part-*.parquet")):
            rows += pq.read_table(part).to_pylist()
        return rows

    def _write_csv(self, rows: list[dict], append: bool = False) -> None:
        """The rows as CSV: appended as they arrive, or the whole table written anew."""
        import csv
        import io
        text = io.StringIO(newline="")
        writer = csv.DictWriter(text, self.columns, extrasaction="ignore")
        if not append:
            writer.writeheader()
        for row in rows:
            writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
        if not append:
            write_text(self.csv, text.getvalue(), "the sweep's table")
            return
        with appending(self.csv, "the sweep's table") as file:
            file.write(text.getvalue())

    def _arrow(self, rows: list[dict]):
        pa = self._pa
        fields = []
        for name in self.columns:
            values = [row.get(name) for row in rows]
            known = [v for v in values if v is not None]
            if name in ("point", "status", "message") or any(isinstance(v, str) for v in known):
                kind = pa.string()
                values = [None if v is None else str(v) for v in values]
            elif known and all(isinstance(v, bool) for v in known):
                kind = pa.bool_()
            elif known and len(known) == len(values) and all(
                    isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in known):
                kind = pa.int64()
            else:
                kind = pa.float64()
                values = [float("nan") if v is None else float(v) for v in values]
            fields.append(pa.array(values, type=kind))
        return pa.Table.from_arrays(fields, names=self.columns)

    def add(self, rows: list[dict]) -> None:
        import pyarrow.parquet as pq
        rows = [row for row in rows if row["point"] not in self.done]
        if not rows:
            return
        with replacing(self.parts / f"part-{self._count:06d}.parquet", "a part of the sweep's table") as temporary:
            pq.write_table(self._arrow(rows), temporary)
        self._count += 1
        self._write_csv(rows, append=True)
        self.rows += rows
        self.done |= {row["point"] for row in rows}

    def finish(self, order: Sequence[str]) -> list[dict]:
        """Writes <name>.parquet and rewrites <name>.csv: the rows of the points `order` names, in
        that order (as they arrived until now); returns them."""
        import pyarrow.parquet as pq
        by_key = {row["point"]: row for row in self.rows}
        rows = [by_key[k] for k in order if k in by_key]
        if rows:
            with replacing(self.parquet, "the sweep's table") as temporary:
                pq.write_table(self._arrow(rows), temporary)
        self._write_csv(rows)
        return rows
