"""The public Python API (cosim.api), every function of it: what each returns on a brief scene or
system, that a Scene changes through its document (its file not read again, no change lost), and
that an argument that does not apply to what it is given is refused in one line, not dropped."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import cosim
from cosim.engine.errors import UsageError
from cosim.engine.structure import SystemStructure

# the Meng scene's first 50 ms at plain 1 ms steps
BRIEF = {"scene.duration": 0.05, "load.pulses": [], "coupling.startup_time": 0.0, "coupling.edge_time": 0.0}


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    """The Meng scene exported as SSP (export_ssp), 50 ms long."""
    return cosim.export_ssp(cosim.load("meng_eq35", BRIEF), tmp_path_factory.mktemp("ssp") / "meng.ssp")


def test_load_reads_a_scene_with_its_overrides_and_a_system():
    scene = cosim.load("meng_eq35", {"scene.step": 5e-4, **BRIEF})
    assert isinstance(scene, cosim.Scene) and scene.step == 5e-4 and scene.duration == 0.05
    assert scene.control.step == 5e-4  # the engine's settings object carries it
    with pytest.raises(cosim.SceneError, match="'scene.stepp' is not a known key"):
        cosim.load("meng_eq35", {"scene.stepp": 1e-3})


def test_load_reads_a_system_and_refuses_scene_overrides_for_it(ssp):
    assert isinstance(cosim.load(ssp), SystemStructure)
    with pytest.raises(UsageError, match="overrides are a scene's keys"):
        cosim.load(ssp, {"scene.step": 1e-3})


def test_simulate_runs_a_scene_by_name_with_named_columns():
    run = cosim.simulate("meng_eq35", overrides=BRIEF)
    assert run.names[0] == "time" and run["time"][-1] == pytest.approx(0.05, abs=1e-12)
    assert {"pose.z", "pose_ref.z", "torque[1]", "torque[6]"} <= set(run.names)
    assert run.report.simulated == pytest.approx(0.05) and "real-time factor" in run.report.text()


def test_a_scene_object_changes_through_its_document_not_its_file(tmp_path):
    """A Scene loaded from a file that then changes on disk: simulate's overrides apply over the
    scene as it was loaded (the file is not read again), and its duration argument over both."""
    path = tmp_path / "scene.toml"
    original = cosim.load("meng_eq35").path.read_text()
    path.write_text(original)
    scene = cosim.load(path, BRIEF)
    path.write_text(original.replace('kind = "pmsm"', 'kind = "linear"'))  # the file changes under it
    run = cosim.simulate(scene, overrides={"scene.step": 5e-4}, duration=0.02)
    assert "torque[1]" in run.names and "force[1]" not in run.names  # still the PMSM scene it was
    assert run["time"][-1] == pytest.approx(0.02, abs=1e-12) and np.allclose(np.diff(run["time"]), 5e-4)
    changed = scene.changed({"scene.step": 5e-4})
    assert changed.step == 5e-4 and scene.step == 1e-3 and changed.overrides["scene.duration"] == 0.05
    with pytest.raises(ValueError, match="init=False"):  # a change that would bypass the checks
        dataclasses.replace(scene, duration=1.0)
    with pytest.raises(cosim.SceneError, match="'scene.step' = -1.0: must be a positive number"):
        scene.changed({"scene.step": -1.0})


def test_simulate_runs_a_system_and_writes_its_results(ssp, tmp_path):
    from_file = cosim.simulate(ssp, settings={"step": "5e-4"}, out=tmp_path / "file")
    assert from_file.report.macro_steps == 100 and (tmp_path / "file" / "meng.csv").is_file()
    structure = cosim.load(ssp)
    from_object = cosim.simulate(structure, out=tmp_path / "object")  # written, not dropped
    assert (tmp_path / "object" / f"{structure.name}.csv").is_file()
    assert np.array_equal(from_object["pose.z"], cosim.simulate(ssp)["pose.z"])
    # with plots, the system's page and figure: every recorded output, one plot per component
    cosim.simulate(ssp, out=tmp_path / "plots", plots=True)
    page = (tmp_path / "plots" / "meng.html").read_text()
    assert all(f"{name}" in page for name in ("mechanics", "pose.z", "trajectory", "pmsm3"))
    assert (tmp_path / "plots" / "meng_outputs.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("arguments,message", [
    (dict(settings={"step": "5e-4"}), "settings are an SSP system's run settings"),
    (dict(plots=True), "plots are drawn into a folder"),
])
def test_simulate_refuses_what_does_not_apply_to_a_scene(arguments, message):
    with pytest.raises(UsageError, match=message):
        cosim.simulate("meng_eq35", overrides=BRIEF, **arguments)


@pytest.mark.parametrize("arguments,message", [
    (dict(overrides={"scene.step": 1e-3}), "overrides applies to a scene"),
    (dict(twin=True), "twin applies to a scene"),
])
def test_simulate_refuses_what_does_not_apply_to_a_system(ssp, arguments, message):
    with pytest.raises(UsageError, match=message):
        cosim.simulate(ssp, **arguments)


def test_export_ssp_writes_the_scene_that_runs_alike(ssp):
    scene = cosim.simulate("meng_eq35", overrides=BRIEF)
    system = cosim.simulate(ssp)
    assert np.array_equal(scene["pose.z"], system["pose.z"])  # the same run, bit for bit


def test_export_fmu_writes_the_scene_as_one_fmu_that_runs_alike(tmp_path):
    """The brief scene as ONE FMU (FMI 2.0 and 3.0), run alone by simulate: the scene's run bit for bit."""
    scene = cosim.simulate("meng_eq35", overrides=BRIEF)
    for fmi in (2, 3):
        fmu = cosim.export_fmu(cosim.load("meng_eq35", BRIEF), tmp_path / f"meng{fmi}.fmu", fmi=fmi)
        alone = cosim.simulate(fmu)
        assert np.array_equal(alone["time"], scene["time"]) and np.array_equal(alone["pose.z"], scene["pose.z"])


