"""The whole Meng scene as one SSP archive (python -m cosim export), run by our master and by three
other tools, each compared with our master running the same SSP with the same algorithm
(order-0 Jacobi at the same 1 ms step):
- our master, scene TOML against the exported SSP with the scene's own settings: bit for bit;
- Ecos (ecospy): bit for bit;
- fmpy.ssp.simulate_ssp: bit for bit with our `zero_start` (fmpy starts every connection at 0.0);
  fmpy applies no parameter bindings, so its parameter set is read from the archive's SSV files;
- libcosim (libcosimpy from_ssp_file): the pose bit for bit, the drive torques within 1e-10 relative;
  libcosim counts time in integer nanoseconds, so the trajectory's sines are evaluated at times that
  differ from our accumulated t + h by round-off.
Where a tool cannot represent our coupling (input derivatives, step doubling), it runs the SSP with
its own algorithm: the export's message says so."""

from __future__ import annotations

import shutil
import zipfile

import numpy as np
import pytest

from cosim.cli import main
from cosim.engine import Algorithm, FixedStep
from cosim.engine.execution import Execution
from cosim.engine.artifacts import ROOT
from cosim.engine.ssp import PARAMETER_SET, read_ssp
from conftest import paper_scene
from cosim.platform.scene import load_scene

STOP, STEP = 0.3, 1e-3
LEGS = [f"pmsm{i}" for i in range(1, 7)]


@pytest.fixture(scope="module")
def meng_ssp(tmp_path_factory):
    path = tmp_path_factory.mktemp("ssp") / "meng.ssp"
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(path)]) == 0
    return path


def ours(path, zero_start: bool = False) -> dict[str, np.ndarray]:
    """Our master on the SSP: order-0 Jacobi without the consistency sweep, as Ecos starts (on this
    system the sweep changes nothing: the outputs at the start do not feed through from inputs)."""
    record = [("mechanics", "leg[1].angle"), ("mechanics", "leg[4].speed"), *[(d, "torque") for d in LEGS]]
    execution = Execution(read_ssp(path), Algorithm("jacobi", 0, None, 0, zero_start), FixedStep(STEP), record,
                          clock="mechanics")
    try:
        return execution.run(STOP)
    finally:
        execution.free()


def test_export_then_run_reproduces_the_scene_bit_for_bit(meng_ssp, tmp_path):
    assert main(["run", str(ROOT / "scenes" / "meng_eq35.toml"), "--out", str(tmp_path / "a"), "--no-plots",
                 "--duration", "0.5"]) == 0
    assert main(["run", str(meng_ssp), "--out", str(tmp_path / "b"), "--duration", "0.5"]) == 0
    a = np.genfromtxt(tmp_path / "a" / "meng_eq35.csv", delimiter=",", names=True)
    b = np.genfromtxt(tmp_path / "b" / "meng.csv", delimiter=",", names=True)
    assert a.dtype.names == b.dtype.names and len(a) == len(b)
    control = load_scene(ROOT / "scenes" / "meng_eq35.toml").control
    first = control.startup_step if control.startup_time else control.step
    assert np.diff(b["time"])[0] == pytest.approx(first, rel=1e-9)  # the finer start travels in the SSP
    for name in a.dtype.names:
        assert np.array_equal(a[name], b[name]), name


def test_ecos_runs_the_ssp_bit_for_bit_like_our_master(meng_ssp):
    ecos_matches(meng_ssp)


def test_fmpy_ssp_runs_the_ssp_bit_for_bit_like_our_master(meng_ssp):
    fmpy_matches(meng_ssp)


def test_libcosim_runs_the_ssp_like_our_master_to_round_off(meng_ssp, tmp_path):
    libcosim_matches(meng_ssp, tmp_path / "meng")


def ecos_matches(meng_ssp) -> None:
    """Ecos runs the SSP bit for bit like our master (order-0 Jacobi at STEP)."""
    from ecospy import EcosSimulation
    reference = ours(meng_ssp)
    simulation = EcosSimulation(ssp_path=str(meng_ssp), step_size=STEP)
    try:
        simulation.init(parameter_set=PARAMETER_SET)
        simulation.step(int(round(STOP / STEP)))
        assert simulation.get_real("mechanics::leg[1].angle") == reference["mechanics.leg[1].angle"][-1]
        assert simulation.get_real("mechanics::leg[4].speed") == reference["mechanics.leg[4].speed"][-1]
        for d in LEGS:
            assert simulation.get_real(f"{d}::torque") == reference[f"{d}.torque"][-1]
    finally:
        simulation.terminate()


