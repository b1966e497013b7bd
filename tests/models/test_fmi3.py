"""Every model as an FMI 3.0 Co-Simulation FMU (build/fmus3/, fmu/common/fmi3_layer.c over the
same model and FMI 2.0 layer): fmpy validates it; its variables are its FMI 2.0 twin's (names,
value references, causalities, units, starts) in FMI 3.0's types, and each Real input's rate and
curvature as inputs of their own, which act as FMI 2.0's input derivatives; it runs the twin's experiment
bit for bit (one source, one compiler: an FMI 3.0 instance holds its inputs over a step, as the
experiment's held inputs do); its state kept, serialized and set back replays bit for bit; wrong
use is refused with a logged reason; its sources/ rebuild it (fmpy's build of buildDescription.xml)
with the same outputs; its Windows binary imports only Windows' own DLLs."""

from __future__ import annotations

import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import FMU_EXPERIMENT_STEPS, FMU_EXPERIMENTS
from cosim.engine.artifacts import fmu_path
from shipped import MODELS

STEPS = 2000
SPAN = 0x100000  # an input's derivative of order k at k * SPAN + its value reference
FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}


@pytest.mark.parametrize("name", MODELS)
def test_the_fmi3_fmu_validates_and_has_its_twins_variables(name):
    assert validate_fmu(str(fmu_path(name, fmi=3))) == []
    two, three = (read_model_description(str(fmu_path(name, fmi=f))) for f in (2, 3))
    assert three.fmiVersion == "3.0" and three.guid == two.guid  # the instantiation token: the table's hash
    assert three.coSimulation.modelIdentifier == two.coSimulation.modelIdentifier == name
    time, *variables = three.modelVariables
    assert (time.name, time.causality, time.valueReference) == ("time", "independent", 0)
    variables, derivatives = variables[:len(two.modelVariables)], variables[len(two.modelVariables):]
    # then each Real input's rate and curvature, inputs of their own (FMI 3.0 has no input derivatives)
    inputs = [v for v in two.modelVariables if v.causality == "input" and v.type == "Real"]
    assert [(d.name, d.valueReference, d.causality, d.type, float(d.start)) for d in derivatives] == [
        (f"fmi.{kind}.{v.name}", order * SPAN + v.valueReference, "input", "Float64", 0.0)
        for v in inputs for order, kind in ((1, "rate"), (2, "curvature"))]
    for a, b in zip(two.modelVariables, variables):
        assert (b.name, b.valueReference, b.causality, b.type, b.unit) == \
               (a.name, a.valueReference, a.causality, FMI3_TYPES[a.type], a.unit), a.name
        if a.causality != "output" and a.type != "String":
            assert b.start == a.start, a.name
    outputs = {u.variable.name: sorted(d.name for d in u.dependencies or []) for u in two.outputs}
    assert {u.variable.name: sorted(d.name for d in u.dependencies or []) for u in three.outputs} == outputs


def experiment(name: str) -> dict:
    step = FMU_EXPERIMENT_STEPS.get(name, 1e-3)
    outputs = [v.name for v in read_model_description(str(fmu_path(name))).modelVariables
               if v.causality == "output" and v.type == "Real"]
    return dict(stop_time=STEPS * step, step_size=step, output_interval=step, start_values=FMU_EXPERIMENTS[name],
                output=outputs)


@pytest.mark.parametrize("name", MODELS)
def test_the_fmi3_fmu_runs_its_twins_experiment_bit_for_bit(name):
    settings = experiment(name)
    two = simulate_fmu(str(fmu_path(name)), **settings)
    three = simulate_fmu(str(fmu_path(name, fmi=3)), fmi_type="CoSimulation", **settings)
    assert len(two) == len(three) == STEPS + 1
    moved = False
    for output in settings["output"]:
        assert np.array_equal(two[output], three[output]), output
        moved = moved or np.ptp(three[output]) > 0
    assert moved


