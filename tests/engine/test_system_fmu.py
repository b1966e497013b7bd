"""The whole scene as ONE Co-Simulation FMU (`cosim export SCENE --fmu FILE`, issue 60), as a user
meets it in tools we did not write: fmpy's simulate_fmu and Reference-FMUs' fmusim (../shared/peers).

- At a communication step that is a multiple of the scene's step (1, 2, 5, 10 ms) the FMU's outputs
  are `cosim run`'s bit for bit at every communication point: one coupling, the kernel's, inside.
- At a step shorter than the scene's (0.5 ms, 0.3 ms) it steps finer inside: within the shipped
  scenes' tolerances of the scene's converged run (the pose within 1e-5 after the start, the drive
  efforts per window within theirs: cosim.platform.run.accuracy.judge).
- fmusim runs it as fmpy does, to the 16 digits its CSV holds; fmpy's validation (the FMI 2.0
  schema included) finds nothing; a broken description or a call at the wrong time is refused
  with the reason logged.

The scene runs over its probe (the start-up at its finer step, the first impact with its refined
edges, steady tracking): every part of its plan."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from cosim.engine.artifacts import ROOT
from cosim.platform.run.accuracy import judge, probe_duration
from cosim.platform.run.portable import converged
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene

SCENE = ROOT / "scenes" / "meng_eq35.toml"


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The scene over its probe, exported as the user does it, and `cosim run`'s results of it."""
    scene = load_scene(SCENE)
    duration = probe_duration(scene)
    scene = scene.changed({"scene.duration": duration})
    target = tmp_path_factory.mktemp("fmu") / "meng.fmu"
    done = subprocess.run([sys.executable, "-m", "cosim", "export", str(SCENE), "--fmu", str(target), "--duration",
                           repr(duration)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"written: {target}" in done.stdout
    ours, _ = run_scene(scene)
    return scene, target, ours


def fmpy_run(fmu: Path, stop: float, step: float, names) -> np.ndarray:
    """fmpy's simulate_fmu as a user calls it. With fmpy's own logger: fmpy 0.3.32's logging proxy
    keeps one process-wide logger, so a `logger=` callback, freed when the run returns, would be
    called by the next FMU that logs through fmpy's default callbacks (a crash in a later test)."""
    return simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step, output=list(names))


def at_common_times(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    _, i, j = np.intersect1d(np.round(a["time"], 9), np.round(b["time"], 9), return_indices=True)
    return a[i], b[j]


@pytest.mark.parametrize("step", [1e-3, 2e-3, 5e-3, 1e-2])
def test_at_multiples_of_the_scenes_step_the_fmu_is_cosim_run_bit_for_bit(exported, step):
    scene, fmu, ours = exported
    names = [n for n in ours.dtype.names if n != "time"]
    result = fmpy_run(fmu, scene.duration, step, names)
    theirs, mine = at_common_times(result, ours)
    assert len(theirs) == round(scene.duration / step) + 1  # every communication point is one of cosim run's
    for name in names:
        assert np.array_equal(theirs[name], mine[name]), name


@pytest.mark.parametrize("step", [5e-4, 3e-4])
def test_at_shorter_steps_it_steps_finer_within_the_scenes_tolerances(exported, step):
    scene, fmu, ours = exported
    names = [n for n in ours.dtype.names if n != "time"]
    result = fmpy_run(fmu, scene.duration, step, names)
    verdict = judge(scene, result, converged(scene, scene.duration))
    assert verdict.pose_error <= 1e-5 and verdict.ratio <= 1.0, verdict
    theirs, mine = at_common_times(result, ours)  # and near cosim run where their points meet
    assert len(theirs) >= scene.duration / 3e-3
    torque = max(np.ptp(mine[f"torque[{k}]"]) for k in range(1, 7))
    assert max(np.max(np.abs(theirs[f"torque[{k}]"] - mine[f"torque[{k}]"])) for k in range(1, 7)) < 0.02 * torque


def test_fmusim_runs_it_as_fmpy_does(exported, tmp_path):
    from peers import fmusim
    scene, fmu, ours = exported
    names = [n for n in ours.dtype.names if n != "time"]
    for step in (1e-3, 1e-2):
        out = tmp_path / f"fmusim_{step:g}.csv"
        done = subprocess.run([str(fmusim()), "--interface-type", "cs", "--stop-time", repr(scene.duration),
                               "--output-interval", repr(step), "--output-file", str(out), str(fmu)],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        theirs = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
        mine = fmpy_run(fmu, scene.duration, step, names)
        assert len(theirs) == len(mine) == round(scene.duration / step) + 1
        for name in names:  # the 16 significant digits fmusim writes
            scale = max(np.max(np.abs(mine[name])), 1e-300)
            assert np.max(np.abs(theirs[name] - mine[name])) <= 1e-15 * scale, (step, name)


def test_fmpys_validation_finds_nothing_and_it_carries_everything(exported):
    from fmpy.validation import validate_fmu
    _, fmu, _ = exported
    assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as archive:
        files = set(archive.namelist())
    assert {"binaries/linux64/meng.so", "resources/system.txt"} <= files
    assert any(f.startswith("resources/fmus/mechanics/binaries/linux64/") for f in files)
    assert not any(f.endswith(".ssv") or f.endswith(".ssd") for f in files)  # its values inside, no SSP


def test_as_fmi3_it_is_the_fmi2_fmu_bit_for_bit(exported, tmp_path):
    """`--fmi 3`: the same system behind FMI 3.0's API (the independent variable `time` added), valid
    by fmpy's validation, its outputs those of the FMI 2.0 FMU bit for bit at 1 and 10 ms."""
    from fmpy.validation import validate_fmu
    scene, fmu, ours = exported
    three = tmp_path / "meng3.fmu"
    done = subprocess.run([sys.executable, "-m", "cosim", "export", str(SCENE), "--fmu", str(three), "--fmi", "3",
                           "--duration", repr(scene.duration)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and "FMI 3.0 Co-Simulation" in done.stdout, done.stdout + done.stderr
    assert validate_fmu(str(three)) == []
    names = ["pose.z", "torque[1]", "current.q[6]"]
    for step in (1e-3, 1e-2):
        two = fmpy_run(fmu, scene.duration, step, names)
        result = simulate_fmu(str(three), stop_time=scene.duration, step_size=step, output_interval=step,
                              output=names, fmi_type="CoSimulation")
        assert len(result) == len(two)
        for name in ("time", *names):
            assert np.array_equal(result[name], two[name]), (step, name)


def test_cosim_run_runs_the_fmu_as_fmpy_does(exported, tmp_path):
    scene, fmu, ours = exported
    done = subprocess.run([sys.executable, "-m", "cosim", "run", str(fmu), "--out", str(tmp_path), "--duration",
                           "0.3"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    import pyarrow.csv
    table = pyarrow.csv.read_csv(tmp_path / "meng.csv")
    mine = fmpy_run(fmu, 0.3, scene.step, ["pose.z", "torque[1]"])
    for name in ("pose.z", "torque[1]"):
        assert np.allclose(table[name].to_numpy(), mine[name], rtol=1e-15, atol=0)


def test_a_broken_description_is_refused_naming_its_line(exported, tmp_path):
    from fmpy import extract
    from cosim.engine.fmi import FmuError, FmuInstance
    _, fmu, _ = exported
    folder = Path(extract(str(fmu), str(tmp_path / "unpacked")))
    description = folder / "resources" / "system.txt"
    lines = description.read_text().splitlines()
    where = next(k for k, line in enumerate(lines) if line.startswith("sequence"))
    lines[where] = lines[where].replace("sequence", "sequense")
    description.write_text("\n".join(lines) + "\n")
    broken = tmp_path / "broken.fmu"
    with zipfile.ZipFile(broken, "w") as archive:
        for path in folder.rglob("*"):
            if path.is_file():
                archive.write(path, path.relative_to(folder).as_posix())
    with pytest.raises(FmuError, match=f"system.txt:{where + 1}: not what a system description holds there"):
        FmuInstance(broken, "platform")


def test_calls_at_the_wrong_time_are_refused_with_the_reason(exported):
    from cosim.engine.fmi import FmuError, FmuInstance
    _, fmu, _ = exported
    instance = FmuInstance(fmu, "platform")
    try:
        with pytest.raises(FmuError, match="fmi2DoStep is not allowed now"):
            instance.do_step(1e-3)  # before initialization
        instance.initialize()
        instance.do_step(1e-3)
        instance.time = 0.5
        with pytest.raises(FmuError, match="where the system is at t = 0.001 s"):
            instance.do_step(1e-3)  # not from where the last step ended
        with pytest.raises(FmuError, match="no variable of this type has value reference"):
            instance._call("fmi2GetReal", instance.fmu.getReal, [len(instance.variables) + 5])
        assert instance.get("pose.z") > 1.5
        # an output is the system's, even where the nested variable is an input (a drive's speed,
        # which the mechanics feeds): the importer cannot set it (found by the system FMU's fuzzer, scripts/fuzz.sh)
        speed = instance.variables["speed[1]"]
        assert speed.causality == "output"
        with pytest.raises(FmuError, match=f"value reference {speed.valueReference} is an output of this FMU"):
            instance._call("fmi2SetReal", instance.fmu.setReal, [speed.valueReference], [1.0])
        # a step that would take more of the system's steps than the models' layer takes in one is
        # refused before it starts, not run for as long as it would take
        instance.time = 1e-3
        with pytest.raises(FmuError, match="would take more than 200000 of the system's steps"):
            instance.do_step(1e6)
        instance.do_step(1e-3)  # and the instance runs on from where it was
        assert instance.time == pytest.approx(2e-3)
    finally:
        instance.free()


def test_values_are_read_from_initialization_on_and_set_until_it_ends(exported):
    """FMI 2.0's state machine: no value is read before initialization (not even none of them);
    after a failed initialization only reading, a reset or freeing it are allowed."""
    from cosim.engine.fmi import FmuError, FmuInstance
    _, fmu, _ = exported
    instance = FmuInstance(fmu, "platform")
    try:
        with pytest.raises(FmuError, match="fmi2GetReal is not allowed now: the FMU is instantiated"):
            instance._call("fmi2GetReal", instance.fmu.getReal, [])
        instance._call("fmi2SetupExperiment", instance.fmu.setupExperiment, None, 0.0, None)
        instance._call("fmi2EnterInitializationMode", instance.fmu.enterInitializationMode)
        instance._call("fmi2ExitInitializationMode", instance.fmu.exitInitializationMode)
        instance._call("fmi2Terminate", instance.fmu.terminate)
        assert instance.get("pose.z") > 1.5  # a terminated FMU's values are read
        with pytest.raises(FmuError, match="fmi2SetReal is not allowed now: the FMU is terminated"):
            instance._call("fmi2SetReal", instance.fmu.setReal, [], [])
    finally:
        instance.free()


def test_parameters_are_passed_on_to_the_instance_whose_they_are(exported):
    """A heavier platform given to the FMU as a user gives it (a start value) runs as the scene's
    system with that value on its mechanics component (the drives as designed for the scene)."""
    from dataclasses import replace
    from fmpy import read_model_description
    from cosim.engine.run import run
    from cosim.engine.structure import with_parameters
    from cosim.platform.run.compile import compile_scene
    scene, fmu, ours = exported
    names = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    mass = "mechanics.platform.mass"
    assert names[mass].causality == "parameter"
    heavier = 1.5 * float(names[mass].start)
    result = simulate_fmu(str(fmu), stop_time=0.3, step_size=1e-3, output=["torque[1]"], start_values={mass: heavier})
    plan = compile_scene(scene).plan
    variant, _ = run(replace(plan, structure=with_parameters(plan.structure, {"mechanics": {"platform.mass": heavier}}),
                             stop_time=0.3))
    theirs, mine = at_common_times(result, variant)
    assert len(theirs) == 301 and np.array_equal(theirs["torque[1]"], mine["torque[1]"])
    assert not np.array_equal(theirs["torque[1]"], at_common_times(result, ours)[1]["torque[1]"])


def test_the_export_refuses_what_it_cannot_write_in_one_line(tmp_path):
    for extra, says in ((["--fmu", str(tmp_path / "x.zip")], "ends in .fmu"),
                        (["--fmu", str(tmp_path / "x.fmu"), "--set", "coupling.step_control=doubling"],
                         "step_control")):
        done = subprocess.run([sys.executable, "-m", "cosim", "export", str(SCENE), *extra], capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 2 and says in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_a_reset_runs_it_again_bit_for_bit(exported):
    """fmi2Reset puts every nested instance back at the scene's values and the coupling at its start:
    the same 0.2 s again, bit for bit."""
    from cosim.engine.fmi import FmuInstance
    _, fmu, _ = exported
    instance = FmuInstance(fmu, "platform")
    runs = []
    try:
        for _ in range(2):
            instance.time = 0.0
            instance.initialize()
            runs.append([instance.get("torque[1]") for _ in range(200) if instance.do_step(1e-3) is None])
            instance._call("fmi2Terminate", instance.fmu.terminate)
            instance._call("fmi2Reset", instance.fmu.reset)
    finally:
        instance.free()
    assert np.ptp(runs[0]) > 1.0 and runs[0] == runs[1]
