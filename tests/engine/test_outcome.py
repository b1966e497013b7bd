"""The one run path (cosim.engine.outcome.execute): every run, an SSP's, a sweep point's or a
scene's, is set up, freed, measured and reported by the same code, so the same system gives the
same report whichever way it is run, and a run that cannot start leaves no FMU behind."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.engine import Algorithm, FixedStep, NoStep
from cosim.engine.run import run_system
from cosim.engine.ssp import read_ssp
from cosim.engine.fmi import FmuInstance
from cosim.engine.outcome import Report
from cosim.engine.run import execute
from cosim.engine.ssp import write_ssp
from cosim.engine.artifacts import ROOT
from cosim.platform.run.compile import scene_structure
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene
from test_coupling import oscillator


@pytest.fixture
def freed(monkeypatch):
    """Counts FmuInstance.free calls."""
    calls = []
    original = FmuInstance.free

    def free(self):
        calls.append(self.name)
        original(self)

    monkeypatch.setattr(FmuInstance, "free", free)
    return calls


def test_a_run_that_cannot_take_a_step_frees_its_fmus(freed):
    """A stop time before the first step is a NoStep, and both FMUs are freed (the old SSP path
    skipped Execution.free there)."""
    with pytest.raises(NoStep):
        execute(oscillator(), Algorithm("jacobi", 0), FixedStep(1e-3), 1e-4, [("mass", "position")])
    assert sorted(freed) == ["coupling", "mass"]


def test_a_run_is_an_outcome_with_its_measures(freed):
    outcome = execute(oscillator(), Algorithm("jacobi", 1), FixedStep(1e-3), 0.2, [("mass", "position")])
    assert outcome.failure is None and len(outcome.steps) == 200 and outcome.simulated == pytest.approx(0.2)
    assert 0 < outcome.fmi_seconds < outcome.wall and list(outcome.bond_residuals) and sorted(freed) == ["coupling", "mass"]
    report = Report.of(outcome)
    assert report.macro_steps == 200 and report.largest_energy_residual == np.max(outcome.energy_residuals)


def test_a_scene_and_its_ssp_are_reported_alike(tmp_path):
    """The Meng scene run as a scene and as its exported SSP: the same macro steps, energy
    residual, warnings and step control in reports of one kind (the SSP's report had its own
    text and its own statistics before)."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 0.15})
    _, scene_report = run_scene(scene)
    path = write_ssp(scene_structure(scene), tmp_path / "meng.ssp")
    _, ssp_report = run_system(read_ssp(path), source=str(path))
    assert isinstance(scene_report, Report) and type(ssp_report) is Report
    for key in ("macro_steps", "rejected_steps", "step_control", "largest_energy_residual", "warnings", "failure"):
        assert getattr(scene_report, key) == getattr(ssp_report, key), key
    assert scene_report.simulated == pytest.approx(ssp_report.simulated, abs=1e-12)
    first = [line.split(": ", 1)[1].split(" s wall")[1] for line in (scene_report.text(), ssp_report.text())]
    assert first[0].splitlines()[0].split("real-time")[0] == first[1].splitlines()[0].split("real-time")[0]


def test_what_a_system_records_is_written_and_read_by_one_pair_of_functions():
    """The record setting's text (written for a scene's SSP, read by `run FILE.ssp`) round-trips,
    names with dots and brackets included, and the run settings ignore it."""
    from cosim.engine.settings import output_interval, output_settings, recorded, system_settings
    record, names = [("mechanics", "pose.x"), ("pmsm1", "torque")], ["pose.x", "torque[1]"]
    settings = {"algorithm": "jacobi", "order": "0", **output_settings(record, names, 2e-3)}
    assert recorded(settings) == (record, names) and output_interval(settings) == 2e-3
    assert system_settings(settings, 1e-3)[0] == Algorithm("jacobi", 0)
