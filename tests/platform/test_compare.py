"""`cosim compare RUN_A RUN_B`: two runs of the Meng scene, as shipped and with a heavier platform,
side by side: the differences it prints and writes are the largest |B - A| computed here from the
two CSVs (A interpolated at B's times), per window of the scene (start-up, the load pulse, steady
tracking) against A's own change there; a run against itself differs by nothing; what cannot be
compared is one line."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from cosim.cli import main
from cosim.engine.results import read_results
from cosim.platform.run.accuracy import windows
from cosim.platform.scene import load_scene

BRIEF = ["--duration", "0.3", "--no-plots"]


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("compare")
    assert main(["run", "meng_eq35", *BRIEF, "--out", str(root / "shipped")]) == 0
    assert main(["run", "meng_eq35", *BRIEF, "--out", str(root / "heavier"), "--set",
                 'mechanics.parameters."platform.mass"=1100']) == 0
    return root


def test_the_differences_are_the_runs_own(folders, tmp_path, capsys):
    capsys.readouterr()
    assert main(["compare", str(folders / "shipped"), str(folders / "heavier"), "--columns", "pose.z", "torque[2]",
                 "--scene", "meng_eq35", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    a, b = read_results(folders / "shipped"), read_results(folders / "heavier")
    rows = list(csv.DictReader((tmp_path / "compare.csv").open()))
    spans = windows(float(a["time"][-1]), load_scene("meng_eq35").pulses)
    for column in ("pose.z", "torque[2]"):
        gap = np.abs(b[column] - np.interp(b["time"], a["time"], a[column]))
        whole = next(r for r in rows if r["column"] == column and r["window"] == "whole run")
        assert float(whole["difference"]) == gap.max() and float(whole["at"]) == b["time"][np.argmax(gap)]
        assert float(whole["reference_change"]) == np.ptp(a[column])
        start = next(r for r in rows if r["column"] == column and r["window"] == "start-up")
        here = spans[0].mask(b["time"])
        assert float(start["difference"]) == gap[here].max() and float(start["relative"]) > 0
        assert f"  {column}: {gap.max():.3g} at t = " in out
    assert "heavier against shipped (the reference)" in out
    assert float(next(r for r in rows if r["column"] == "torque[2]" and r["window"] == "whole run")["difference"]) > 1.0
    page = (tmp_path / "compare.html").read_text()
    assert "shipped" in page and "heavier" in page


def test_a_run_against_itself_differs_by_nothing(folders, tmp_path):
    csv_path = next((folders / "shipped").glob("*.csv"))
    assert main(["compare", str(folders / "shipped"), str(csv_path), "--out", str(tmp_path), "--no-plots"]) == 0
    rows = list(csv.DictReader((tmp_path / "compare.csv").open()))
    assert rows and all(float(r["difference"]) == 0.0 for r in rows)
    assert {r["column"] for r in rows} >= {"pose.x", "torque[1]", "current.q[6]"}  # the default columns


@pytest.mark.parametrize("make, message", [
    (lambda tmp, f: [str(f / "shipped")], "give two runs or more"),
    (lambda tmp, f: [str(f / "shipped"), str(tmp / "nowhere")], "no such file or folder"),
    (lambda tmp, f: [str(f / "shipped"), str(tmp)], "an output folder holds one run's CSV; here none"),
    (lambda tmp, f: [str(f / "shipped"), str(_write(tmp / "x.csv", "t,a\n0,1\n1,2\n"))], "its first column is 't'"),
    (lambda tmp, f: [str(f / "shipped"), str(_write(tmp / "y.csv", "time,a\n0,1\n1,x\n"))], "column 'a' holds"),
    (lambda tmp, f: [str(f / "shipped"), str(_write(tmp / "z.csv", "time,a\n1,1\n0,2\n"))], "its times go back"),
    (lambda tmp, f: [str(f / "shipped"), str(f / "heavier"), "--columns", "torque[9]"], "has no column 'torque[9]'"),
])
def test_what_cannot_be_compared_is_one_line(folders, tmp_path, capsys, make, message):
    capsys.readouterr()
    assert main(["compare", *make(tmp_path, folders), "--out", str(tmp_path / "out"), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


def _write(path, text):
    path.write_text(text)
    return path