@pytest.fixture
def slave(tmp_path):
    """An FMI 3.0 instance of the trajectory FMU through fmpy, its log collected."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    path = fmu_path("trajectory", fmi=3)
    description = read_model_description(str(path))
    unzipped = extract(str(path), str(tmp_path / "unzipped"))
    made = []

    def make(**instantiate):
        fmu = FMU3Slave(guid=description.guid, unzipDirectory=unzipped, modelIdentifier="trajectory",
                        instanceName="it")
        log = []
        fmu.instantiate(logMessage=lambda env, status, category, message: log.append(message.decode()),
                        **instantiate)
        made.append(fmu)
        return fmu, log, {v.name: v.valueReference for v in description.modelVariables}
    yield make
    for fmu in made:
        try:
            fmu.freeInstance()
        except Exception:
            pass


def test_the_fmi3_state_replays_the_steps_bit_for_bit(slave):
    fmu, _, vr = slave()
    fmu.setFloat64([vr["x.sine[1].amplitude"], vr["x.sine[1].frequency"]], [0.1, 1.5])
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    watched = [vr["pose_ref.x"], vr["pose_ref.roll"], vr["time"]]
    for k in range(100):
        fmu.doStep(k * 1e-3, 1e-3)
    kept = fmu.serializeFMUState(fmu.getFMUState())
    first = []
    for k in range(100, 200):
        fmu.doStep(k * 1e-3, 1e-3)
        first.append(fmu.getFloat64(watched))
    fmu.setFMUState(fmu.deserializeFMUState(kept))
    again = []
    for k in range(100, 200):
        fmu.doStep(k * 1e-3, 1e-3)
        again.append(fmu.getFloat64(watched))
    assert first == again and first[-1][2] == pytest.approx(0.2, abs=1e-12)  # time, value reference 0


def test_wrong_use_of_the_fmi3_layer_is_refused_with_its_reason(slave):
    from fmpy.fmi1 import FMICallException
    fmu, log, vr = slave()
    with pytest.raises(FMICallException):  # a step before initialization
        fmu.doStep(0.0, 1e-3)
    assert "illegal call sequence" in log[-1]
    assert "fmi3DoStep" in log[-1] and "fmi2" not in log[-1]  # the call the importer made, by its FMI 3.0 name
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    with pytest.raises(FMICallException):  # a Float64 read as an Int32
        fmu.getInt32([vr["pose_ref.x"]])
    assert "is of type Real, not Integer" in log[-1] and "fmi3GetInt32" in log[-1]
    with pytest.raises(FMICallException):  # no Float32 variables
        fmu.getFloat32([vr["pose_ref.x"]])
    assert "no Float32 variables" in log[-1]
    with pytest.raises(FMICallException):
        fmu.enterEventMode()
    assert "no event mode" in log[-1]
    with pytest.raises(FMICallException):  # the independent variable is not set
        fmu.setFloat64([vr["time"]], [1.0])
    with pytest.raises(Exception):  # an FMU without event mode refuses to be instantiated for one
        slave(eventModeUsed=True)


@pytest.mark.parametrize("name", MODELS)
def test_the_fmi3_fmu_rebuilds_from_its_sources(name, tmp_path):
    from fmpy.build import build_platform_binary
    rebuilt = tmp_path / "unzipped"
    with zipfile.ZipFile(fmu_path(name, fmi=3)) as z:
        z.extractall(rebuilt)
    shutil.rmtree(rebuilt / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(rebuilt, build_dir=tmp_path / "build")
    assert (rebuilt / "binaries" / "x86_64-linux" / f"{name}.so").exists()
    settings = {**experiment(name), "stop_time": 20 * FMU_EXPERIMENT_STEPS.get(name, 1e-3)}
    original = simulate_fmu(str(fmu_path(name, fmi=3)), **settings)
    from_sources = simulate_fmu(str(rebuilt), **settings)
    for output in settings["output"]:
        np.testing.assert_allclose(from_sources[output], original[output], rtol=1e-9, atol=1e-12)


OBJDUMP = shutil.which("x86_64-w64-mingw32-objdump")


@pytest.mark.skipif(not OBJDUMP, reason="needs MinGW-w64's objdump (scripts/setup.sh installs it)")
@pytest.mark.parametrize("name", MODELS)
def test_the_fmi3_windows_binary_needs_only_windows_own_dlls(name, tmp_path):
    with zipfile.ZipFile(fmu_path(name, fmi=3)) as z:
        z.extract(f"binaries/x86_64-windows/{name}.dll", tmp_path)
    table = subprocess.run([OBJDUMP, "-p", str(tmp_path / "binaries" / "x86_64-windows" / f"{name}.dll")],
                           capture_output=True, text=True, check=True).stdout
    assert {line.split(":", 1)[1].strip() for line in table.splitlines() if "DLL Name:" in line} == \
        {"KERNEL32.dll", "msvcrt.dll"}
    for function in ("fmi3InstantiateCoSimulation", "fmi3DoStep", "fmi3GetFloat64", "fmi3SerializeFMUState"):
        assert f"] {function}\n" in table, function


def test_the_engine_runs_the_meng_scene_on_fmi3_fmus_as_on_fmi2_at_order_0():
    """The whole platform on the FMI 3.0 FMUs (scene.fmi = 3) through the C step kernel's FMI 3.0
    adapters: at order 0 (what FMI 3.0's held inputs are) bit for bit the FMI 2.0 run, fixed steps
    with the finer start and step doubling with its rollbacks through FMU state alike."""
    from cosim.platform.run.runner import run_scene
    from cosim.platform.scene import load_scene
    for control in ({}, {"coupling.step_control": "doubling"}):
        scene = load_scene("meng_eq35", {"scene.duration": 0.3, "coupling.order": 0, **control})
        two, _ = run_scene(scene)
        three, report = run_scene(scene.changed({"scene.fmi": 3}))
        assert two.dtype.names == three.dtype.names and len(two) == len(three) > 100
        for name in two.dtype.names:
            assert np.array_equal(two[name], three[name]), (control, name)
        assert not any(r.startswith("FMI 3.0") for r in report.remarks)


def test_an_fmi3_run_that_extrapolates_says_how_its_inputs_reach_the_fmus(tmp_path, capsys):
    from cosim.cli import main
    assert main(["run", "meng_eq35", "--fmi", "3", "--duration", "0.05", "--no-plots", "--out", str(tmp_path)]) == 0
    assert "FMI 3.0: FMI 3.0 has no input derivatives; the master gives each input's rate and curvature through " \
           "the FMUs' own inputs fmi.rate.* and fmi.curvature.*" in capsys.readouterr().out
    assert main(["export", "meng_eq35", "--ssp", str(tmp_path / "m.ssp"), "--scene-step"]) == 0
    from cosim.engine.ssp import read_ssp
    assert main(["run", str(tmp_path / "m.ssp"), "--fmi", "3", "--out", str(tmp_path)]) == 2
    assert "--fmi: for a scene" in capsys.readouterr().err
    assert read_ssp(tmp_path / "m.ssp").components  # the FMI 2.0 archive as before


def test_a_scene_on_fmi3_fmus_exports_and_runs_from_its_archive_as_itself(tmp_path, capsys):
    """cosim export SCENE --fmi 3: an SSP 1.0 archive of the FMI 3.0 FMUs (their Float64 connectors
    as SSP's Real), which our engine runs bit for bit as the scene on FMI 3.0 FMUs."""
    from cosim.cli import main
    from cosim.engine.artifacts import ROOT
    archive = tmp_path / "meng3.ssp"
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(archive), "--fmi", "3",
                 "--scene-step"]) == 0
    assert "holds our FMUs as FMI 3.0" in capsys.readouterr().out
    with zipfile.ZipFile(archive) as z:
        description = z.read("resources/mechanics.fmu")
    assert b'fmiVersion="3.0"' in zipfile.ZipFile(__import__("io").BytesIO(description)).read("modelDescription.xml")
    assert main(["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--fmi", "3", "--duration", "0.3", "--no-plots",
                 "--out", str(tmp_path / "a")]) == 0
    assert main(["run", str(archive), "--duration", "0.3", "--out", str(tmp_path / "b")]) == 0
    a = np.genfromtxt(tmp_path / "a" / "meng_eq35.csv", delimiter=",", names=True)
    b = np.genfromtxt(tmp_path / "b" / "meng3.csv", delimiter=",", names=True)
    assert a.dtype.names == b.dtype.names and len(a) == len(b)
    for name in a.dtype.names:
        assert np.array_equal(a[name], b[name]), name