def test_sweep_runs_a_sweep_file_and_refuses_two_kinds_of_cluster(tmp_path):
    from cosim.engine.artifacts import ROOT
    path = tmp_path / "brief.toml"
    path.write_text(f'[sweep]\nscene = "{ROOT / "scenes" / "meng_eq35.toml"}"\nduration = 0.02\n'
                    '[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n')
    outcome = cosim.sweep(path, workers=0, out=tmp_path / "out")
    assert [r["scene.step"] for r in outcome.rows] == [5e-4, 1e-3] and all(r["status"] == "ok" for r in outcome.rows)
    assert all(f.is_file() for f in outcome.files)
    with pytest.raises(UsageError, match="give one of them"):
        cosim.sweep(path, workers=2, scheduler="tcp://127.0.0.1:8786", out=tmp_path / "out")
    with pytest.raises(UsageError, match="workers = -1"):
        cosim.sweep(path, workers=-1, out=tmp_path / "out")


def test_advise_finds_candidates_and_refuses_a_tolerance_of_zero():
    scene = cosim.load("meng_eq35", BRIEF)
    advice = cosim.advise(scene, 1e-3, effort_tolerance=0.2, probe=0.05, workers=0)
    within = [c for c in advice.candidates if c.diverged is None and c.error <= 1e-3 and c.effort_error <= 0.2
              and c.window_error <= 0.2]
    assert len(advice.candidates) > 10 and within, advice.text
    assert advice.recommended is min(within, key=lambda c: c.wall) and "recommended for" in advice.text
    with pytest.raises(UsageError, match="tolerance = 0"):
        cosim.advise(scene, 0.0)


def test_the_command_line_says_its_version(capsys):
    """`cosim --version`: the installed package's, which is pyproject.toml's (one source)."""
    import tomllib

    from cosim.cli import main
    from cosim.engine.artifacts import ROOT
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    wanted = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert capsys.readouterr().out.split()[-1] == wanted
