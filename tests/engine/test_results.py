"""Results as files: the .mat writer (no scipy on the run's path) gives what scipy reads back bit
for bit, one column vector per result column under a MATLAB-safe name; the CSV round-trips every
value (17 significant digits)."""

from __future__ import annotations

import numpy as np
from scipy.io import loadmat

from cosim.engine.results import write_csv, write_mat


def result() -> np.ndarray:
    r = np.zeros(2001, dtype=[("time", float), ("pose.x", float), ("torque[6]", float)])
    r["time"] = np.arange(2001) * 1e-3
    r["pose.x"] = np.sin(r["time"]) * 1e-7 + 1.689527733348906
    r["torque[6]"] = np.where(r["time"] > 1, np.nan, -np.exp(r["time"]))
    return r


def test_the_mat_file_reads_back_bit_for_bit(tmp_path):
    r = result()
    write_mat(r, tmp_path / "r.mat")
    m = loadmat(tmp_path / "r.mat")
    assert sorted(k for k in m if not k.startswith("__")) == ["pose_x", "time", "torque_6"]
    for name, key in (("time", "time"), ("pose.x", "pose_x"), ("torque[6]", "torque_6")):
        assert m[key].shape == (len(r), 1)
        np.testing.assert_array_equal(m[key][:, 0], r[name])  # NaN where NaN, every bit elsewhere


def test_the_csv_round_trips_every_value(tmp_path):
    r = result()
    write_csv(r, tmp_path / "r.csv")
    back = np.genfromtxt(tmp_path / "r.csv", delimiter=",", names=True)
    for name, key in (("time", "time"), ("pose.x", "posex"), ("torque[6]", "torque6")):
        np.testing.assert_array_equal(back[key], r[name])


def test_the_csv_is_printf_17g_row_by_row_whatever_the_threads(tmp_path):
    """The rows are formatted in two halves on two threads from 1000 rows on: the file is, byte for
    byte, the header and every value as C's %.17g (Python's own), in row order."""
    rng = np.random.default_rng(5)
    for rows in (3, 999, 1000, 4001):
        r = np.zeros(rows, dtype=[("time", float), ("a", float), ("b", float)])
        r["time"] = np.arange(rows) * 1e-3
        r["a"] = rng.normal(size=rows) * 10.0 ** rng.integers(-300, 300, rows)
        r["b"] = np.where(rng.random(rows) < 0.1, np.nan, rng.normal(size=rows))
        write_csv(r, tmp_path / "r.csv")
        expected = "time,a,b\n" + "".join(",".join("nan" if np.isnan(v) else "%.17g" % v for v in row) + "\n"
                                            for row in r.tolist())
        assert (tmp_path / "r.csv").read_text() == expected, rows
