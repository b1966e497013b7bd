"""Shared fixtures: the built FMUs (built on demand) and drive instances that are freed after use."""

from __future__ import annotations

from pathlib import Path

import pytest
from fmpy import extract

from cosim.platform.scene.parameter_sets import read_parameter_set
from cosim.engine.fmi import FmuInstance
from cosim.engine.artifacts import fmu_path


@pytest.fixture(scope="session")
def pmsm_fmu() -> Path:
    return fmu_path("pmsm_drive")


@pytest.fixture(scope="session")
def pmsm_unzip_dir(pmsm_fmu, tmp_path_factory) -> Path:
    return Path(extract(str(pmsm_fmu), unzipdir=str(tmp_path_factory.mktemp("pmsm_drive"))))


@pytest.fixture(scope="session")
def meng_params() -> dict:
    return read_parameter_set("meng2010")


@pytest.fixture
def make_drive(pmsm_fmu, pmsm_unzip_dir):
    """make_drive(start_values, initialize=True) -> FmuInstance of pmsm_drive, freed after the test."""
    made = []

    def make(start_values: dict | None = None, initialize: bool = True, name: str = "leg1") -> FmuInstance:
        drive = FmuInstance(pmsm_fmu, name, unzip_dir=pmsm_unzip_dir)
        made.append(drive)
        if initialize:
            drive.initialize(start_values or {})
        return drive

    yield make
    for drive in made:
        drive.free()


# The numerics the paper's scene ran at when the tests written around it were: a 1 ms step, the
# first 0.1 s at an eighth of it, no interface Jacobian, no finer windows after the loads' edges,
# each FMU's own solver step. A test that relies on them loads the scene through paper_scene, so
# that the shipped scene's numerics can change (issue 24) without it.
PAPER_NUMERICS = {"scene.step": 1e-3, "coupling.startup_time": 0.1, "coupling.startup_step": 1.25e-4,
                  "coupling.interface_jacobian": False, "coupling.edge_time": 0.0}


# The interface-Jacobian coupling at a 2 ms macro step: each drive's d effort / d flow applied in
# the mechanics, the start-up and the 20 ms after each edge of a load pulse at a sixteenth of the
# step, the drives' RK4 at 0.2 ms and the mechanics' at the macro step (scene overrides; with
# paper_scene, over PAPER_NUMERICS).
INTERFACE_JACOBIAN_2MS = {
    "scene.step": 2e-3, "coupling.interface_jacobian": True, "coupling.startup_time": 0.1,
    "coupling.startup_step": 1.25e-4, "coupling.edge_time": 0.02, 'drive.parameters."solver.step"': 2e-4,
    'mechanics.parameters."solver.step"': 2e-3}


def paper_scene(name: str = "meng_eq35", overrides: dict | None = None):
    """A shipped scene at PAPER_NUMERICS (and `overrides` over them); a solver setting the scene
    file sets (solver.step, solver.exponential, solver.method) goes back to its FMU's own unless
    the overrides set it. Everything goes through
    load_scene's overrides, so whatever reloads the scene from its file (advise, sweeps) gets the
    same scene."""
    from cosim.engine.artifacts import ROOT, fmu_path
    from cosim.engine.checks import variables
    from cosim.platform.ports import DRIVES
    from cosim.platform.scene import load_scene
    path = ROOT / "scenes" / f"{name}.toml"
    overrides = {**PAPER_NUMERICS, **(overrides or {})}
    scene = load_scene(path, overrides)
    for table, fmu, given in (("drive", DRIVES[scene.drive].fmu, scene.drive_parameters),
                              ("mechanics", "mechanics", scene.mechanics_parameters)):
        own = variables(fmu_path(fmu))
        for setting in ("solver.step", "solver.exponential", "solver.method"):
            key = f'{table}.parameters."{setting}"'
            if setting in given and key not in overrides:
                start = own[setting].start
                overrides[key] = {"Real": float, "Integer": int, "Boolean": lambda v: v in (True, "true", 1)}[
                    own[setting].type](start)
    return load_scene(path, overrides)


