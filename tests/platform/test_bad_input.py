"""Bad input gets one clear line and loses nothing: every mistake below is reported by
`python -m cosim run` as one line naming the file, the line, the key, the value and the reason,
with exit code 2, before any FMU is instantiated or stepped, and the results of an earlier run in
the output folder stay as they were. A failure that is not the user's prints its traceback and
says that it is a bug (exit 3)."""

from __future__ import annotations

import pytest

from cosim.cli import main
from cosim.engine.artifacts import ROOT

# Meng's platform in a scene of the tests' own (the shipped scenes' layout and numerics may change)
MENG = """[scene]
name = "Meng's platform for the bad-input tests"
duration = 0.05
step = 1e-3

[drive]
kind = "pmsm"

[mechanics]
parameter_set = "meng2010"

[coupling]
algorithm = "gauss-seidel"
order = 1

[trajectory.x]
sines = [{amplitude = 0.1, frequency = 0.2}]
[trajectory.z]
offset = "neutral"
"""


def drive_parameter(line: str) -> str:
    return MENG.replace("\n[mechanics]\n", f"\n[drive.parameters]\n{line}\n\n[mechanics]\n", 1)


CASES = {
    "boolean as text": ('[scene]\nduration = 1.0\n[mechanics.parameters]\n"limit.hard_stop" = "false"\n',
                        ':4: mechanics.parameters."limit.hard_stop" = \'false\': must be true or false (mechanics)'),
    "integer with a fraction": (drive_parameter('"motor.pole_pairs" = 4.7'),
                                ':10: drive.parameters."motor.pole_pairs" = 4.7: must be a whole number (pmsm_drive)'),
    "value outside its bounds": (drive_parameter('"motor.resistance" = -0.7'),
                                 ':10: drive.parameters."motor.resistance" = -0.7: outside (0, inf] Ohm (pmsm_drive)'),
    "misspelt parameter": (drive_parameter('"motor.resistnce" = 0.7'),
                           "no such variable (did you mean 'motor.resistance'?) (pmsm_drive)"),
    "NaN amplitude": ("[scene]\nduration = 1.0\n[trajectory.x]\nsines = [{amplitude = nan, frequency = 1.0}]\n",
                      ":4: 'trajectory.x.sines[1].amplitude' = nan: must be a finite number"),
    "pulse that ends before it starts": (
        '[scene]\nduration = 1.0\n[load]\npulses = [{component = "force.z", value = 1.0, start = 2.0, end = 1.0}]\n',
        ":4: load.pulses (load.force.z.pulse[1].end): rejected by trajectory:"),
    "step longer than the run": ("[scene]\nduration = 0.0005\nstep = 0.001\n",
                                 ":3: 'scene.step' = 0.001: is longer than the scene's duration (0.0005 s)"),
    # found by mutating the shipped scene (issue 28): each was an internal-error traceback
    "sines as a number": (MENG.replace("sines = [{amplitude = 0.1, frequency = 0.2}]", "sines = 0", 1),
                          ":17: 'trajectory.x.sines' = 0: must be a list of inline tables"),
    "sines as infinity": (MENG.replace("sines = [{amplitude = 0.1, frequency = 0.2}]", "sines = inf", 1),
                          ":17: 'trajectory.x.sines' = inf: must be a list of inline tables"),
    "the [mechanics] header deleted": (MENG.replace("\n[mechanics]\n", "\n", 1),
                                       ":9: 'drive.parameter_set' = 'meng2010': is not one of the project's drive sets"),
    "a run whose results would not fit in memory": (MENG.replace("duration = 0.05", "duration = 1e12"),
                                                    ":4: scene.step = 0.001 s, duration 1e+12 s: the run would record "
                                                    "1e+15 rows of 31 columns"),
    # found by tests/fuzz/fuzz_inputs.py (each was an internal-error traceback)
    "an order of -0.0": (MENG.replace("order = 1", "order = -0.0"), ":14: 'coupling.order' = -0.0: must be a whole number in [0, 2]"),
    "a platform set that is a table": (MENG.replace('parameter_set = "meng2010"', "parameter_set = {}"),
                                       ":10: 'mechanics.parameter_set' = {}: use 'meng2010' or 'sumnu2015'"),
    "a mass set that is a number": (MENG.replace('parameter_set = "meng2010"', 'parameter_set = "meng2010"\nmass_set = 3'),
                                    ":11: 'mechanics.mass_set' = 3: must be text"),
    "a start pose that is a table": (MENG.replace('parameter_set = "meng2010"', 'parameter_set = "meng2010"\n'
                                                  '[mechanics.parameters]\n"initial.pose.z" = {}'),
                                     ':12: mechanics.parameters."initial.pose.z" = {}: must be a finite number (mechanics)'),
    "a finer start at a step of 0": (MENG.replace("order = 1", "order = 1\nstartup_time = 0.01\nstartup_step = 0"),
                                     ":16: 'coupling.startup_step' = 0: must be a positive number"),
    "a start pose out of reach": (MENG.replace('parameter_set = "meng2010"', 'parameter_set = "meng2010"\n'
                                               '[mechanics.parameters]\n"initial.pose.y" = -1e300'),
                                  ":11: the platform of [mechanics] at its start pose: the legs are singular at the pose"),
}


