"""A drive FMU of the user's own, in one line of a scene (issue 26): drives built here by another
tool than our CMake (pythonfmu, from the Python servos in tests/platform/drives/) run on Meng's
platform, alone and mixed with ours; each FMU that cannot drive a leg is a one-line error naming
the FMU, the port and the reason; what the FMU cannot do limits the master; the SSP export carries
the FMU and runs bit for bit like the scene.

The servos are plain PD(+I) position loops whose gains are designed here for the leg they drive
(critically damped at 10 Hz on the leg's inertia M_ii), so their static stiffness is known: at rest
each leg gives way by exactly its static force over that stiffness, which the tests hold to 1e-3
(the deflection moves the pose, and with it the static force, by less than that).
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from cosim.cli import main
from cosim.engine.run import run_system
from cosim.engine.ssp import read_ssp
from cosim.engine.ssp import write_ssp
from cosim.platform.ports import LEGS
from cosim.platform.run.compile import scene_structure, scene_values
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import SceneError, load_scene
from cosim.platform.run.tuning import leg_plants

DRIVES = Path(__file__).parent / "drives"
BANDWIDTH = 2 * math.pi * 10.0  # [rad/s] the servos' design


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict[str, Path]:
    """The two servos exported by pythonfmu (the linear one with its state: --handle-state)."""
    out = tmp_path_factory.mktemp("user_drives")
    for name, extra in (("rotary_servo", []), ("linear_servo", ["--handle-state"])):
        subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(DRIVES / f"{name}.py"), "-d", str(out),
                        *extra], check=True, capture_output=True)
    return {name: out / f"{name}.fmu" for name in ("rotary_servo", "linear_servo")}


def plant(kind: str):
    """Leg 1's plant on Meng's platform with this drive kind (the rotary's on the motor side)."""
    scene = load_scene("meng_eq35_linear" if kind == "linear" else "meng_eq35")
    return leg_plants(scene_values(scene)[0])


def gains(kind: str) -> dict[str, float]:
    """PD gains, critically damped at BANDWIDTH on leg 1's inertia (all legs alike at neutral)."""
    leg = plant(kind)[0]
    inertia = leg.mass if kind == "linear" else leg.mass / (leg.force_torque * leg.screw_ratio)  # kg, or kg m^2
    return {"kp": inertia * BANDWIDTH ** 2, "kd": 2 * inertia * BANDWIDTH}


def scene_file(folder: Path, drive: str, motion: bool = False, duration: float = 1.5, extra: str = "") -> Path:
    """Meng's platform under a drive section: at rest at the neutral pose, or in part of Eq 35."""
    motion_text = """sines = [{amplitude = 0.3, frequency = 0.2}]
[trajectory.yaw]
sines = [{amplitude = 0.261799387799149, frequency = 0.3}]
[trajectory.x]
sines = [{amplitude = 0.1, frequency = 0.2}]""" if motion else ""
    path = folder / "scene.toml"
    path.write_text(f"""[scene]
duration = {duration}
step = 1e-3
{drive}
[mechanics]
parameter_set = "meng2010"
{extra}
[outputs]
mechanics = [{", ".join(f'"leg[{i}].angle", "leg[{i}].angle_ref", "leg[{i}].length", "leg[{i}].length_ref"'
                       for i in LEGS)}]
[trajectory.z]
offset = "neutral"
{motion_text}
""")
    return path


def drive_section(fmu: Path, folder: Path, kind: str, **more) -> str:
    values = {**gains(kind), **more}
    local = folder / fmu.name
    if not local.exists():
        local.write_bytes(fmu.read_bytes())
    return f'[drive]\nfmu = "{fmu.name}"\n[drive.parameters]\n' + "\n".join(f"{k} = {v!r}" for k, v in values.items())


@pytest.mark.parametrize("kind", ["rotary", "linear"])
def test_a_users_servo_holds_each_leg_with_its_own_stiffness(kind, fmus, tmp_path):
    fmu = fmus[f"{kind}_servo"]
    linear = kind == "linear"
    pd = {} if linear else {"ki": 0.0}  # the rotary servo's integral off: a pure stiffness at rest
    scene = load_scene(scene_file(tmp_path, drive_section(fmu, tmp_path, "linear" if linear else "pmsm", **pd)))
    assert scene.drive == ("linear" if linear else "pmsm") and scene.drive_fmu == (tmp_path / fmu.name).resolve()
    result, report = run_scene(scene)
    assert report.failure is None
    stiffness = gains("linear" if linear else "pmsm")["kp"]
    plants = plant("linear" if linear else "pmsm")
    last = result[-1]
    for i, leg in zip(LEGS, plants):
        if linear:  # position_ref - position = F / kp
            deflection, expected = last[f"leg[{i}].length_ref"] - last[f"leg[{i}].length"], leg.static_force / stiffness
        else:       # angle_ref - angle = (F / K_FT) / kp
            deflection = last[f"leg[{i}].angle_ref"] - last[f"leg[{i}].angle"]
            expected = leg.static_force / leg.force_torque / stiffness
        assert deflection == pytest.approx(expected, rel=1e-3), (i, deflection, expected)
    # the effort recorded is the servo's: what holds the leg
    effort = "force" if linear else "torque"
    static = [p.static_force / (1.0 if linear else p.force_torque) for p in plants]
    assert [last[f"{effort}[{i}]"] for i in LEGS] == pytest.approx(static, rel=1e-3)
    assert f"drive FMU {fmu.name}" in report.text() and "PythonFMU" in report.text()


def test_a_users_servo_tracks_eq35_and_mixes_with_ours(fmus, tmp_path):
    """Leg 3 on the Python servo (PID), the other five on our PMSM drive: Eq 35's heave, surge and
    yaw for 3 s. The servo's leg follows its reference closer than the servo's pure stiffness
    would hold the static load (F/k, 0.36 mm; the integral takes that part), and the platform
    tracks as it does on six of our drives to within that compliance."""
    values = {**gains("pmsm"), "ki": gains("pmsm")["kp"] * BANDWIDTH / 10}
    (tmp_path / "rotary_servo.fmu").write_bytes(fmus["rotary_servo"].read_bytes())
    drive = "[drive]\nkind = \"pmsm\"\n[drive.leg.3]\nfmu = \"rotary_servo.fmu\"\nparameters = {" + \
        ", ".join(f"{k} = {v!r}" for k, v in values.items()) + "}"
    scene = load_scene(scene_file(tmp_path, drive, motion=True, duration=3.0))
    assert scene.leg_fmus == {3: (tmp_path / "rotary_servo.fmu").resolve()} and scene.drive_fmu is None
    structure = scene_structure(scene)
    fmus_of = {c.name: c.fmu.name for c in structure.components}
    assert fmus_of["pmsm3"] == "rotary_servo.fmu" and fmus_of["pmsm2"] == "pmsm_drive.fmu"
    assert "initial.current_q" in next(c for c in structure.components if c.name == "pmsm2").parameters
    assert next(c for c in structure.components if c.name == "pmsm3").parameters == values
    result, report = run_scene(scene)
    assert report.failure is None
    compliance = plant("pmsm")[2].static_force / plant("pmsm")[2].force_torque / values["kp"] / \
        plant("pmsm")[2].screw_ratio  # [m] of leg 3
    late = result["time"] >= 0.3
    assert np.abs(result["leg[3].length_ref"] - result["leg[3].length"])[late].max() < compliance
    ours = run_scene(load_scene(scene_file(tmp_path, '[drive]\nkind = "pmsm"', motion=True, duration=3.0)))[0]
    def leg_errors(run):
        return [np.abs(run[f"leg[{i}].length_ref"] - run[f"leg[{i}].length"])[late].max() for i in LEGS]
    assert max(leg_errors(result)) < max(leg_errors(ours)) + compliance, (leg_errors(result), leg_errors(ours))
    assert "current.q[1]" not in result.dtype.names  # the servo has no current: not recorded for any leg
    assert "on legs 3" in report.text() and "sizing not checked for legs 3" in report.text()
    # the headline names what ran: the user's FMU on its leg, ours on the others
    assert "the user's rotary_servo.fmu on leg 3, PMSM drives on the others]" in report.text().splitlines()[0]


def test_a_users_co_simulation_fmu_is_one_line_for_a_model_exchange_run(fmus, tmp_path, capsys):
    """`cosim run --me` needs every FMU as Model Exchange: a user's Co-Simulation servo is named in
    one line, exit 2."""
    (tmp_path / "rotary_servo.fmu").write_bytes(fmus["rotary_servo"].read_bytes())
    drive = '[drive]\nkind = "pmsm"\n[drive.leg.3]\nfmu = "rotary_servo.fmu"'
    scene = scene_file(tmp_path, drive, duration=0.1)
    assert main(["run", str(scene), "--me", "--no-plots", "--out", str(tmp_path / "out")]) == 2
    said = capsys.readouterr().err.strip().splitlines()
    assert said == ["error: pmsm3: rotary_servo.fmu is Co-Simulation only (no Model Exchange FMU of it): this system "
                    "runs as co-simulation"]


def test_the_ssp_export_carries_the_users_fmu_and_runs_bit_for_bit(fmus, tmp_path, capsys):
    scene = load_scene(scene_file(tmp_path, drive_section(fmus["rotary_servo"], tmp_path, "pmsm"), motion=True,
                                  duration=0.5))
    result, _ = run_scene(scene)
    path = write_ssp(scene_structure(scene), tmp_path / "user.ssp")
    with zipfile.ZipFile(path) as archive:
        assert "resources/rotary_servo.fmu" in archive.namelist()
    again, _ = run_system(read_ssp(path), source=str(path))
    assert again.dtype.names == result.dtype.names
    assert all(np.array_equal(again[n], result[n]) for n in result.dtype.names)
    # the engine reads the capability flags of any system's FMUs: no state, no step doubling
    assert main(["run", str(path), "--set", "step_control=doubling", "--no-plots"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pmsm1 (rotary_servo.fmu) cannot get and set its state" in err, err


def test_the_peers_run_a_users_drive_as_they_run_ours(fmus, tmp_path):
    """Leg 3 on the Python servo beside five of ours, exported as SSP and run by Ecos and fmpy.ssp
    (bit for bit like our master, as for the all-ours system: tests/platform/test_ssp_tools.py)
    and libcosim (the pose to 1e-12 there too; the torques to 1e-8, not 1e-10: the servo
    differentiates its reference over the step, which turns libcosim's integer-nanosecond clock's
    round-off in the trajectory's times into differences 1/h = 1e3 times larger)."""
    import test_ssp_tools as peers
    (tmp_path / "rotary_servo.fmu").write_bytes(fmus["rotary_servo"].read_bytes())
    drive = '[drive]\nkind = "pmsm"\n[drive.leg.3]\nfmu = "rotary_servo.fmu"\nparameters = {' + \
        ", ".join(f"{k} = {v!r}" for k, v in gains("pmsm").items()) + "}"
    path = tmp_path / "mixed.ssp"
    assert main(["export", str(scene_file(tmp_path, drive, motion=True)), "--ssp", str(path)]) == 0
    peers.ecos_matches(path)
    peers.fmpy_matches(path, bindings=True)  # the user's FMU carries no values of its own
    peers.libcosim_matches(path, tmp_path / "libcosim", torque_rel=1e-8)


def test_what_the_fmu_cannot_do_the_master_does_not(fmus, tmp_path):
    rotary = drive_section(fmus["rotary_servo"], tmp_path, "pmsm")
    with pytest.raises(SceneError, match=r"scene.toml:\d+: 'coupling.step_control' is refused: rotary_servo.fmu "
                                         r"\(drive.fmu\) cannot get and set its state"):
        load_scene(scene_file(tmp_path, rotary, extra='[coupling]\nstep_control = "doubling"'))
    # the linear servo keeps its state (pythonfmu --handle-state): step doubling rolls it back
    linear = drive_section(fmus["linear_servo"], tmp_path, "linear")
    scene = load_scene(scene_file(tmp_path, linear, duration=0.3, extra='[coupling]\nstep_control = "doubling"'))
    result, report = run_scene(scene)
    assert report.failure is None and result["time"][-1] == pytest.approx(0.3)
    # one step size only: a finer start is refused, the plain fixed step runs
    edited(fmus["linear_servo"], tmp_path, "fixed_step", lambda t: t.replace(
        'canHandleVariableCommunicationStepSize="true"', 'canHandleVariableCommunicationStepSize="false"'))
    one_step = linear.replace("linear_servo.fmu", "fixed_step.fmu")
    with pytest.raises(SceneError, match=r"'coupling.startup_time' is refused: fixed_step.fmu \(drive.fmu\) takes one "
                                         r"communication step size only"):
        load_scene(scene_file(tmp_path, one_step, extra="[coupling]\nstartup_time = 0.1\nstartup_step = 1e-4"))
    assert run_scene(load_scene(scene_file(tmp_path, one_step, duration=0.1)))[1].failure is None
    # no input derivatives to a drive that cannot interpolate its inputs (pythonfmu's): the coupling holds them
    from cosim.engine.execution import Execution
    scene = load_scene(scene_file(tmp_path, linear, duration=0.1))
    with Execution(scene_structure(scene), scene.algorithm, scene.control) as execution:
        assert execution.coupling.interpolating["linear1"] is False
        assert execution.coupling.interpolating["mechanics"] is True  # ours takes them
    # no interface Jacobian from a drive without the slope output: the run says so and keeps going
    scene = load_scene(scene_file(tmp_path, linear, duration=0.1, extra="[coupling]\ninterface_jacobian = true"))
    structure = scene_structure(scene)
    assert all(b.slope is None for b in structure.bonds)
    assert any(c.target == ("linear1", "velocity_ref") for c in structure.connections)  # its optional input, wired
    assert "no interface Jacobian (no output 'force_velocity_slope')" in run_scene(scene)[1].text()


def test_the_sizing_check_holds_a_users_drive_to_the_limit_it_names(fmus, tmp_path):
    low = drive_section(fmus["rotary_servo"], tmp_path, "pmsm", torque_continuous=5.0)
    with pytest.raises(SceneError, match=r"leg 1 needs 8.26 N m to hold the start pose, above rotary_servo.fmu's "
                                         r"torque_continuous = 5 N m"):
        run_scene(load_scene(scene_file(tmp_path, low.replace("[drive.parameters]", 'continuous_limit = '
                                                                   '"torque_continuous"\n[drive.parameters]'))),
                  plots=False)
    with pytest.raises(SceneError, match=r"'drive.continuous_limit' = 'rated': is not a Real parameter of "
                                         r"rotary_servo.fmu"):
        load_scene(scene_file(tmp_path, low.replace("[drive.parameters]", 'continuous_limit = "rated"\n'
                                                                           "[drive.parameters]")))


def edited(fmu: Path, folder: Path, name: str, xml=None, drop: str | None = None) -> Path:
    """A copy of `fmu` with its modelDescription.xml changed by `xml` and the members under `drop` left out."""
    out = folder / f"{name}.fmu"
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(out, "w") as target:
        for item in source.infolist():
            if drop and item.filename.startswith(drop):
                continue
            data = source.read(item)
            if item.filename == "modelDescription.xml" and xml:
                data = xml(data.decode()).encode()
            target.writestr(item, data)
    return out


def _speed_as(text: str, declaration: str) -> str:
    return re.sub(r'<ScalarVariable name="speed" valueReference="2" causality="input">\s*<Real start="0"/>',
                  declaration, text, count=1)


def _input(name: str, body: str, causality: str = 'causality="input"') -> str:
    return f'<ScalarVariable name="{name}" valueReference="2" {causality}>{body}'


BAD = {  # name: (change of the modelDescription, members left out, the message)
    "not_an_fmu": (None, None, r"not_an_fmu.fmu is not an FMU \(not a zip archive\)"),
    "model_exchange": (lambda t: re.sub(r"<CoSimulation [^>]*/>", '<ModelExchange modelIdentifier="rotary_servo"/>', t),
                       None, r"model_exchange.fmu is a Model Exchange FMU only"),
    "no_binary": (None, "binaries/linux64",
                  r"no_binary.fmu has no binary for this machine \(binaries/linux64/rotary_servo.so; it holds win64\)"),
    "no_speed": (lambda t: t.replace('name="speed"', 'name="rotor_speed"'), None,
                 r"no_speed.fmu: the rotary drive's input 'speed' is missing"),
    "speed_parameter": (lambda t: _speed_as(t, _input("speed", '<Real start="0"/>',
                                                      'causality="parameter" variability="tunable"')), None,
                        r"speed_parameter.fmu: the rotary drive's input 'speed' is declared parameter"),
    "speed_integer": (lambda t: _speed_as(t, _input("speed", '<Integer start="0"/>',
                                                                    'causality="input" variability="discrete"')), None,
                      r"speed_integer.fmu: the rotary drive's input 'speed' is Integer, not Real"),
    "speed_in_rpm": (lambda t: _speed_as(t, _input("speed", '<Real start="0" unit="rpm"/>')).replace(
        "<LogCategories>", '<UnitDefinitions><Unit name="rpm"/></UnitDefinitions><LogCategories>'), None,
                     r"speed_in_rpm.fmu: the rotary drive's input 'speed' is in 'rpm'; the contract's unit is 'rad/s'"),
    "broken_xml": (lambda t: t.replace("</ModelVariables>", ""), None,
                   r"broken_xml.fmu is not an FMU fmpy can read: .*\S"),
    "no_effort": (lambda t: t.replace('name="torque"', 'name="torque_em"'), None,
                  r"no_effort.fmu has neither a 'torque' output \(a rotary drive\) nor a 'force' output"),
}


@pytest.mark.parametrize("case", BAD)
def test_an_fmu_that_cannot_drive_a_leg_is_one_line(case, fmus, tmp_path, capsys):
    xml, drop, message = BAD[case]
    if case == "not_an_fmu":
        (tmp_path / f"{case}.fmu").write_text("not a zip archive")
    else:
        edited(fmus["rotary_servo"], tmp_path, case, xml, drop)
    path = scene_file(tmp_path, f'[drive]\nfmu = "{case}.fmu"')
    assert main(["run", str(path), "--no-plots"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert f"scene.toml:5: 'drive.fmu' = '{case}.fmu': " in err
    assert re.search(message, err), err


def test_the_scene_says_what_a_users_drive_is_not(fmus, tmp_path):
    section = drive_section(fmus["rotary_servo"], tmp_path, "pmsm")
    cases = {
        section.replace("[drive]\n", '[drive]\nkind = "linear"\n'):
            "'drive.kind' = 'linear': but drive.fmu rotary_servo.fmu has the rotary drive's ports",
        section.replace("[drive]\n", '[drive]\ntuning = "auto"\n'):
            "'drive.tuning' = 'auto': designs the loops of our drives",
        section.replace("kp =", "kpp ="): "drive.parameters.\"kpp\" = ",
        '[drive]\nkind = "linear"\n[drive.leg.2]\nfmu = "rotary_servo.fmu"':
            "'drive.leg.2.fmu' = 'rotary_servo.fmu': has the rotary drive's ports, the other legs' drives are linear",
        '[drive.leg.7]\nfmu = "rotary_servo.fmu"': "'drive.leg.7' is not a known key (known here: 1, 2, 3, 4, 5, 6)",
    }
    for drive, message in cases.items():
        with pytest.raises(SceneError) as error:
            load_scene(scene_file(tmp_path, drive))
        assert message in str(error.value) and "\n" not in str(error.value), str(error.value)