def platform_run(drive: str, stop_time: float, step: float, mechanics_values=None, drive_values=None,
                 trajectory_values=None, mechanics_outputs=(), drive_outputs=(), order: int = 1,
                 algorithm: str = "gauss-seidel", divergence_ratio: float | None = 0.05, leg_values=None,
                 interface_jacobian: bool = False):
    """The platform wired from parameter values alone (no scene) at a fixed step, through the
    engine's run loop: its Outcome (energy residuals, steps, results), the pose and reference and
    the chosen outputs recorded; RunFailed where an FMU failed or the coupling diverged (watched
    by the divergence monitor unless divergence_ratio is None)."""
    from cosim.engine import DivergenceMonitor, FixedStep, RunFailed
    from cosim.engine.run import execute
    from cosim.platform.ports import platform_algorithm
    from cosim.platform.run.system import columns, platform_structure
    structure = platform_structure(drive, mechanics_values, drive_values, trajectory_values, leg_values=leg_values,
                                   interface_jacobian=interface_jacobian)
    outcome = execute(structure, platform_algorithm(drive, algorithm, order), FixedStep(step), stop_time,
                      *columns(drive, mechanics_outputs, drive_outputs), clock="mechanics",
                      observers=[DivergenceMonitor(ratio=divergence_ratio)] if divergence_ratio else [])
    if outcome.failure is not None:
        raise RunFailed(outcome.failure.error, outcome.result, outcome)
    return outcome


def mounted_tmpfs(folder, options: str):
    """A tmpfs mounted at `folder` (made) with these mount options; pytest.skip where this machine
    cannot mount one (not root)."""
    import subprocess
    folder.mkdir(parents=True, exist_ok=True)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)], capture_output=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({mounted.stderr.decode().strip()})")
    return folder


@pytest.fixture
def small_disk(tmp_path):
    """A folder on a file system of 3 MB (a tmpfs mounted for the test), to fill a disk in a test."""
    yield from _mounted(tmp_path / "small_disk", "size=3m")


@pytest.fixture
def read_only_disk(tmp_path):
    """A folder on a file system mounted read-only (which refuses root's writes too)."""
    yield from _mounted(tmp_path / "read_only", "size=1m,ro")


def _mounted(folder, options: str):
    import subprocess
    mounted_tmpfs(folder, options)
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], capture_output=True)


def fill(folder, leave: int) -> None:
    """Fills the disk that holds `folder` but for `leave` bytes."""
    import shutil
    (folder / "filler").write_bytes(bytes(max(0, shutil.disk_usage(folder).free - leave)))


def fmpy_parameter_set(archive):
    """An SSP archive's SSV values as one fmpy.ssp ParameterSet (fmpy applies no parameter bindings,
    so a run in fmpy.ssp of an archive with a user's FMU, which carries no values of its own as ours
    do, is given them by name, component.variable). Booleans go as 1.0 and 0.0:
    fmpy.ssp sets a Boolean to `value != 0.0`, which the SSV's literal 'false' passes as true
    (fmpy 0.3.32), so a false switch would silently run on."""
    import zipfile
    from fmpy.ssp.ssd import ParameterSet, read_ssv
    parameters = ParameterSet(name="all")
    parameters.parameters = []
    with zipfile.ZipFile(archive) as z:
        for name in z.namelist():
            if name.endswith(".ssv"):
                component = name.rsplit("/", 1)[-1][:-4]
                for p in read_ssv(str(archive), resource=name).parameters:
                    p.name = f"{component}.{p.name}"
                    if p.type == "Boolean":
                        p.value = 1.0 if str(p.value).lower() in ("true", "1") else 0.0
                    parameters.parameters.append(p)
    return parameters


# Per shipped FMU, an experiment that moves it (values set by name before initialization: inputs
# held, parameters), and its communication step where not 1 ms: what the binaries of one model built
# twice (win64 against linux64, FMI 3.0 against FMI 2.0) are compared on.
FMU_EXPERIMENTS = {
    "pmsm_drive": {"angle_ref": 2.0, "torque_ff": 3.0},
    "mechanics": {f"leg[{i}].torque": 8.2 + 0.03 * i for i in range(1, 7)},  # about what holds it: it drifts
    "linear_motor": {"position_ref": 0.01, "force_ff": 5.0},
    "trajectory": {"x.sine[1].amplitude": 0.1, "x.sine[1].frequency": 1.5, "roll.sine[1].amplitude": 0.05,
                   "roll.sine[1].frequency": 0.7, "load.force.z.pulse[1].value": -500.0,
                   "load.force.z.pulse[1].start": 0.5, "load.force.z.pulse[1].end": 0.7},
    "cueing": {"vehicle.file": str(Path(__file__).resolve().parents[1] / "examples" / "vehicle" / "drive.csv")},
}
FMU_EXPERIMENT_STEPS = {"cueing": 5e-3}  # the vehicle's drive brakes from 2 s on: 10 s of it