@pytest.fixture
def earlier_results(tmp_path):
    """An output folder holding the results of an earlier run, which no failed start may touch."""
    out = tmp_path / "out"
    out.mkdir()
    for name in ("scene.csv", "scene.mat", "scene.log"):
        (out / name).write_text("earlier run")
    return out


def assert_untouched(out) -> None:
    assert sorted(p.name for p in out.iterdir()) == ["scene.csv", "scene.log", "scene.mat"]
    assert all(p.read_text() == "earlier run" for p in out.iterdir())


@pytest.mark.parametrize("case", CASES)
def test_a_bad_scene_value_is_one_line_with_its_place_and_loses_nothing(case, tmp_path, earlier_results, capsys):
    text, message = CASES[case]
    path = tmp_path / "scene.toml"
    path.write_text(text)
    assert main(["run", str(path), "--no-plots", "--out", str(earlier_results)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"error: {path}") and message in err, err
    assert_untouched(earlier_results)


@pytest.mark.parametrize("arguments,message", [
    (["--duration", "-1"], "--duration -1: must be a positive finite number of seconds"),
    (["--duration", "nan"], "--duration nan: must be a positive finite number of seconds"),
    (["--duration", "0"], "--duration 0: must be a positive finite number of seconds"),
    (["--duration", "ten"], "--duration ten: must be a positive finite number of seconds"),
])
def test_bad_command_line_arguments_are_one_line(arguments, message, earlier_results, capsys):
    assert main(["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--out", str(earlier_results), *arguments]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err
    assert_untouched(earlier_results)


def ssd_mutant(tmp_path, change) -> str:
    """The Meng scene's exported SSD, unpacked beside its resources, with one change."""
    import zipfile
    archive = tmp_path / "meng.ssp"
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(archive)]) == 0
    with zipfile.ZipFile(archive) as z:
        z.extractall(tmp_path / "unpacked")
    ssd = tmp_path / "unpacked" / "SystemStructure.ssd"
    text = ssd.read_text()
    changed = change(text)
    assert changed != text
    ssd.write_text(changed)
    return str(ssd)


CONNECTION = '<ssd:Connection startElement="mechanics" startConnector="leg[1].angle_ref" endElement="pmsm1" ' \
             'endConnector="angle_ref"/>'


