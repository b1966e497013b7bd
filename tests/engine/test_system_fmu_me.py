"""The whole scene as ONE Model Exchange FMU (`cosim export SCENE --fmu FILE --me`, issue 61): the
nested FMUs' continuous states its own, every connection carried inside each evaluation of its
derivatives, so that a tool's solver integrates the coupled platform with no coupling delay.

- Its derivatives are the monolithic system's (cosim.engine.monolithic: the same FMUs, the
  connections carried by Python) bit for bit, at the start and at states and times of our choosing:
  the connections are carried inside, at every evaluation.
- fmpy's CVODE and Reference-FMUs' fmusim (CVODE) integrate it, at the tolerance its default
  experiment gives, within the scene's tolerances of its converged co-simulation over the probe
  (the start-up, the first load pulse, steady tracking): the pose, and the drives' efforts per
  window against their own scale (cosim.platform.run.accuracy.judge).
- As FMI 3.0 it is the FMI 2.0 FMU bit for bit under the same solver; fmpy's validation (the XSDs)
  finds nothing in either; calls in the wrong interface or mode are refused with the reason."""

from __future__ import annotations

import ctypes
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model

from cosim.engine.artifacts import ROOT
from cosim.platform.run.accuracy import judge, probe_duration
from cosim.platform.run.portable import converged
from cosim.platform.scene import load_scene

SCENE = ROOT / "scenes" / "meng_eq35.toml"


