"""The drive demo (examples/drive_demo.py) runs end to end and its drive settles where it was sent."""

from __future__ import annotations

import sys

import numpy as np

import drive_demo


def test_main_job_writes_plot_and_results(tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["drive_demo", "--out", str(tmp_path)])
    drive_demo.main()
    assert (tmp_path / "pmsm_drive_demo.png").stat().st_size > 10_000
    for name in ("ideal", "averaged", "switching"):
        result = np.genfromtxt(tmp_path / f"pmsm_step_{name}.csv", delimiter=",", names=True)
        assert abs(result["loadangle"][-1] - 5.0) < 0.05  # 1 % of the 5 rad step after 0.38 s