@pytest.mark.parametrize("change,message", [
    (lambda t: t.replace('startConnector="leg[1].angle_ref"', 'startConnector="leg[0].angle_ref"'),
     "connection starts at 'mechanics.leg[0].angle_ref', which is no connector of 'mechanics'"),
    (lambda t: t.replace('<ssd:Connector name="leg[1].angle_ref" kind="output">',
                         '<ssd:Connector name="leg[1].angle_rfe" kind="output">'),
     "connector 'leg[1].angle_rfe' of component 'mechanics': mechanics.fmu has no such variable (did you mean "
     "'leg[1].angle_ref'?)"),
    (lambda t: t.replace('<ssd:Connector name="leg[1].angle_ref" kind="output">',
                         '<ssd:Connector name="leg[1].angle_ref" kind="input">'),
     "connector 'leg[1].angle_ref' of component 'mechanics' is declared input, but mechanics.fmu has it as output"),
    (lambda t: t.replace(CONNECTION, CONNECTION + CONNECTION.replace("leg[1].angle_ref", "leg[2].angle_ref")),
     "input 'pmsm1.angle_ref' takes a second connection"),
])
def test_a_broken_ssd_is_one_line_before_anything_is_instantiated(tmp_path, change, message, capsys):
    """Each connector against its FMU's modelDescription and each connection against SSP's rules
    (issue 28: a connection to a variable the FMU lacks was a KeyError traceback, a connector
    the FMU lacks was accepted without a word)."""
    path = ssd_mutant(tmp_path, change)
    capsys.readouterr()
    assert main(["run", path, "--duration", "0.01", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and message in err, err
    assert err.startswith(f"error: {path}:") and not (tmp_path / "out").exists()


def test_a_folder_given_as_the_scene_is_one_line(capsys):
    assert main(["run", str(ROOT / "scenes")]) == 2
    assert "is a folder, not a scene file" in capsys.readouterr().err


def test_an_unexpected_failure_says_it_is_a_bug(monkeypatch, capsys):
    import cosim.api as api  # what `cosim run` calls (imported when the command runs)

    def broken(*args, **kwargs):
        raise ZeroDivisionError("deliberately broken for this test")

    monkeypatch.setattr(api, "simulate", broken)
    assert main(["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--no-plots"]) == 3
    err = capsys.readouterr().err
    assert "Traceback" in err and "is a bug in cosim" in err


def test_every_warning_is_in_the_log_beside_the_results(tmp_path, capsys):
    """The Meng scene's own motion takes legs past the stroke: each warning is a row of
    <scene>.log with the step in which it was raised, the summary counts them by kind."""
    import csv
    from cosim.platform.scene import load_scene
    path = ROOT / "scenes" / "meng_eq35.toml"
    step = load_scene(path).control.step  # the regular step (the warnings come after the finer start)
    assert main(["run", str(path), "--no-plots", "--duration", "1.0", "--out", str(tmp_path)]) == 0
    with open(tmp_path / "meng_eq35.log") as f:
        rows = list(csv.DictReader(f))
    warnings = [r for r in rows if r["status"] == "warning"]
    assert warnings and all(r["instance"] == "mechanics" for r in warnings)
    for r in warnings:  # the FMU's own time in the text is the end of the step that raised it
        t = float(r["message"].split("t = ")[1].split(" s")[0])
        assert t == pytest.approx(float(r["step_start"]) + step, abs=1e-9)
    out = capsys.readouterr().out
    assert f"{len(warnings)} warnings from the FMUs (" in out and "x mechanics: leg # length # m is outside the stroke" in out


def test_an_output_folder_that_cannot_be_written_is_one_line_before_the_run(tmp_path, capsys):
    """--out below a file: one line, exit 2, before anything runs (so nothing computed is lost)."""
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    for command in (["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--no-plots"],
                    ["sweep", str(ROOT / "sweeps" / "meng_coupling.toml"), "--workers", "0"]):
        assert main([*command, "--out", str(blocker / "out")]) == 2
        err = capsys.readouterr().err.strip()
        assert err == f"error: --out {blocker / 'out'}: cannot write results there ({blocker} is not a folder)", err


def test_set_on_a_scene_sets_its_keys_or_refuses_in_one_line(tmp_path, capsys):
    """`cosim run SCENE --set`: a run setting by its name (step) or any key of the scene as its file
    writes it takes effect, checked as the file's own; what a scene does not take is one line."""
    scene = str(ROOT / "scenes" / "meng_eq35.toml")
    brief = ["--duration", "0.1", "--no-plots", "--out", str(tmp_path), "--set", "coupling.startup_time=0", "--set",
             "coupling.edge_time=0"]
    assert main(["run", scene, *brief, "--set", "step=5e-4"]) == 0
    assert "0.1 s simulated in" in capsys.readouterr().out
    import numpy as np
    times = np.genfromtxt(tmp_path / "meng_eq35.csv", delimiter=",", names=True)["time"]
    assert np.allclose(np.diff(times), 5e-4)  # the step the option set, not the scene's 1 ms
    assert main(["run", scene, *brief, "--set", 'mechanics.parameters."platform.mass"=1100']) == 0
    capsys.readouterr()
    # an error about a value --set gave names the option, not the shipped file's line
    for setting, message in (("bogus=1", "--set bogus=1: 'bogus' is not a run setting a scene takes"),
                             ("scene.bogus=1", "--set scene.bogus=1 (over "),
                             ("bogus.key=1", "--set bogus.key=1 (over "),  # a table the file has not
                             ("mechanics.parameterz.mass=1", "--set mechanics.parameterz.mass=1 (over "),
                             ("step=fast", "--set step=fast (over "),
                             ("step=-1e-3", "--set step=-1e-3 (over "),
                             ('mechanics.parameters."platform.mass"=-5',
                              '--set mechanics.parameters."platform.mass"=-5 (over '),
                             ("step=3", "--set step=3 (over "),
                             ("sequence=a b", "--set sequence=a b: 'sequence' is not a run setting a scene takes")):
        assert main(["run", scene, *brief, "--set", setting]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err and "meng_eq35.toml:" not in err, err


def test_set_on_an_ssp_sets_its_run_settings_or_refuses_in_one_line(tmp_path, capsys):
    """`cosim run SYSTEM.ssp --set`: the system's run settings by name (cosim.engine.settings), as
    `cosim.simulate(ssp, settings=...)` takes them; a scene's keys are not the system's."""
    from cosim.api import export_ssp
    archive = export_ssp("meng_eq35", tmp_path / "meng.ssp", measure=False)
    brief = ["--duration", "0.01", "--out", str(tmp_path / "out")]
    assert main(["run", str(archive), *brief, "--set", "windows=", "--set", "startup_time=0", "--set", "step=5e-4"]) == 0
    capsys.readouterr()
    import numpy as np
    times = np.genfromtxt(tmp_path / "out" / "meng.csv", delimiter=",", names=True)["time"]
    assert np.allclose(np.diff(times), 5e-4)
    for setting, message in (("bogus=1", "meng.ssp: unknown setting 'bogus'"),
                             ("step=fast", "meng.ssp: step 'fast'")):
        assert main(["run", str(archive), *brief, "--set", setting]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err


def test_a_closed_pipe_ends_the_command_quietly(tmp_path):
    """`cosim run ... | head -1` and `cosim copy | head -1`, the reader gone before the output is
    printed: exit 0 and nothing on stderr (as `cat` does), not a BrokenPipeError."""
    import subprocess
    import sys
    for command in (["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--duration", "0.05", "--no-plots", "--out",
                     str(tmp_path)], ["copy"]):
        process = subprocess.Popen([sys.executable, "-m", "cosim", *command], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE)
        process.stdout.close()  # the reader goes away at once
        err = process.stderr.read().decode()
        assert process.wait(timeout=120) == 0 and err == "", (command, err)


def test_ctrl_c_during_a_run_is_one_line(tmp_path):
    """SIGINT while a scene runs (whichever FMU call or callback it lands in): one line, exit 130,
    never an interrupt swallowed in an FMU's logger and the run going on."""
    import signal
    import subprocess
    import sys
    import time
    process = subprocess.Popen([sys.executable, "-m", "cosim", "run", str(ROOT / "scenes" / "meng_eq35.toml"),
                                "--duration", "600", "--no-plots", "--out", str(tmp_path)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(2.0)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=120)
    assert process.returncode == 130 and err == "interrupted\n" and out == "", (err, out)


VEHICLE_HEADER = "time,specific_force.x,specific_force.y,specific_force.z,angular_rate.x,angular_rate.y,angular_rate.z"
VEHICLE_ROWS = [f"{0.01 * k:g},{0.5 * (k > 5):g},0,9.81,0,0,0" for k in range(40)]


@pytest.mark.parametrize("break_it, reason", [
    (lambda rows: rows[:5] + ["0.005,0,0,9.8,0,0,0"] + rows[6:], "does not increase"),               # time goes back
    (lambda rows: rows[:5] + ["0.05,0,0,9.8,nan,0,0"] + rows[6:], "finite numbers"),                 # a NaN cell
    (lambda rows: [",".join(r.split(",")[1:]) for r in rows], "the first column must be 'time'"),    # no time column
    (lambda rows: [rows[0].replace("specific_force.x", "specfic_force.x"), *rows[1:]], "'specfic_force.x' is unknown"),
    (lambda rows: rows[:5] + ["0.05,0,,9.8,0,0,0"] + rows[6:], "finite numbers"),                    # an empty cell
    (lambda rows: rows[:2] + ["0.01,0,0,9.8,0,0,1e300"] + rows[3:],                                   # no vehicle's
     "angular_rate.z = 1e+300 rad/s at t = 0.01 s is beyond any vehicle's motion (at most 100 rad/s)"),
    (lambda rows: [rows[0].replace("angular_rate.z", "specific_force.x"), *rows[1:]],                # a column twice
     "column 'specific_force.x' is repeated"),
    (lambda rows: [r.replace(",", ";") for r in rows], "the columns are separated by ';'"),           # a decimal comma's
])
@pytest.mark.parametrize("command", ["run", "tune"])
def test_a_bad_vehicle_table_is_one_line_through_run_and_tune(tmp_path, capsys, break_it, reason, command):
    """The cueing FMU refuses the table with its file and line; the command names the scene's
    motion.vehicle key beside it, exit 2 (the error path names the cueing component by its name:
    no component is taken for a drive)."""
    (tmp_path / "drive.csv").write_text("\n".join(break_it([VEHICLE_HEADER, *VEHICLE_ROWS])) + "\n")
    scene = tmp_path / "car.toml"
    scene.write_text('[scene]\nduration = 0.3\n\n[drive]\nkind = "pmsm"\n\n[motion]\nvehicle = "drive.csv"\n')
    code = main([command, str(scene), *(["--no-plots", "--out", str(tmp_path / "out")] if command == "run" else [])])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert f"{scene}:8: motion.vehicle: rejected by cueing: vehicle.file {tmp_path / 'drive.csv'}:" in err
    assert reason in err


MPC_SCENE = '[scene]\nduration = 0.3\n\n[drive]\nkind = "pmsm"\n\n[motion]\nvehicle = "drive.csv"\n\n' \
            '[cueing]\nalgorithm = "mpc"\n\n[cueing.parameters]\n'


@pytest.mark.parametrize("values, line, key, reason", [
    ('"mpc.period" = 4.0\n', 14, '"mpc.period"', "mpc.horizon = 3 s is shorter than its 12 intervals"),
    ('"mpc.period" = 0.0205\n', 14, '"mpc.period"', "which is no whole number of the scene's steps of 0.001 s"),
    ('"mpc.weight.angular_rate" = 0\n"mpc.weight.specific_force" = 0.0\n', 15, '"mpc.weight.specific_force"',
     "both 0: the MPC would have nothing felt to bring close"),
])
def test_what_the_mpc_cannot_mean_is_one_line_at_its_key(tmp_path, capsys, values, line, key, reason):
    """An MPC period longer than its horizon's intervals allow (named at the period the scene sets,
    not at the horizon it leaves to the FMU), one that is no whole number of steps, both weights of
    what is felt 0: each one line at the scene's line of the key, exit 2."""
    (tmp_path / "drive.csv").write_text("\n".join([VEHICLE_HEADER, *VEHICLE_ROWS]) + "\n")
    scene = tmp_path / "car.toml"
    scene.write_text(MPC_SCENE + values)
    code = main(["run", str(scene), "--no-plots", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"error: {scene}:{line}:") and f'cueing.parameters.{key}' in err and reason in err, err


@pytest.mark.parametrize("command", ["run", "tune"])
def test_a_vehicle_scene_too_long_to_record_is_one_line_through_run_and_tune(tmp_path, capsys, command):
    """A cueing scene of 1e12 s at 1 ms would record 1e15 rows: `tune` screens the scene's own
    cueing first and `run` records the system; both refuse at scene.step with the scene's file
    and line, exit 2, before a step (CI's input fuzzer found tune's traceback)."""
    (tmp_path / "drive.csv").write_text("\n".join([VEHICLE_HEADER, *VEHICLE_ROWS]) + "\n")
    scene = tmp_path / "car.toml"
    scene.write_text('[scene]\nduration = 1e12\nstep = 1e-3\n\n[drive]\nkind = "pmsm"\n\n'
                     '[motion]\nvehicle = "drive.csv"\n')
    code = main([command, str(scene), *(["--no-plots", "--out", str(tmp_path / "out")] if command == "run" else [])])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"error: {scene}:3: scene.step = 0.001 s, duration 1e+12 s: the run would record"), err


def test_export_takes_set_and_duration(tmp_path, capsys):
    """`cosim export SCENE --set KEY=VALUE --duration S`: the variant is exported (its value in the
    SSV and in the FMU that carries it, its stop time in the SSD), the scene file unchanged; a bad
    value is one line naming the option."""
    from cosim.engine.ssp import read_ssp
    scene = str(ROOT / "scenes" / "meng_eq35.toml")
    before = (ROOT / "scenes" / "meng_eq35.toml").read_text()
    archive = tmp_path / "variant.ssp"
    assert main(["export", scene, "--ssp", str(archive), "--scene-step", "--duration", "2",
                 "--set", 'mechanics.parameters."platform.mass"=1100']) == 0
    structure = read_ssp(archive)
    assert structure.experiment.stop == 2.0 and structure.component("mechanics").parameters["platform.mass"] == 1100.0
    assert (ROOT / "scenes" / "meng_eq35.toml").read_text() == before
    capsys.readouterr()
    for arguments, message in ((["--set", "step=-1"], "--set step=-1 (over "), (["--duration", "-3"], "--duration -3:")):
        assert main(["export", scene, "--ssp", str(archive), "--scene-step", *arguments]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err


def test_a_reference_the_platform_cannot_take_is_refused_before_its_run(tmp_path, capsys):
    """A roll amplitude of 5 (degrees meant, read as radians) takes the legs past any joint: refused
    in one line naming the scene's line of that angle and what it reaches, before the run (no
    results written), not when the mechanics stops part way."""
    scene = tmp_path / "tilted.toml"
    scene.write_text('[scene]\nduration = 3.0\n[mechanics]\nparameter_set = "meng2010"\n[trajectory.z]\n'
                     'offset = "neutral"\n[trajectory.roll]\nsines = [{amplitude = 5, frequency = 0.3}]\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "tilted.toml:7: the reference takes leg" in err, err
    assert "its roll reaches 5 rad (286 deg): a scene's angles are radians" in err
    assert not list((tmp_path / "out").glob("*.csv"))


def test_the_dof_an_impossible_pose_needs_is_blamed_not_the_farthest(tmp_path, capsys):
    """A yaw of 1.5 rad, which Meng's platform takes alone, and a pitch of 1.4, which it does not:
    the pitch is named (its line), though the yaw is the farther from neutral."""
    scene = tmp_path / "pitched.toml"
    scene.write_text('[scene]\nduration = 1.0\n[mechanics]\nparameter_set = "meng2010"\n[trajectory.z]\n'
                     'offset = "neutral"\n[trajectory.yaw]\noffset = 1.5\n[trajectory.pitch]\noffset = 1.4\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pitched.toml:9: the reference takes leg" in err, err


@pytest.mark.parametrize("column, value, hint", [("z", -10.0, ""),
                                                 ("roll", 3.0, "its roll reaches 3 rad (172 deg): a scene's angles")])
def test_a_table_the_platform_cannot_take_names_its_row(tmp_path, capsys, column, value, hint):
    """A trajectory table (a comment, its header, rows 10 ms apart) whose z (below the base) or roll
    (upside down) jumps past any joint from 0.5 s: refused before the run in one line at the scene's table line,
    naming the table's row there (its file and line), not the scene's file alone."""
    rows = [f"{t / 100:g},{value if t >= 50 else 0.0:g}" for t in range(101)]
    (tmp_path / "reference.csv").write_text("# a reference\n" + f"time,{column}\n" + "\n".join(rows) + "\n")
    scene = tmp_path / "table.toml"
    scene.write_text('[scene]\nduration = 1.0\n[mechanics]\nparameter_set = "meng2010"\n[trajectory]\n'
                     'table = "reference.csv"\n[trajectory.z]\noffset = "neutral"\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{scene}:6: the reference takes leg" in err, err
    assert "at t = 0.500 s (the joints would cross)" in err and hint in err
    assert err.rstrip().endswith(f"the table's row there: {tmp_path / 'reference.csv'}:53"), err  # t = 0.5: line 53


@pytest.mark.parametrize("command", [["run", "--no-plots", "--out", "{out}"], ["export", "--ssp", "{out}/a.ssp"],
                                     ["export", "--fmu", "{out}/a.fmu"], ["export", "--fmu", "{out}/a.fmu", "--me"]])
def test_a_reference_no_tool_could_run_is_refused_by_run_and_every_export(tmp_path, capsys, command):
    """A height of 1e300 m crosses the joints at the start: `run` and every export refuse it at the
    line of the DOF that asks it, one line, nothing written (CI's input fuzzer found the SSP
    export's traceback: its start-up sweep ran into the mechanics' refusal)."""
    scene = tmp_path / "high.toml"
    scene.write_text('[scene]\nduration = 1.0\n[mechanics]\nparameter_set = "meng2010"\n[trajectory.x]\n'
                     'sines = [{amplitude = 0.01, frequency = 1.0}]\n[trajectory.z]\noffset = 1e300\n')
    out = tmp_path / "out"
    out.mkdir()
    assert main([command[0], str(scene), *(a.format(out=out) for a in command[1:])]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {scene}:7: the reference takes leg "), err
    assert "(the joints would cross)" in err and not list(out.iterdir())


@pytest.mark.parametrize("scale, says", [
    (1.0, "the drive ends at 0.39 s, the scene at 0.5 s: its last row is held for the rest"),
    (1000.0, "its rows are 10 apart and it ends at 390: are its times milliseconds?"),
])
def test_a_drive_that_fits_its_scene_badly_is_said_in_the_report(tmp_path, scale, says):
    """A vehicle's drive shorter than its scene (its last row held), or one timed in milliseconds
    (the scene would cue its first instants alone): what a user may mean, so said, not refused,
    at the scene's motion.vehicle line."""
    rows = [",".join([f"{float(r.split(',')[0]) * scale:g}", *r.split(",")[1:]]) for r in VEHICLE_ROWS]
    (tmp_path / "drive.csv").write_text("\n".join([VEHICLE_HEADER, *rows]) + "\n")
    scene = tmp_path / "car.toml"
    scene.write_text('[scene]\nduration = 0.5\n\n[drive]\nkind = "pmsm"\n\n[motion]\nvehicle = "drive.csv"\n')
    import cosim
    remarks = cosim.simulate(scene).report.remarks
    assert any(f"{scene}:8: motion.vehicle: {says}" in remark for remark in remarks), remarks
