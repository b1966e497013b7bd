"""Scenes and the command line: shipped scenes load, wrong keys and values are named with their
line, the drive swaps by one line, and a run that fails mid-way says where and keeps its results."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import loadmat

from cosim.cli import main
from cosim.engine.artifacts import ROOT, fmu_path
from cosim.engine.outcome import RunStopped
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import SceneError, load_scene
from cosim.platform.run.compile import scene_structure
from cosim.platform.ports import DRIVES

SCENES = sorted((ROOT / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_shipped_scenes_load(path):
    scene = load_scene(path)
    assert scene.duration > 0 and scene.drive in DRIVES and scene.trajectory


def write(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


BASE = """[scene]
duration = 1.0
[drive]
kind = "pmsm"
[coupling]
order = 1
"""


@pytest.mark.parametrize("extra,message", [
    ('algoritm = "jacobi"\n', "scene.toml:7: 'coupling.algoritm' is not a known key"),
    ("[trajectory.surge]\n", "scene.toml:7: 'trajectory.surge' is not a known key"),
    ("[trajectory.x]\nsines = [{amplitude = 1.0, frequncy = 2.0}]\n", "scene.toml:8: 'trajectory.x.sines[1].frequncy' is not a known key"),
])
def test_a_wrong_key_is_named_with_its_line(tmp_path, extra, message):
    with pytest.raises(SceneError) as error:
        load_scene(write(tmp_path, BASE + extra))
    assert message.split(": ", 1)[0] in str(error.value)
    assert message.split(": ", 1)[1].split(" is")[0] in str(error.value)


@pytest.mark.parametrize("text,message", [
    (BASE.replace("order = 1", "order = 3"), ":6: 'coupling.order' = 3"),
    (BASE.replace('kind = "pmsm"', 'kind = "hydraulic"'), ":4: 'drive.kind' = 'hydraulic': use 'pmsm' or 'linear'"),
    (BASE.replace("duration = 1.0", "duration = -1"), ":2: 'scene.duration' = -1: must be a positive number"),
    (BASE.replace("duration = 1.0", 'duration = "long"'), ":2: 'scene.duration' = 'long'"),
    (BASE.replace("order = 1", "order = 1\ninterface_jacobian = 1"), ":7: 'coupling.interface_jacobian' = 1: must be true or false"),
    (BASE.replace("order = 1", "order = 0\ninterface_jacobian = true"),
     ":7: 'coupling.interface_jacobian' = true: needs coupling.order 1 or 2"),
])
def test_a_wrong_value_is_named_with_its_line(tmp_path, text, message):
    with pytest.raises(SceneError) as error:
        load_scene(write(tmp_path, text))
    assert message in str(error.value)


def test_cli_reports_a_bad_scene_and_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert "missing.toml: no such scene file" in capsys.readouterr().err


def test_a_missing_fmu_is_named_with_the_command_that_builds_it():
    with pytest.raises(FileNotFoundError, match=r"FMU 'hydraulic_drive' is not built .* run `bash scripts/setup.sh`"):
        fmu_path("hydraulic_drive")


def test_a_stale_build_is_refused_with_the_command_that_builds_it(monkeypatch, tmp_path):
    """The package never builds: a build stamp older than a C source is one line naming the command."""
    from cosim.engine import artifacts
    stamp = tmp_path / "built.stamp"
    stamp.touch()
    import os
    os.utime(stamp, (0, 0))
    monkeypatch.setattr(artifacts, "BUILD_STAMP", stamp)
    with pytest.raises(artifacts.ArtifactMissing, match=r"is older than .*: run `bash scripts/setup.sh`"):
        fmu_path("mechanics")


def test_swapping_the_drive_is_one_line_of_the_scene(tmp_path):
    """sumnu_case_1 with kind = "pmsm" instead of "linear": the two scene files differ in that line,
    the loaded scenes only in the drive kind, and the systems only in the drive connections."""
    original = (ROOT / "scenes" / "sumnu_case_1.toml").read_text()
    swapped = original.replace('kind = "linear"', 'kind = "pmsm"')
    differing = [(a, b) for a, b in zip(original.splitlines(), swapped.splitlines()) if a != b]
    assert differing == [('kind = "linear"', 'kind = "pmsm"')]
    a, b = load_scene(ROOT / "scenes" / "sumnu_case_1.toml"), load_scene(write(tmp_path, swapped))
    # the swapped drive is designed for the platform (tuning "auto"); the native one keeps its defaults
    assert {k for k in vars(a) if vars(a)[k] != vars(b)[k]} == {"drive", "path", "tuning", "drive_set", "text", "data",
                                                               "document", "algorithm"}
    assert a.algorithm.sequence != b.algorithm.sequence and a.algorithm.kind == b.algorithm.kind  # its components' names
    assert (a.tuning, b.tuning) == ("defaults", "auto")
    assert (a.drive_set, b.drive_set) == (None, "sumnu2015_pmsm")  # a PMSM and screw sized for these legs
    for scene in (a, b):
        wiring = DRIVES[scene.drive]
        from_drives = [c.target[1] for c in scene_structure(scene).connections
                       if c.target[0] == "mechanics" and c.target[1].startswith("leg[")]
        assert from_drives == [wiring.effort[1].format(i=i) for i in range(1, 7)]
        # each power bond is the drive's effort times the leg's own flow (speed, velocity), not the
        # reference's rate that a linear drive also takes
        bonds = scene_structure(scene).bonds
        assert [(b.effort.source[1], b.flow.source[1]) for b in bonds] == \
            [(wiring.effort[0], wiring.velocity[0].format(i=i)) for i in range(1, 7)]


def test_a_run_that_fails_names_the_fmu_and_keeps_its_results(tmp_path, capsys):
    """The Meng scene with the stroke as a hard stop: Eq 35 takes leg 4 past its 2.2 m stroke at
    0.634 s, the mechanics stops the run with an error, and the CLI names the instance, the call
    and the time, exits 1, and the CSV and .mat files hold the results up to the last good step."""
    text = (ROOT / "scenes" / "meng_eq35.toml").read_text().replace("duration = 10.0", "duration = 1.0")
    hard_stop = '"limit.hard_stop" = true\n'
    text = text.replace("[mechanics.parameters]\n", "[mechanics.parameters]\n" + hard_stop, 1) \
        if "[mechanics.parameters]\n" in text else text + "[mechanics.parameters]\n" + hard_stop
    scene_file = write(tmp_path, text)
    out = tmp_path / "out"
    assert main(["run", str(scene_file), "--out", str(out), "--no-plots"]) == 1
    err = capsys.readouterr().err
    assert "FAILED: mechanics: fmi2DoStep failed at t = 0.63" in err and "stroke" in err, err
    stopped = float(err.split("fmi2DoStep failed at t = ")[1].split(" s")[0])  # the failed step's start
    saved = np.genfromtxt(out / "scene.csv", delimiter=",", names=True)
    assert saved["time"][-1] == pytest.approx(stopped, abs=1e-9)  # the last good communication point
    mat = loadmat(out / "scene.mat")
    assert mat["pose_z"].size == saved.size
    with pytest.raises(RunStopped) as failed:
        run_scene(load_scene(scene_file))
    assert failed.value.report.failure.startswith("mechanics: fmi2DoStep failed at t = ")


def test_a_scene_table_drives_the_platform_like_the_signal_it_samples(tmp_path):
    """Sumnu case I's heave sine written as a CSV table (every 10 ms, cubic interpolation) and
    given as [trajectory] table: the run follows the run with the sine within 1e-6 m and rad (the
    table's interpolation error is ~1e-7 m; measured pose difference 7e-8 m). This caught a table
    giving a zero rate at its first row, which the drives' feedforward then missed."""
    original = (ROOT / "scenes" / "sumnu_case_1.toml").read_text().replace("duration = 5.0", "duration = 1.0")
    times = np.arange(0.0, 1.2, 0.01)
    np.savetxt(tmp_path / "heave.csv", np.c_[times, 0.2 * np.sin(3.0 * times)], delimiter=",",
               header="time,z", comments="# heave of Sumnu case I\n")
    tabled = original.replace("[trajectory.x]", '[trajectory]\ntable = "heave.csv"\n[trajectory.x]', 1)
    tabled = tabled.replace("offset = 1.0\nsines = [{amplitude = 0.2, frequency = 0.477464829275686}]", "offset = 1.0")
    assert tabled.count("sines") == original.count("sines") - 1
    with_sine, _ = run_scene(load_scene(write(tmp_path, original)))
    path = tmp_path / "tabled.toml"
    path.write_text(tabled)
    with_table, _ = run_scene(load_scene(path))
    for a in ("x", "y", "z", "roll", "pitch", "yaw"):
        np.testing.assert_allclose(with_table[f"pose.{a}"], with_sine[f"pose.{a}"], atol=1e-6)
    # the table travels in the SSP archive: exported, its source deleted, the archive runs the same
    assert main(["export", str(path), "--ssp", str(tmp_path / "tabled.ssp")]) == 0
    (tmp_path / "heave.csv").unlink()
    from cosim.engine.run import run_system
    from cosim.engine.ssp import read_ssp
    from_archive, _ = run_system(read_ssp(tmp_path / "tabled.ssp"), source=str(tmp_path / "tabled.ssp"))
    assert np.array_equal(from_archive["pose.z"], with_table["pose.z"])


@pytest.mark.parametrize("extra,message", [
    ('[trajectory]\ntable = "missing.csv"\n', ":8: 'trajectory.table' = 'missing.csv': no such file"),
    ("[trajectory.x]\nsines = [" + ", ".join(["{amplitude = 1.0, frequency = 1.0}"] * 4) + "]\n",
     ":8: 'trajectory.x.sines' has 4 entries; at most 3"),
    ("[load]\npulses = [" + ", ".join(['{component = "force.z", value = 1.0, start = 0.0, end = 1.0}'] * 3) + "]\n",
     ":8: 'load.pulses[3].component' = 'force.z': one pulse too many on it"),
])
def test_what_the_trajectory_fmu_cannot_hold_is_named_with_its_line(tmp_path, extra, message):
    with pytest.raises(SceneError) as error:
        load_scene(write(tmp_path, BASE + extra))
    assert message in str(error.value)


def test_outputs_choose_what_is_recorded_and_how_often(tmp_path):
    """[outputs]: mechanics energy accounts and the drives' voltage recorded, every 10 ms."""
    text = BASE + "[trajectory.z]\noffset = 1.689527733348906\n" + \
        '[outputs]\nmechanics = ["energy.kinetic", "power.drive"]\ndrive = ["torque", "voltage.q"]\ninterval = 0.01\n'
    result, _ = run_scene(load_scene(write(tmp_path, text).parent / "scene.toml"))
    assert {"energy.kinetic", "power.drive", "torque[1]", "voltage.q[6]"} <= set(result.dtype.names)
    assert "speed[1]" not in result.dtype.names
    np.testing.assert_allclose(np.diff(result["time"]), 0.01, atol=1e-9)


def test_an_unknown_output_is_named_with_its_line(tmp_path, capsys):
    text = BASE + '[outputs]\ndrive = ["torque", "torqe"]\n'
    with pytest.raises(SceneError) as error:
        run_scene(load_scene(write(tmp_path, text)))
    assert "scene.toml:8: 'outputs.drive'" in str(error.value) and "no variable 'torqe'" in str(error.value)
    assert main(["run", str(tmp_path / "scene.toml"), "--no-plots", "--out", str(tmp_path)]) == 2
    assert "no variable 'torqe'" in capsys.readouterr().err


def test_a_neutral_offset_is_the_pose_the_mechanics_starts_at(tmp_path):
    """offset = "neutral" is solved from the geometry: for the Meng scene it is the height at which
    the mechanics FMU starts (its own solve, bit for bit), and with a longer middle leg it rises so
    that every leg is again l_0 long."""
    from cosim.engine.fmi import FmuInstance
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    mechanics = FmuInstance(fmu_path("mechanics"), "mechanics")
    try:
        mechanics.initialize()
        assert scene.trajectory["z"].offset == mechanics.get("pose.z")
        legs = [mechanics.get(f"leg[{i}].length") for i in range(1, 7)]
    finally:
        mechanics.free()
    assert np.allclose(legs, 1.86, atol=1e-12)
    longer = load_scene(write(tmp_path, "[scene]\nduration = 1.0\n[mechanics.parameters]\n"
                                        '"geometry.middle_leg_length" = 1.96\n[trajectory.z]\noffset = "neutral"\n'))
    assert longer.trajectory["z"].offset > scene.trajectory["z"].offset + 0.05


def test_a_drive_that_cannot_hold_its_leg_is_named_before_the_run(tmp_path, capsys):
    """Sizing: six linear motors with their FMU's defaults (Sumnu's, 203 N continuous; the scene
    asks for no drive set) under the 950 kg Meng platform, whose legs each need 2066 N at the
    neutral pose: one line naming the leg, the load and the limit, exit 2."""
    text = (ROOT / "scenes" / "meng_eq35.toml").read_text().replace('kind = "pmsm"', 'kind = "linear"\nparameter_set = "none"')
    assert main(["run", str(write(tmp_path, text)), "--no-plots", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert ":8: drive.kind = 'linear' on meng2010: leg 1 needs 2066 N to hold the start pose, above " \
           "linear_motor's motor.continuous_force = 203 N" in err, err
    assert not (tmp_path / "out").exists()


def test_auto_tuning_on_the_meng_platform_reproduces_the_pmsm_defaults():
    """The documented rules applied to the plant the mechanics' core gives (J_eq = M_ii / (K_FT
    i_theta) = 0.0209 kg m^2 with the rotor, static torque 8.264 N m) give the FMU's own default
    gains, which were designed by hand for it, and the hold current the Meng scene types in."""
    from cosim.platform.scene.parameter_sets import mechanics_start_values
    from cosim.platform.run.tuning import design, leg_plants
    from cosim.engine.checks import variables
    values = mechanics_start_values("meng2010")
    designed = design("pmsm", leg_plants(values), {})
    defaults = {n: float(v.start) for n, v in variables(fmu_path("pmsm_drive")).items() if v.start is not None
                and v.type == "Real"}
    for leg in designed:
        for key in ("control.speed_kp", "control.speed_ki", "control.position_kp", "control.position_ki"):
            assert leg[key] == pytest.approx(defaults[key], rel=1e-3), key
        assert leg["initial.current_q"] == pytest.approx(5.509, rel=1e-3)


def test_explicit_gains_win_over_the_design_and_the_design_is_reported(tmp_path):
    """tuning = "auto" designs every leg; a gain the scene gives is kept on every leg; the run's
    report lists the designed gains."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 0.05, "drive.tuning": "auto",
                                                           'drive.parameters."control.speed_kp"': 5.0})
    structure = scene_structure(scene)
    drives = [c for c in structure.components if c.name.startswith("pmsm")]
    assert all(c.parameters["control.speed_kp"] == 5.0 for c in drives)
    assert all(c.parameters["initial.current_q"] == pytest.approx(5.509, rel=1e-3) for c in drives)
    _, report = run_scene(scene)
    assert "drive loops designed for the plant: speed_kp 5" in report.text()


def test_a_bad_tuning_is_named_with_its_line(tmp_path):
    with pytest.raises(SceneError, match=r"scene.toml:4: 'drive.tuning' = 'manual'"):
        load_scene(write(tmp_path, '[scene]\nduration = 1.0\n[drive]\ntuning = "manual"\n'))


def test_a_shipped_scene_is_reachable_by_name_and_the_cli_is_a_console_script(tmp_path, capsys):
    """`cosim run meng_eq35` (the console script pip installs, the same CLI as python -m cosim)
    runs the shipped scene by its name; a name close to one is a one-line error that names it."""
    import subprocess
    import sys
    from pathlib import Path
    assert load_scene("meng_eq35").path == ROOT / "scenes" / "meng_eq35.toml"
    with pytest.raises(SceneError, match=r"meng_eq53: no such scene file \(a shipped scene is named 'meng_eq35'\)"):
        load_scene("meng_eq53")
    script = Path(sys.executable).parent / "cosim"
    run = subprocess.run([str(script), "run", "sumnu_case_1", "--duration", "0.02", "--no-plots", "--out",
                          str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and (tmp_path / "sumnu_case_1.csv").exists(), run.stderr
    usage = subprocess.run([str(script), "--help"], capture_output=True, text=True, timeout=60)
    assert usage.returncode == 0 and usage.stdout.startswith("usage: cosim ")


def test_a_copy_of_the_python_files_alone_says_so_in_one_line(tmp_path):
    """The Python package copied without its data (neither a wheel's cosim/_data/ nor a checkout
    around it: no FMUs, libraries, parameter sets or scenes): run from another folder, a scene by
    name or by path ends in one line that says what is missing and how to install, exit 2, not a
    traceback."""
    import os
    import shutil
    import subprocess
    import sys
    copy = tmp_path / "site"
    shutil.copytree(ROOT / "cosim", copy / "cosim", ignore=shutil.ignore_patterns("__pycache__", "_data"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    # -S: no site module, so the editable install's import hook (a .pth file) does not take cosim
    # from the checkout; the dependencies from site-packages on the path
    import sysconfig
    path = os.pathsep.join([str(copy), sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]])
    for scene in ["meng_eq35", str(ROOT / "scenes" / "meng_eq35.toml")]:
        run = subprocess.run([sys.executable, "-S", "-m", "cosim", "run", scene, "--no-plots"], cwd=elsewhere,
                             env={**os.environ, "PYTHONPATH": path}, capture_output=True, text=True, timeout=120)
        assert run.returncode == 2, run.stderr
        assert str(copy / "cosim") in run.stderr
        assert run.stderr.count("\n") == 1 and "has neither its wheel's data nor a checkout" in run.stderr, run.stderr
        assert str(copy / "cosim") in run.stderr


def test_a_shipped_scene_or_sweep_is_copied_out_to_edit_and_runs_from_there(tmp_path, capsys):
    """`cosim copy NAME --to DIR` copies a shipped scene or sweep file (a sweep names its scene by
    name, so the copy runs anywhere); never over a file; a wrong name is one line with a hint."""
    assert main(["copy"]) == 0 and "meng_eq35_linear" in capsys.readouterr().out
    assert main(["copy", "meng_eq35", "--to", str(tmp_path / "mine")]) == 0
    copied = tmp_path / "mine" / "meng_eq35.toml"
    assert copied.read_text() == (ROOT / "scenes" / "meng_eq35.toml").read_text()
    assert main(["copy", "meng_coupling", "--to", str(tmp_path / "mine")]) == 0
    from cosim.platform.run.sweep import load_sweep
    assert load_sweep(tmp_path / "mine" / "meng_coupling.toml").evaluate.path == str(ROOT / "scenes" / "meng_eq35.toml")
    capsys.readouterr()
    assert main(["copy", "meng_eq35", "--to", str(tmp_path / "mine")]) == 2
    assert main(["copy", "meng_eq53"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "exists; copy elsewhere with --to" in err[0] and "did you mean 'meng_eq35'?" in err[1]


def test_every_shipped_name_is_one_file():
    """Scenes, sweep files and design studies are copied and run by name (`cosim copy NAME` takes the
    first folder that holds it): no name may stand for two of them."""
    from cosim.platform.scene import shipped_scenes
    names = [n for folder in ("scenes", "sweeps", "studies") for n in shipped_scenes(folder)]
    assert len(names) == len(set(names)), sorted(n for n in names if names.count(n) > 1)
