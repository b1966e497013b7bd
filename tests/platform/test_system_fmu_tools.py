"""Every shipped scene as ONE Co-Simulation FMU (`cosim export SCENE --fmu`, issue 60), FMI 2.0 and
FMI 3.0, in the tools a user imports it into, each at 1 ms and 10 ms communication steps over the
scene's probe (the start-up at its finer step, the first load pulse with its refined edges, steady
tracking):

- fmpy's simulate_fmu: `cosim run`'s outputs bit for bit at every communication point (both steps
  are multiples of the scene's), so within the scene's tolerances of its converged run as
  `cosim run` is (cosim.platform.run.accuracy.judge);
- Reference-FMUs' fmusim and OMSimulator (the FMU alone, its command line; ../shared/peers) and
  libcosim (libcosimpy): fmpy's outputs to the digits each writes (fmusim 16, OMSimulator 12) or
  gives (libcosim: bit for bit);
- the win64 binary under Wine, as the Linux binary, to 1e-12 of each output's range (glibc's and
  MinGW's libm may differ in the last bit: tests/models/test_win64.py): FMI 2.0 through fmpy's
  remoting (FMI 2.0 only, as an unprivileged user), both versions through tests/c/fmu_run.c.

A stage of scripts/test.sh (pytest -m tools)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

import cosim
from cosim.engine.artifacts import ROOT
from cosim.platform.run.accuracy import judge, probe_duration
from cosim.platform.run.portable import converged, export_fmu
from cosim.platform.ports import POSE
from cosim.platform.run.runner import run_scene
from models.test_win64 import WINE, harness, remote_wine, run_remotely, wine_env  # noqa: F401 (fixtures: the
#                                             harness built for both systems, Wine prefixes: the tests', the user's)

pytestmark = pytest.mark.tools

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))
STEPS = (1e-3, 1e-2)


class Exported:
    def __init__(self, scene, fmu: Path, fmi: int):
        self.scene, self.fmu, self.fmi = scene, fmu, fmi
        self.ours = run_scene(scene)[0]
        self.names = [n for n in self.ours.dtype.names if n != "time"]
        self.reference = converged(scene, scene.duration)
        self._fmpy: dict[float, np.ndarray] = {}

    def fmpy(self, step: float) -> np.ndarray:
        if step not in self._fmpy:
            self._fmpy[step] = simulate_fmu(str(self.fmu), stop_time=self.scene.duration, step_size=step,
                                            output_interval=step, output=self.names, fmi_type="CoSimulation")
        return self._fmpy[step]


EVERY = [(name, fmi) for name in SCENES for fmi in (2, 3)]  # each shipped scene as FMI 2.0 and 3.0
FMI2 = [(name, 2) for name in SCENES]  # libcosimpy 0.0.6 loads FMI 2.0 FMUs only


def each(cases):
    """The `exported` fixture over `cases` (module-scoped: each export made once for every test)."""
    return pytest.mark.parametrize("exported", cases, indirect=True, ids=[f"{n}-fmi{f}" for n, f in cases])


@pytest.fixture(scope="module")
def exported(request, tmp_path_factory) -> Exported:
    name, fmi = request.param
    scene = cosim.load(name)
    scene = scene.changed({"scene.duration": probe_duration(scene)})
    fmu = tmp_path_factory.mktemp(name) / f"{name}.fmu"
    export_fmu(scene, fmu, fmi=fmi)
    return Exported(scene, fmu, fmi)


def same_to(theirs: dict, mine: np.ndarray, names, relative: float) -> None:
    assert len(theirs["time"]) == len(mine), (len(theirs["time"]), len(mine))
    assert np.allclose(theirs["time"], mine["time"], rtol=0, atol=1e-9)
    for name in names:
        scale = max(float(np.max(np.abs(mine[name]))), 1e-300)
        assert np.max(np.abs(np.asarray(theirs[name]) - mine[name])) <= relative * scale, name


@each(EVERY)
@pytest.mark.parametrize("step", STEPS)
def test_fmpy_runs_it_as_cosim_run_bit_for_bit_within_the_tolerances(exported, step):
    result = exported.fmpy(step)
    _, i, j = np.intersect1d(np.round(result["time"], 9), np.round(exported.ours["time"], 9), return_indices=True)
    assert len(i) == len(result) == round(exported.scene.duration / step) + 1
    for name in exported.names:
        assert np.array_equal(result[name][i], exported.ours[name][j]), name
    verdict = judge(exported.scene, result, exported.reference)
    assert verdict.within, verdict


@each(EVERY)
@pytest.mark.parametrize("step", STEPS)
def test_fmusim_runs_it_as_fmpy_does(exported, step, tmp_path):
    from peers import fmusim
    out = tmp_path / "fmusim.csv"
    done = subprocess.run([str(fmusim()), "--interface-type", "cs", "--stop-time", repr(exported.scene.duration),
                           "--output-interval", repr(step), "--output-file", str(out), str(exported.fmu)],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    same_to({n: table[n] for n in table.dtype.names}, exported.fmpy(step), exported.names, 1e-15)


@each(EVERY)
@pytest.mark.parametrize("step", STEPS)
def test_omsimulator_runs_it_as_fmpy_does(exported, step, tmp_path):
    from peers import omsimulator
    done = subprocess.run([str(omsimulator()), "--mode=cs", f"--stopTime={exported.scene.duration!r}",
                           f"--stepSize={step!r}", "--resultFile=out.csv", str(exported.fmu)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=900)
    log = done.stdout + done.stderr
    assert done.returncode == 0 and "error:" not in log, log[-3000:]
    out = tmp_path / "out.csv"
    header = [name.strip().strip('"') for name in out.open().readline().split(",")]
    wanted = ("time", *exported.names)  # the FMU's own names (an FMI 3.0 FMU's `time` is written twice: the first)
    data = np.loadtxt(out, delimiter=",", skiprows=1, usecols=[header.index(name) for name in wanted], ndmin=2)
    columns = {name: data[:, k] for k, name in enumerate(wanted)}
    time = columns["time"]
    last = np.r_[np.diff(time) > 0, True]  # a point written twice (before and after its events): the later one
    same_to({n: v[last] for n, v in columns.items()}, exported.fmpy(step), exported.names, 1e-11)  # its 12 digits


@pytest.mark.parametrize("fmi", [2, 3])
def test_fmusim_and_omsimulator_hold_the_exported_cueing_as_cosim_run_does(fmi, tmp_path):
    """The classical washout's emergency stop, whose reference the cueing FMU's guard holds at the
    joints' limit for thousands of steps, exported as one FMU: fmusim and OMSimulator run it at the
    scene's step as `cosim run` runs it (to the digits each writes), the reference within the
    envelope and the guard's count of the steps it held the same. Exported as one Model Exchange
    FMU, fmusim's CVODE integrates it through the guard's steps (its time events): the reference
    within the envelope at every output, the platform within its stroke and joints, the guard's
    count within 1 % of `cosim run`'s."""
    from peers import fmusim, omsimulator
    from test_guard import assert_platform_within_its_limits, assert_reference_inside, emergency_stop, limits_of
    model = emergency_stop(tmp_path)
    scene = cosim.load(model)
    ours = run_scene(scene)[0]
    fmu = export_fmu(scene, tmp_path / "stop.fmu", fmi=fmi).files[0]
    names = [*(f"pose_ref.{a}" for a in POSE), *(f"pose.{a}" for a in POSE), "guard.held.joint"]
    grid = np.flatnonzero(np.isin(np.round(ours["time"], 9), np.round(np.arange(0.0, 10.0 + 1e-9, scene.step), 9)))
    mine = ours[["time", *names]][grid]
    out = tmp_path / "fmusim.csv"
    done = subprocess.run([str(fmusim()), "--interface-type", "cs", "--stop-time", "10.0", "--output-interval",
                           repr(scene.step), "--output-file", str(out), str(fmu)], capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    same_to({n: table[n] for n in ("time", *names)}, mine, names, 1e-15)
    done = subprocess.run([str(omsimulator()), "--mode=cs", "--stopTime=10.0", f"--stepSize={scene.step!r}",
                           "--resultFile=out.csv", str(fmu)], capture_output=True, text=True, cwd=tmp_path, timeout=900)
    assert done.returncode == 0 and "error:" not in done.stdout + done.stderr, (done.stdout + done.stderr)[-3000:]
    header = [name.strip().strip('"') for name in (tmp_path / "out.csv").open().readline().split(",")]
    data = np.loadtxt(tmp_path / "out.csv", delimiter=",", skiprows=1, ndmin=2,
                      usecols=[header.index(name) for name in ("time", *names)])
    last = np.r_[np.diff(data[:, 0]) > 0, True]
    same_to({n: data[last, k] for k, n in enumerate(("time", *names))}, mine, names, 1e-11)
    envelope, core = limits_of(model)
    assert_reference_inside(np.column_stack([table[f"pose_ref.{a}"] for a in POSE]), envelope, core)
    assert table["guard.held.joint"][-1] == ours["guard.held.joint"][-1] > 1000
    me = export_fmu(scene, tmp_path / "stop_me.fmu", fmi=fmi, model_exchange=True).files[0]
    done = subprocess.run([str(fmusim()), "--interface-type", "me", "--solver", "cvode", "--stop-time", "10.0",
                           "--output-interval", repr(scene.step), "--output-file", str(out), str(me)],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    assert table["time"][-1] == pytest.approx(10.0)
    assert_reference_inside(np.column_stack([table[f"pose_ref.{a}"] for a in POSE]), envelope, core)
    assert_platform_within_its_limits({f"pose.{a}": table[f"pose.{a}"] for a in POSE}, envelope, core)
    assert table["guard.held.joint"][-1] == pytest.approx(ours["guard.held.joint"][-1], rel=0.01)


@each(FMI2)
@pytest.mark.parametrize("step", STEPS)
def test_libcosim_runs_it_as_fmpy_does(exported, step):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=int(round(step * 1e9)))
    slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(exported.fmu), instance_name="platform"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(slave)}
    vrs = [refs[n] for n in exported.names]
    n = int(round(exported.scene.duration / step))
    rows = {name: np.zeros(n) for name in ("time", *exported.names)}
    for i in range(n):
        assert execution.simulate_until(int(round((i + 1) * step * 1e9))), f"libcosim stopped at step {i + 1}"
        rows["time"][i] = (i + 1) * step
        for name, value in zip(exported.names, observer.last_real_values(slave, vrs)):
            rows[name][i] = value
    same_to(rows, exported.fmpy(step)[1:], exported.names, 0.0)


