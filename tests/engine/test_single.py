"""One FMU as a system (cosim.engine.single, `cosim run FILE.fmu`): a Co-Simulation FMU run alone
gives what a tool we did not write (fmpy's simulate_fmu) gives at the same step, bit for bit, FMI
3.0 as FMI 2.0; the run's settings and duration apply; what is not a runnable FMU is one line."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu

import cosim
from cosim.cli import main
from cosim.engine.artifacts import fmu_path
from cosim.engine.errors import SspError

def test_an_fmu_alone_runs_as_fmpy_runs_it():
    """The mechanics alone at its own step (its DefaultExperiment's) and start values, no torque:
    the platform falls under gravity, and every recorded sample is fmpy's simulate_fmu's of the same
    FMU to the last bits (fmpy's communication points are start + n h, ours the sum of the steps: the
    times differ by ulps, and so what the FMU computes at them)."""
    path = fmu_path("mechanics")
    columns = ["pose.z", "pose.x", "leg[1].length", "leg[4].velocity"]
    ours = cosim.simulate(path, duration=0.5)
    theirs = simulate_fmu(str(path), stop_time=0.5, step_size=1e-3, output=columns, fmi_type="CoSimulation")
    assert len(ours["time"]) == len(theirs["time"]) == 501
    assert np.abs(ours["time"] - theirs["time"]).max() < 1e-14
    assert np.ptp(ours["pose.z"]) > 0.1  # it fell
    assert "energy residual" not in ours.report.text()  # one FMU: no power bond to account for
    for name in columns:
        assert np.abs(ours[name] - theirs[name]).max() <= 1e-12 * max(1.0, np.ptp(theirs[name])), name


def test_fmi3_alone_equals_fmi2_alone():
    two = cosim.simulate(fmu_path("mechanics"), duration=0.3)
    three = cosim.simulate(fmu_path("mechanics", fmi=3), duration=0.3)
    for name in ("pose.z", "leg[1].length", "energy.kinetic"):
        assert np.array_equal(two[name], three[name]), name


def test_the_run_settings_and_duration_apply(tmp_path):
    run = cosim.simulate(fmu_path("trajectory"), duration=0.2, settings={"step": "2e-3"})
    assert np.allclose(np.diff(run["time"]), 2e-3) and run["time"][-1] == pytest.approx(0.2)
    assert main(["run", str(fmu_path("trajectory")), "--duration", "0.1", "--set", "step=5e-4", "--out",
                 str(tmp_path)]) == 0
    text = (tmp_path / "trajectory.csv").read_text().splitlines()
    assert text[0].split(",")[:2] == ["time", "pose_ref.x"] and len(text) == 1 + 201


def _zip(path, members: dict[str, str]):
    with zipfile.ZipFile(path, "w") as archive:
        for name, text in members.items():
            archive.writestr(name, text)
    return path


@pytest.mark.parametrize("make, message", [
    (lambda tmp: tmp / "missing.fmu", "no such file"),
    (lambda tmp: (tmp / "text.fmu").write_text("not a zip") and tmp / "text.fmu", "not an FMU"),
    (lambda tmp: _zip(tmp / "empty.fmu", {"readme.txt": "x"}), "not an FMU that can be read"),
    (lambda tmp: _zip(tmp / "broken.fmu", {"modelDescription.xml": "<fmiModelDescription"}),
     "not an FMU that can be read"),
])
def test_what_is_not_a_runnable_fmu_is_one_line(tmp_path, capsys, make, message):
    path = make(tmp_path)
    with pytest.raises(SspError, match=message):
        cosim.simulate(path)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
