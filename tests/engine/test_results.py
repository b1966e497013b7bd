"""Results as files: the .mat writer (no scipy on the run's path) gives what scipy reads back bit
for bit, one column vector per result column under a MATLAB-safe name; the CSV round-trips every
value (17 significant digits) and is, byte for byte, C's %.17g: the writer's own conversion
(cosim/engine/kernel/csv.c) where it can go wrong too (next to powers of ten, ties, carries)."""

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


def _hard_values(rng: np.random.Generator) -> np.ndarray:
    """Values where a 17-digit conversion can go wrong: one ulp either side of every power of ten in
    its range and beyond, exact binary fractions (decimal ties), large integers, random bit patterns,
    every decade from 1e-32 to 1e20, the smallest and largest doubles, signed zeros and infinities."""
    powers = 10.0 ** np.arange(-32, 21)
    return np.concatenate([
        powers, np.nextafter(powers, np.inf), np.nextafter(powers, 0), np.nextafter(-powers, -np.inf),
        rng.integers(-10**6, 10**6, 20000) / 2.0 ** rng.integers(1, 60, 20000),
        rng.integers(-10**17, 10**17, 5000).astype(float),
        rng.integers(0, 2**63, 20000, dtype=np.uint64).view(np.float64),
        10 ** rng.uniform(-32, 20, 20000) * rng.choice([-1.0, 1.0], 20000),
        [0.0, -0.0, np.inf, -np.inf, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1, 0.3, 2.5,
         9.9999999999999998e16, 99999999999999984.0, 0.99999999999999994, 9.9999999999999995e-5]])


def test_the_csv_conversion_is_printf_17g_where_it_can_go_wrong(tmp_path):
    values = _hard_values(np.random.default_rng(11))
    values = values[~np.isnan(values)]
    r = np.zeros(len(values), dtype=[("time", float), ("value", float)])
    r["time"], r["value"] = np.arange(len(values)), values
    write_csv(r, tmp_path / "r.csv")
    written = (tmp_path / "r.csv").read_text().splitlines()[1:]
    expected = [f"{t:.17g},{v:.17g}" for t, v in r.tolist()]
    wrong = [(e, w) for e, w in zip(expected, written) if e != w]
    assert len(written) == len(values) and not wrong, wrong[:5]
    finite = np.isfinite(values)
    np.testing.assert_array_equal(np.array([float(w.split(",")[1]) for w in written])[finite], values[finite])