REMOTE_RUN = """
import shutil, sys
import numpy as np
from fmpy import extract, simulate_fmu
fmu, folder, stop, step = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
linux_dir, windows_dir = (str(extract(fmu, folder + "/" + part)) for part in ("linux", "windows"))
shutil.rmtree(windows_dir + "/binaries/linux64")  # (fmpy remotes only an FMU without a binary for this platform)
run = dict(stop_time=stop, step_size=step, output_interval=step)
np.savez(folder + "/runs.npz", linux=simulate_fmu(linux_dir, **run),
         windows=simulate_fmu(windows_dir, remote_platform="win64", **run))
"""


def test_under_wine_the_windows_binary_gives_the_linux_outputs(remote_wine):
    """The Meng scene's FMU over its first 0.3 s at 1 ms: the system FMU's DLL nesting the models'
    DLLs, driven by fmpy's remoting under Wine, as its Linux binary."""
    import tempfile
    folder = Path(tempfile.mkdtemp(prefix="cosim-remoting-"))
    try:
        folder.chmod(0o755)
        scene = cosim.load("meng_eq35").changed({"scene.duration": 0.3})
        fmu = export_fmu(scene, folder / "meng.fmu").files[0]
        fmu.chmod(0o644)
        (folder / "run.py").write_text(REMOTE_RUN)
        status, output = run_remotely(remote_wine, folder, [str(folder / "run.py"), str(fmu), str(folder), "0.3",
                                                            "0.001"], 900)
        assert status == 0, output
        runs = np.load(folder / "runs.npz")
        linux, windows = runs["linux"], runs["windows"]
        assert len(linux) == len(windows) == 301
        for column in linux.dtype.names:
            scale = max(float(np.ptp(linux[column])), 1.0)
            assert np.all(np.abs(windows[column] - linux[column]) <= 1e-12 * scale), column
        assert np.ptp(linux["torque[1]"]) > 1.0
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def harness_run(command: list[str], env: dict) -> np.ndarray:
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    return np.array([[float(x) for x in line.split(",")] for line in done.stdout.splitlines() if line.strip()])


