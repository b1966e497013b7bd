"""Errors judged where people look (cosim.platform.accuracy, issue 24): the windows of a run (the
start-up, each load pulse with the time after it, the steady tracking between) cover it without
overlap, and a window's error is measured against the reference's own change there, so that an
error that passes as a fraction of the start-up shock's peak shows at its size through an impact."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.platform.accuracy import window_errors, windows
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
