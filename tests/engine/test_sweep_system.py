"""A sweep of any SSP system (cosim.engine.sweep.SystemPoint), on the oscillator alone: settings
and component parameters as axes, each row equal to the same run of the SSP on its own."""

from __future__ import annotations

import numpy as np

from cosim.engine import Algorithm, FixedStep
from cosim.engine.run import run_system
from cosim.engine.settings import to_strings
from cosim.engine.ssp import read_ssp, write_ssp
from cosim.engine.structure import with_parameters
from cosim.engine.sweep import Axis, SystemPoint, grid, run_sweep
from test_coupling import oscillator


def test_a_sweep_of_an_ssp_system_reports_what_each_run_gives(tmp_path):
    system = oscillator(0.5)
    system.settings = to_strings(Algorithm("gauss-seidel", 1, ("coupling", "mass")), FixedStep(1e-3))
    path = write_ssp(system, tmp_path / "oscillator.ssp")
    before = path.read_bytes()
    evaluate = SystemPoint(str(path), None, (("mass.position", ("max", "rms", "final")),))
    points = grid([Axis("order", (0, 1)), Axis("mass.mass", (1.0, 2.0, -1.0))])
    rows = run_sweep("oscillator", points, evaluate, evaluate.columns(), tmp_path / "out", workers=0,
                     progress=False).rows
    assert [(r["order"], r["mass.mass"]) for r in rows] == [(p["order"], p["mass.mass"]) for p in points]
    for row in rows:
        if row["mass.mass"] < 0:  # a value the FMU's modelDescription refuses: a row that says so
            assert row["status"] == "failed" and "mass.mass = -1.0" in row["message"], row
            continue
        assert row["status"] == "ok", row["message"]
        alone = with_parameters(read_ssp(path), {"mass": {"mass": row["mass.mass"]}})
        result, report = run_system(alone, {"order": str(row["order"])})
        position = result["mass.position"]
        assert row["max.mass.position"] == position.max() and row["final.mass.position"] == position[-1]
        assert row["rms.mass.position"] == np.sqrt(np.mean(position ** 2))
        assert row["steps"] == report.macro_steps == 500 and row["energy_residual"] == report.largest_energy_residual
    assert path.read_bytes() == before  # the sweep changes nothing in the archive


def test_the_sweep_file_reader_is_the_engine_s_with_pluggable_targets(tmp_path):
    """The engine reads a sweep file of an SSP system on its own (no application's target given);
    a target it was not given is named as the one-line error, with the kinds it knows."""
    import pytest
    from cosim.engine.sweep import SYSTEM, SweepError, load_sweep
    system = oscillator(0.2)
    system.settings = to_strings(Algorithm("jacobi", 0), FixedStep(1e-3))
    write_ssp(system, tmp_path / "oscillator.ssp")
    path = tmp_path / "sweep.toml"
    path.write_text('[sweep]\nsystem = "oscillator.ssp"\n[[axis]]\nkey = "order"\nvalues = [0, 1]\n'
                    '[report]\noutputs = { "mass.position" = ["max"] }\n')
    sweep = load_sweep(path, {"system": SYSTEM})
    assert [p["order"] for p in sweep.points] == [0, 1] and isinstance(sweep.evaluate, SystemPoint)
    assert sweep.columns == ["steps", "rejected", "energy_residual", "real_time_factor", "max.mass.position"]
    path.write_text('[sweep]\nscene = "meng.toml"\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n')
    with pytest.raises(SweepError, match=r"sweep.toml:2: 'sweep.scene' is not a known key .*system"):
        load_sweep(path, {"system": SYSTEM})