@pytest.mark.parametrize("fmi", [2, 3])
def test_under_wine_each_versions_windows_binary_gives_the_linux_outputs(fmi, tmp_path, harness, wine_env):
    """The Meng scene's FMU over 0.3 s at 1 ms through tests/c/fmu_run.c (FMI 2.0 and FMI 3.0 entry
    points): the Windows DLL, nesting the models' DLLs, under Wine as the Linux binary, to 1e-12 of each
    output's range. The resources are given as each version gives them (a file URI, a path)."""
    import re
    import zipfile
    from fmpy import read_model_description
    from cosim.engine.system_fmu import PLATFORMS
    fmu = export_fmu(cosim.load("meng_eq35").changed({"scene.duration": 0.3}), tmp_path / "meng.fmu", fmi=fmi).files[0]
    folder = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(folder)
    token = re.search(r'(?:guid|instantiationToken)="([^"]+)"', (folder / "modelDescription.xml").read_text()).group(1)
    outputs = ",".join(str(v.valueReference) for v in read_model_description(str(folder)).modelVariables
                       if v.causality == "output")
    resources = folder / "resources"
    on_linux = f"{resources.as_uri()}/" if fmi == 2 else f"{resources}/"
    on_windows = f"file:///Z:{resources}/" if fmi == 2 else f"Z:{resources}/"
    linux_dir, windows_dir = PLATFORMS[fmi]
    common = [token, "0.001", "300", outputs]
    linux = harness_run([str(harness["linux64", fmi]), str(folder / "binaries" / linux_dir / "meng.so"), *common],
                        {**os.environ, "FMU_RUN_RESOURCES": on_linux})
    if WINE is None:
        pytest.skip("needs Wine (scripts/setup.sh installs wine64)")
    windows = harness_run([WINE, str(harness["win64", fmi]), str(folder / "binaries" / windows_dir / "meng.dll"),
                           *common], {**wine_env, "FMU_RUN_RESOURCES": on_windows})
    assert linux.shape == windows.shape == (301, 1 + len(outputs.split(",")))
    scale = np.maximum(np.ptp(linux, axis=0), 1.0)
    assert np.all(np.abs(windows - linux) <= 1e-12 * scale)
    assert np.ptp(linux[:, 1:], axis=0).max() > 1.0  # the torques move