def fmpy_matches(meng_ssp, bindings: bool = False) -> None:
    """fmpy.ssp, called as a user calls it (it applies no parameter bindings: our FMUs carry the
    scene's values; with `bindings`, for a user's FMU that carries none, the SSV's values given by
    name), runs the SSP bit for bit like our master with zero_start."""
    from fmpy.ssp.simulation import simulate_ssp
    from conftest import fmpy_parameter_set
    theirs = simulate_ssp(str(meng_ssp), stop_time=STOP, step_size=STEP,
                          parameter_set=fmpy_parameter_set(meng_ssp) if bindings else None)
    reference = ours(meng_ssp, zero_start=True)  # fmpy's rows are labelled with the step's start
    assert len(theirs) == len(reference) - 1
    for name in ("mechanics.leg[1].angle", "mechanics.leg[4].speed", *[f"{d}.torque" for d in LEGS]):
        assert np.array_equal(theirs[name], reference[name][1:]), name


def libcosim_matches(meng_ssp, folder, torque_rel: float = 1e-9) -> None:
    """libcosim runs the SSP like our master: the pose to 1e-12, the torques to `torque_rel`.
    libcosim's clock counts whole nanoseconds, so the times it hands the FMUs differ from ours in
    their last bits; the drives' loops (about 600 N m per rad of angle error) make that a torque
    difference of about 1e-10 of the torque (1.3e-10 measured at 0.3 s): 1e-9 is round-off with a
    tenfold margin for the scene's numerics."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    log_output_level(CosimLogLevel.ERROR)
    with zipfile.ZipFile(meng_ssp) as archive:
        archive.extractall(folder)
    reference = ours(meng_ssp)
    execution = CosimExecution.from_ssp_file(str(folder), step_size=int(round(STEP * 1e9)))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    assert execution.simulate_until(int(round(STOP * 1e9)))
    index = {s.name.decode(): s.index for s in execution.slave_infos()}

    def value(instance: str, name: str) -> float:
        refs = {v.name.decode(): v.reference for v in execution.slave_variables(index[instance])}
        return observer.last_real_values(index[instance], [refs[name]])[0]

    assert value("mechanics", "leg[1].angle") == pytest.approx(reference["mechanics.leg[1].angle"][-1], rel=1e-12)
    for d in LEGS:
        assert value(d, "torque") == pytest.approx(reference[f"{d}.torque"][-1], rel=torque_rel)
    shutil.rmtree(folder)


def run_osp(xml, stop: float) -> dict[str, float]:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(str(xml))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    assert execution.simulate_until(int(round(stop * 1e9)))
    index = {s.name.decode(): s.index for s in execution.slave_infos()}
    values = {}
    for instance, name in [("mechanics", "leg[1].angle"), *[(d, "torque") for d in LEGS]]:
        refs = {v.name.decode(): v.reference for v in execution.slave_variables(index[instance])}
        values[f"{instance}.{name}"] = observer.last_real_values(index[instance], [refs[name]])[0]
    return values


def test_libcosim_runs_the_osp_configuration_like_our_master_to_round_off(tmp_path):
    """The Meng scene as OspSystemStructure.xml (python -m cosim export --osp), fixed step: the same
    agreement as the SSP run in libcosim."""
    from cosim.engine.osp import write_osp
    from cosim.platform.run.compile import scene_structure
    structure = scene_structure(paper_scene("meng_eq35"))  # the 1 ms numerics libcosim's fixed step compares at
    theirs = run_osp(write_osp(structure, tmp_path, power_bonds=False), STOP)
    execution = Execution(structure, Algorithm("jacobi", 0, None, 0), FixedStep(STEP),
                          [("mechanics", "leg[1].angle"), *[(d, "torque") for d in LEGS]], clock="mechanics")
    try:
        reference = execution.run(STOP)
    finally:
        execution.free()
    assert theirs["mechanics.leg[1].angle"] == pytest.approx(reference["mechanics.leg[1].angle"][-1], rel=1e-12)
    for d in LEGS:
        assert theirs[f"{d}.torque"] == pytest.approx(reference[f"{d}.torque"][-1], rel=1e-10)


@pytest.mark.xfail(strict=True, reason="libcosimpy 0.0.6's configuration parser rejects more than one power bond "
                   "(libcosim fixed it upstream, see its OspSystemStructure_MultiBond.xml); when a fixed libcosimpy "
                   "is pinned this passes and the strict xfail fails, so the note can go")
def test_libcosim_loads_the_osp_configuration_with_its_six_power_bonds(tmp_path):
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--osp", str(tmp_path)]) == 0
    run_osp(tmp_path / "OspSystemStructure.xml", 0.01)


def test_the_export_says_what_other_tools_will_not_do(tmp_path, capsys):
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(tmp_path / "m.ssp")]) == 0
    out = capsys.readouterr().out
    assert "without input extrapolation of order 1" in out and "without Gauss-Seidel stepping" in out