def export(target: Path, duration: float, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "cosim", "export", str(SCENE), "--fmu", str(target), "--me",
                           "--duration", repr(duration), *extra], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The scene over its probe as one ME FMU (FMI 2.0 and 3.0), exported as a user does it, and its
    converged co-simulation."""
    scene = load_scene(SCENE)
    scene = scene.changed({"scene.duration": probe_duration(scene)})
    folder = tmp_path_factory.mktemp("me")
    fmus = {}
    for fmi in (2, 3):
        fmus[fmi] = folder / f"meng{fmi}.fmu"
        done = export(fmus[fmi], scene.duration, "--fmi", str(fmi))
        assert done.returncode == 0, done.stdout + done.stderr
        assert f"written: {fmus[fmi]} (FMI {fmi}.0 Model Exchange" in done.stdout
    return scene, fmus, converged(scene, scene.duration)


def names_of(reference: np.ndarray) -> list[str]:
    return [n for n in reference.dtype.names if n != "time"]


def tolerance_of(fmu: Path) -> float:
    return float(read_model_description(str(fmu)).defaultExperiment.tolerance)


def test_fmpys_cvode_integrates_it_within_the_scenes_tolerances(exported):
    scene, fmus, reference = exported
    result = simulate_fmu(str(fmus[2]), fmi_type="ModelExchange", solver="CVode", stop_time=scene.duration,
                          relative_tolerance=tolerance_of(fmus[2]), output_interval=scene.step,
                          output=names_of(reference))
    verdict = judge(scene, result, reference)
    assert verdict.within and verdict.pose_error <= 1e-5, verdict


def test_fmusims_cvode_integrates_it_within_the_scenes_tolerances(exported, tmp_path):
    from peers import fmusim
    scene, fmus, reference = exported
    for fmi, fmu in fmus.items():
        out = tmp_path / f"fmusim{fmi}.csv"
        done = subprocess.run([str(fmusim()), "--interface-type", "me", "--solver", "cvode", "--tolerance",
                               repr(tolerance_of(fmu)), "--stop-time", repr(scene.duration), "--output-interval",
                               repr(scene.step), "--output-file", str(out), str(fmu)],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        table = on_the_grid(np.genfromtxt(out, delimiter=",", names=True, deletechars=""), scene.step)
        assert len(table) == round(scene.duration / scene.step) + 1
        verdict = judge(scene, table, reference)
        assert verdict.within, (fmi, verdict)


def on_the_grid(table: np.ndarray, step: float) -> np.ndarray:
    """fmusim's rows at the output points (it writes a row before and after each time event too):
    one per point, the last written there."""
    ticks = np.round(table["time"] / step)
    on = np.abs(table["time"] - ticks * step) <= 1e-9
    last = np.r_[ticks[1:] != ticks[:-1], True]
    return table[on & last]


def _pointer(values: np.ndarray):
    return values.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def test_its_derivatives_are_the_monolithic_systems_bit_for_bit(exported, tmp_path):
    """The connections are carried inside every evaluation: at the start, and at states of our own
    (the start's, each scaled by 1 +- 1 %) at two times, its derivatives are those of the same FMUs
    with Python carrying the connections (cosim.engine.monolithic), to the last bit."""
    from cosim.engine.monolithic import MonolithicSystem, model_exchange_structure
    from cosim.platform.run.compile import compile_scene
    scene, fmus, _ = exported
    description = read_model_description(str(fmus[2]))
    n = description.numberOfContinuousStates
    ours = FMU2Model(guid=description.guid, unzipDirectory=extract(str(fmus[2]), str(tmp_path / "unpacked")),
                     modelIdentifier=description.modelExchange.modelIdentifier, instanceName="platform")
    ours.instantiate()
    theirs = MonolithicSystem(model_exchange_structure(compile_scene(scene).plan.structure))
    try:
        assert n == theirs.size > 60  # the mechanics' and six drives' states
        ours.setupExperiment(startTime=0.0)
        ours.enterInitializationMode()
        ours.exitInitializationMode()
        ours.newDiscreteStates()
        ours.enterContinuousTimeMode()
        x, dx = np.zeros(n), np.zeros(n)
        ours.getContinuousStates(_pointer(x), n)
        ours.getDerivatives(_pointer(dx), n)
        assert np.array_equal(x, theirs.states()) and np.array_equal(dx, theirs.derivatives())
        rng = np.random.default_rng(61)
        for t in (0.05, 0.2):
            changed = x * (1 + 0.01 * rng.standard_normal(n))
            ours.setTime(t)
            ours.setContinuousStates(_pointer(changed), n)
            ours.getDerivatives(_pointer(dx), n)
            theirs.set_time(t)
            theirs.set_states(changed)
            assert np.array_equal(dx, theirs.derivatives()), t
            assert np.ptp(dx) > 0
    finally:
        ours.terminate()
        ours.freeInstance()
        theirs.free()


def test_as_fmi3_it_is_the_fmi2_fmu_bit_for_bit_and_both_are_valid(exported):
    from fmpy.validation import validate_fmu
    scene, fmus, _ = exported
    names = ["pose.z", "torque[1]", "current.q[6]"]
    runs = [simulate_fmu(str(fmus[fmi]), fmi_type="ModelExchange", stop_time=0.3, output=names, output_interval=scene.step,
                         relative_tolerance=tolerance_of(fmus[fmi])) for fmi in (2, 3)]
    assert len(runs[0]) == len(runs[1]) == round(0.3 / scene.step) + 1
    for name in ("time", *names):
        assert np.array_equal(runs[0][name], runs[1][name]), name
    for fmu in fmus.values():
        assert validate_fmu(str(fmu)) == []
        description = read_model_description(str(fmu))
        assert description.modelExchange is not None and description.coSimulation is None
        assert description.numberOfContinuousStates == len(description.derivatives) > 60


def test_calls_in_the_wrong_interface_or_mode_are_refused_with_the_reason(exported, tmp_path):
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)
    from cosim.engine.fmi import FmuError, FmuInstance
    _, fmus, _ = exported
    with pytest.raises(FmuError, match="this FMU is Model Exchange only"):
        FmuInstance(fmus[2], "platform")  # our engine instantiates Co-Simulation
    description = read_model_description(str(fmus[2]))
    n = description.numberOfContinuousStates
    said: list[str] = []
    libc = ctypes.CDLL(None)
    libc.calloc.restype, libc.calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t, ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, category, message: said.append(message.decode()))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(libc.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(libc.free)
    fmu = FMU2Model(guid=description.guid, unzipDirectory=extract(str(fmus[2]), str(tmp_path / "unpacked")),
                    modelIdentifier=description.modelExchange.modelIdentifier, instanceName="platform")
    fmu.instantiate(callbacks=callbacks)
    x = np.zeros(n)

    def refused(call, *args, says: str) -> None:
        with pytest.raises(FMICallException):
            call(*args)
        assert says in said[-1], said[-3:]

    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()  # Event Mode now
        refused(fmu.setContinuousStates, _pointer(x), n, says="fmi2SetContinuousStates is not allowed: the instance is in "
                "Event Mode (EnterContinuousTimeMode first)")
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
        refused(fmu.getContinuousStates, _pointer(x), n - 1, says=f"{n - 1} values, and the system has {n} continuous")
        do_step = fmu.dll.fmi2DoStep  # what a Co-Simulation importer would call
        do_step.argtypes, do_step.restype = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int], ctypes.c_int
        assert do_step(fmu.component, 0.0, 1e-3, 1) == 3  # fmi2Error
        assert "fmi2DoStep is not allowed: this instance is Model Exchange, the call Co-Simulation's" in said[-1]
        refused(fmu.newDiscreteStates, says="Continuous-Time Mode (EnterEventMode first)")
        fmu.getContinuousStates(_pointer(x), n)
        assert np.all(np.isfinite(x)) and np.ptp(x) > 0
    finally:
        fmu.freeInstance()


def test_cosim_run_integrates_it_as_it_runs_the_scene_as_model_exchange(exported, tmp_path):
    """`cosim run FILE.fmu` on the exported FMU and `cosim run SCENE --me` (which integrates the same
    FMU, written for the run) give the same results bit for bit."""
    import pyarrow.csv
    scene, fmus, _ = exported
    for args, folder in (([str(fmus[2])], "fmu"), ([str(SCENE), "--me"], "scene")):
        done = subprocess.run([sys.executable, "-m", "cosim", "run", *args, "--duration", "0.3", "--no-plots",
                               "--out", str(tmp_path / folder)], capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stdout + done.stderr
    lone = pyarrow.csv.read_csv(tmp_path / "fmu" / "meng2.csv")
    whole = pyarrow.csv.read_csv(tmp_path / "scene" / "meng_eq35.csv")
    assert lone.num_rows == whole.num_rows == 301
    for name in ("time", "pose.z", "torque[1]", "current.q[6]"):
        assert np.array_equal(lone[name].to_numpy(), whole[name].to_numpy()), name


def test_a_process_running_many_model_exchange_runs_keeps_none_of_their_fmus():
    """Each `simulate(..., model_exchange=True)` writes the scene's one ME FMU for the run and
    extracts it: after the run neither the FMU nor its extraction is left, nor remembered, so that a
    sweep of such runs in one process accumulates nothing (two runs, the same results)."""
    import cosim
    from cosim.engine import fmi
    scene = load_scene(SCENE).changed({"scene.duration": 0.05})
    before = dict(fmi._LOADED)
    runs = [cosim.simulate(scene, model_exchange=True) for _ in range(2)]
    assert np.array_equal(runs[0]["pose.z"], runs[1]["pose.z"]) and len(runs[0]["pose.z"]) > 10
    added = {key: folder for key, folder in fmi._LOADED.items() if key not in before}
    assert not [key for key in added if "cosim-me-" in key[0]], added
    assert all(folder.is_dir() for _, folder in fmi._LOADED.values())


def test_the_model_exchange_export_refuses_what_it_cannot_write_in_one_line(tmp_path):
    done = export(tmp_path / "x.fmu", 1.0, "--ssp", str(tmp_path / "x.ssp"))
    assert done.returncode == 2 and "the one Model Exchange FMU alone" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_the_api_writes_the_same_fmu(exported, tmp_path):
    """cosim.export_fmu(scene, path, model_exchange=True) writes what `cosim export --fmu --me` does:
    the same description, its integration by fmpy the same bit for bit."""
    import cosim
    scene, fmus, _ = exported
    path = cosim.export_fmu(scene, tmp_path / "api.fmu", model_exchange=True)
    theirs, ours = read_model_description(str(path)), read_model_description(str(fmus[2]))
    assert theirs.modelExchange is not None and theirs.guid == ours.guid
    runs = [simulate_fmu(str(p), fmi_type="ModelExchange", stop_time=0.2, output=["pose.z", "torque[1]"],
                         output_interval=scene.step) for p in (path, fmus[2])]
    for name in ("time", "pose.z", "torque[1]"):
        assert np.array_equal(runs[0][name], runs[1][name]), name