# -- the scene as ONE Model Exchange FMU (`cosim export SCENE --fmu FILE --me`, issue 61) ----------

class ExportedMe:
    """A shipped scene's probe as one Model Exchange FMU, its converged co-simulation and the
    tolerance its default experiment gives the importer's solver."""

    def __init__(self, scene, fmu: Path, fmi: int):
        from fmpy import read_model_description
        self.scene, self.fmu, self.fmi = scene, fmu, fmi
        self.reference = converged(scene, scene.duration)
        self.names = [n for n in self.reference.dtype.names if n != "time"]
        self.tolerance = float(read_model_description(str(fmu)).defaultExperiment.tolerance)


@pytest.fixture(scope="module")
def exported_me(request, tmp_path_factory) -> ExportedMe:
    name, fmi = request.param
    scene = cosim.load(name)
    scene = scene.changed({"scene.duration": probe_duration(scene)})
    fmu = tmp_path_factory.mktemp(f"{name}_me") / f"{name}.fmu"
    export_fmu(scene, fmu, fmi=fmi, model_exchange=True)
    return ExportedMe(scene, fmu, fmi)


def each_me(cases):
    return pytest.mark.parametrize("exported_me", cases, indirect=True, ids=[f"{n}-fmi{f}-me" for n, f in cases])


def fmusim_table(out: Path, step: float) -> np.ndarray:
    return on_the_grid(np.genfromtxt(out, delimiter=",", names=True, deletechars=""), step)


def on_the_grid(table: np.ndarray, step: float) -> np.ndarray:
    """A Model Exchange run's rows at the output points (fmusim and fmpy write a row before and after
    each time event too): one row per point, the last written there."""
    ticks = np.round(table["time"] / step)
    on = np.abs(table["time"] - ticks * step) <= 1e-9
    return table[on & np.r_[ticks[1:] != ticks[:-1], True]]


