"""Errors judged where people look (cosim.platform.run.accuracy, issue 24): the windows of a run (the
start-up, each load pulse with the time after it, the steady tracking between) cover it without
overlap, and a window's error is measured against the reference's own change there, so that an
error that passes as a fraction of the start-up shock's peak shows at its size through an impact."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.platform.run.accuracy import window_errors, windows
from cosim.platform.scene import Pulse


def test_the_windows_cover_the_run_once():
    spans = windows(10.0, [Pulse("force.z", 500.0, 2.5, 2.52), Pulse("force.x", 10.0, 2.5, 2.52)])
    assert [w.name for w in spans] == ["start-up", "load pulse at 2.5 s", "steady tracking"]
    t = np.linspace(0.0, 10.0, 100001)
    covered = np.sum([w.mask(t) for w in spans], axis=0)
    assert np.all(covered == 1)  # half-open spans: every instant in one window, the end included
    short = windows(0.1, [Pulse("force.z", 500.0, 2.5, 2.52)])
    assert [w.name for w in short] == ["start-up"] and short[0].mask(np.array([0.1]))[0]


def test_an_error_is_judged_against_the_window_s_own_change():
    """A reference with a start-up shock of 64 and an impact that moves it by 0.8: a result off by
    0.3 through the impact is 0.5 % of the shock's peak but 38 % of the impact's own change."""
    t = np.linspace(0.0, 5.0, 5001)
    ref = np.where(t < 0.05, 64.0, 8.0) + np.where((t >= 2.5) & (t <= 2.6), 0.8, 0.0)
    off = ref + np.where((t >= 2.5) & (t <= 2.7), 0.3, 1e-4)
    table = np.zeros(len(t), dtype=[("time", float), ("torque[1]", float)])
    table["time"], table["torque[1]"] = t, ref
    result = table.copy()
    result["torque[1]"] = off
    errors = {e.window: e for e in window_errors(result, table, ["torque[1]"], windows(5.0, [Pulse("force.z", 500.0,
                                                                                                2.5, 2.52)]))}
    assert errors["load pulse at 2.5 s"].error == pytest.approx(0.3)
    assert errors["load pulse at 2.5 s"].relative == pytest.approx(0.3 / 0.8)
    assert errors["steady tracking"].error == pytest.approx(1e-4)
    assert errors["start-up"].scale == pytest.approx(56.0)
    assert 0.3 / 64.0 < 0.01 < errors["load pulse at 2.5 s"].relative


def test_a_run_reports_its_errors_against_its_converged_twin(tmp_path, capsys):
    """`cosim run SCENE --twin`: the report gives, per window, the run's largest pose and effort
    differences to the same scene at a 16th of its step; on the Meng scene's first 0.6 s the pose
    is within 1e-5 and the torques within 2 % of their change in each window, and the HTML report
    carries the same rows."""
    from cosim.cli import main
    from cosim.engine.artifacts import ROOT
    text = (ROOT / "scenes" / "meng_eq35.toml").read_text().replace("duration = 10.0", "duration = 0.6")
    path = tmp_path / "short.toml"
    path.write_text(text)
    assert main(["run", str(path), "--twin", "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    line = next(l for l in out.splitlines() if l.startswith("against the converged twin"))
    assert "start-up: pose" in line and "steady tracking: pose" in line
    import re
    for pose, relative in re.findall(r"pose ([\d.e+-]+), efforts [\d.e+-]+ \(([\d.]+) % of their change\)", line):
        assert float(pose) < 1e-5 and float(relative) < 2.0, line
    assert "against the converged twin, start-up" in (tmp_path / "out" / "short.html").read_text()