def test_a_users_drive_fmu_may_be_fmi3(tmp_path):
    """A drive FMU of the user's own ([drive] fmu) as FMI 3.0: checked against the contract's ports
    as an FMI 2.0 one (its Float64 read as Real), and run: our PMSM drive's FMI 3.0 FMU as the
    user's gives, at order 0, the run of its FMI 2.0 FMU in the same place bit for bit."""
    from cosim.platform.run.runner import run_scene
    from cosim.platform.scene import load_scene
    from cosim.platform.scene.drive_fmu import inspect
    runs = []
    for fmi in (2, 3):
        folder = tmp_path / f"fmi{fmi}"
        folder.mkdir()
        (folder / "pmsm_drive.fmu").write_bytes(fmu_path("pmsm_drive", fmi=fmi).read_bytes())
        assert inspect(folder / "pmsm_drive.fmu").kind == "pmsm"
        (folder / "scene.toml").write_text('[scene]\nduration = 0.2\n[drive]\nfmu = "pmsm_drive.fmu"\n'
                                           '[mechanics]\nparameter_set = "meng2010"\n[coupling]\norder = 0\n'
                                           '[trajectory.z]\noffset = "neutral"\n[trajectory.x]\n'
                                           'sines = [{amplitude = 0.05, frequency = 1.0}]\n')
        result, report = run_scene(load_scene(folder / "scene.toml"))
        assert report.failure is None
        runs.append(result)
    assert runs[0].dtype.names == runs[1].dtype.names
    for name in runs[0].dtype.names:
        assert np.array_equal(runs[0][name], runs[1][name]), name