def within(exported: ExportedMe, rows: np.ndarray) -> None:
    assert len(rows) == round(exported.scene.duration / exported.scene.step) + 1
    verdict = judge(exported.scene, rows, exported.reference)
    assert verdict.within, verdict


def fmusim_me(binary: list[str], fmu: str, exported: ExportedMe, out: str, env=None) -> None:
    done = subprocess.run([*binary, "--interface-type", "me", "--solver", "cvode", "--tolerance",
                           repr(exported.tolerance), "--stop-time", repr(exported.scene.duration), "--output-interval",
                           repr(exported.scene.step), "--output-file", out, fmu],
                          capture_output=True, text=True, timeout=900, env=env)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]


@each_me(EVERY)
def test_fmusims_cvode_integrates_it_within_the_scenes_tolerances(exported_me, tmp_path):
    from peers import fmusim
    fmusim_me([str(fmusim())], str(exported_me.fmu), exported_me, str(tmp_path / "out.csv"))
    within(exported_me, fmusim_table(tmp_path / "out.csv", exported_me.scene.step))


@each_me(EVERY)
def test_fmpys_cvode_integrates_it_within_the_scenes_tolerances(exported_me):
    result = simulate_fmu(str(exported_me.fmu), fmi_type="ModelExchange", solver="CVode",
                          relative_tolerance=exported_me.tolerance, stop_time=exported_me.scene.duration,
                          output_interval=exported_me.scene.step, output=exported_me.names)
    within(exported_me, on_the_grid(result, exported_me.scene.step))


@each_me(FMI2)
def test_omsimulators_cvode_integrates_it_within_the_scenes_tolerances(exported_me, tmp_path):
    """The FMU alone on OMSimulator's command line (its CVODE, steps up to the output interval).
    OMSimulator b3cd458 imports FMI 3.0 Co-Simulation only ("Unsupported FMI version: 3" for Model
    Exchange): the FMI 2.0 export."""
    from peers import omsimulator
    done = subprocess.run([str(omsimulator()), "--mode=me", "--solver=cvode", f"--tolerance={exported_me.tolerance!r}",
                           f"--stopTime={exported_me.scene.duration!r}", f"--stepSize={exported_me.scene.step!r}",
                           "--resultFile=out.csv", str(exported_me.fmu)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=900)
    log = done.stdout + done.stderr
    assert done.returncode == 0 and "error:" not in log, log[-3000:]
    out = tmp_path / "out.csv"
    header = [name.strip().strip('"') for name in out.open().readline().split(",")]
    wanted = ("time", *exported_me.names)
    data = np.loadtxt(out, delimiter=",", skiprows=1, usecols=[header.index(name) for name in wanted], ndmin=2)
    rows = np.zeros(len(data), dtype=[(name, float) for name in wanted])
    for k, name in enumerate(wanted):
        rows[name] = data[:, k]
    within(exported_me, on_the_grid(rows, exported_me.scene.step))


@each_me(EVERY)
def test_under_wine_fmusim_exe_integrates_its_windows_binary_as_on_linux(exported_me, tmp_path, wine_env):
    """Reference-FMUs' fmusim.exe under Wine on the FMU's win64 binary (nesting the models' DLLs):
    within the scene's tolerances, and the outputs of Linux's fmusim to 1e-4 of each one's range (the
    same solver and FMU; glibc's and MinGW's libm differ in the last bit, and CVODE's step choices
    grow that to a few times its relative tolerance, 1e-6: 1.2e-5 of the torques' range measured)."""
    from peers import fmusim
    if WINE is None:
        pytest.skip("needs Wine (scripts/setup.sh installs wine64)")
    windows = Path(str(fmusim()) + ".exe")
    fmusim_me([WINE, str(windows)], f"Z:{exported_me.fmu}", exported_me, f"Z:{tmp_path / 'windows.csv'}", wine_env)
    fmusim_me([str(fmusim())], str(exported_me.fmu), exported_me, str(tmp_path / "linux.csv"))
    step = exported_me.scene.step
    on_windows, on_linux = fmusim_table(tmp_path / "windows.csv", step), fmusim_table(tmp_path / "linux.csv", step)
    within(exported_me, on_windows)
    for name in exported_me.names:
        scale = max(float(np.ptp(on_linux[name])), 1e-300)
        assert np.max(np.abs(on_windows[name] - on_linux[name])) <= 1e-4 * scale, name