def test_the_inputs_derivatives_act_as_fmi2s_and_read_back():
    """A drive stepped with its inputs' rates given: through fmi2SetRealInputDerivatives on the FMI
    2.0 binary and through fmi.rate.* on the FMI 3.0 one, bit for bit; the rate reads back as set,
    0 after the step (a derivative holds for one step); a derivative reference of an output is
    refused."""
    from cosim.engine.fmi import FmuError, FmuInstance
    runs = []
    for fmi in (2, 3):
        drive = FmuInstance(fmu_path("pmsm_drive", fmi=fmi), f"drive{fmi}")
        try:
            drive.initialize({})
            assert drive.can_interpolate_inputs
            rows = []
            for k in range(200):
                drive.set({"angle_ref": 0.01 * k})
                if fmi == 2:
                    drive._call("fmi2SetRealInputDerivatives", drive.fmu.setRealInputDerivatives,
                                [drive.vr("angle_ref")], [1], [1.0 / 1e-3 * 0.01])
                else:
                    drive.set({"fmi.rate.angle_ref": 1.0 / 1e-3 * 0.01})
                    assert drive.get("fmi.rate.angle_ref") == 10.0
                drive.do_step(1e-3)
                rows.append([drive.get(n) for n in ("torque", "speed_ref", "current.q")])
            if fmi == 3:
                assert drive.get("fmi.rate.angle_ref") == 0.0
                with pytest.raises(FmuError, match="unknown value reference"):
                    drive._call("fmi3SetFloat64", drive.fmu.setFloat64, [SPAN + drive.vr("torque")], [1.0])
            runs.append(np.array(rows))
        finally:
            drive.free()
    assert np.array_equal(runs[0], runs[1]) and np.abs(runs[0][:, 1]).max() > 0
