"""A scene as one system of Model Exchange FMUs under one solver (`cosim run --me`,
cosim.engine.monolithic): no coupling, so it agrees with the scene's co-simulation converged (at a
16th of its step) within the oracle's windows: the pose to 1e-5 m and rad, the drive torques to 2 %
of their own change through the start-up, and so a vehicle's drive through the cueing; an SSP
system or Model Exchange in real time are one line each (a user's FMU without Model Exchange:
tests/platform/test_user_drives.py)."""

from __future__ import annotations

import numpy as np
import pytest

import cosim
from cosim.cli import main
from cosim.engine.artifacts import ROOT
from cosim.engine.errors import UsageError
from cosim.platform.ports import LEGS, POSE
from cosim.platform.scene import load_scene

DURATION = 0.25  # the start-up, where the drives' and the platform's transients are largest (fixed here)


@pytest.fixture(scope="module")
def runs():
    scene = load_scene("meng_eq35").changed({"scene.duration": DURATION})
    converged = scene.changed({"scene.step": scene.step / 16, "coupling.startup_step": scene.control.startup_step / 16})
    return cosim.simulate(scene, model_exchange=True), cosim.simulate(converged)


def test_the_monolithic_run_agrees_with_the_converged_co_simulation(runs):
    me, cs = runs
    times = me["time"]
    assert times[-1] == pytest.approx(DURATION)
    for dof in POSE:
        reference = np.interp(times, cs["time"], cs[f"pose.{dof}"])
        assert np.abs(me[f"pose.{dof}"] - reference).max() < 1e-5, dof
    for leg in LEGS:
        reference = np.interp(times, cs["time"], cs[f"torque[{leg}]"])
        change = np.ptp(reference)
        assert np.abs(me[f"torque[{leg}]"] - reference).max() < 0.02 * change, leg
    assert any("Model Exchange" in remark for remark in me.report.remarks)
    # no coupling, so no energy residual to speak of: the co-simulation's report has the line, this one not
    assert "energy residual" in cs.report.text() and "energy residual" not in me.report.text()


def test_a_vehicles_drive_runs_as_one_system_too():
    """The car drive's first 3 s (cruise into braking: the washout's tilt at its rate limit) with the
    cueing as a Model Exchange FMU in the one system, its guard stepped at time events (the scene's
    step): the pose (the cue the platform gives) and the torques as the converged co-simulation's,
    by the bounds above."""
    scene = load_scene(ROOT / "examples/vehicle/car_drive.toml").changed({"scene.duration": 3.0})
    converged = scene.changed({"scene.step": scene.step / 16, "coupling.startup_step": scene.control.startup_step / 16})
    me, cs = cosim.simulate(scene, model_exchange=True), cosim.simulate(converged)
    times = me["time"]
    assert np.ptp(me["pose.pitch"]) > 0.03  # the braking's tilt is under way (2.1 deg at 2.5 deg/s)
    assert any("held within the platform's envelope by its guard, stepped at time events 0.001 s apart" in remark
               for remark in me.report.remarks)  # it says so
    for dof in POSE:
        assert np.abs(me[f"pose.{dof}"] - np.interp(times, cs["time"], cs[f"pose.{dof}"])).max() < 1e-5, dof
    for leg in LEGS:
        reference = np.interp(times, cs["time"], cs[f"torque[{leg}]"])
        assert np.abs(me[f"torque[{leg}]"] - reference).max() < 0.02 * np.ptp(reference), leg


def test_the_mpc_drive_runs_as_one_system_through_its_solves():
    """The MPC car drive's first second (50 solves, each a time event 20 ms after the last, beside the
    vehicle table's 10 ms rows: an event and a row, or a row and an output point, fall a few ulps
    apart, e.g. 0.12 + 0.02 against 0.14) runs to its end (it stopped at 0.14 s on CVODE's "tout
    too close to t0") and agrees with the converged co-simulation by the bounds above."""
    scene = load_scene(ROOT / "examples/vehicle/car_drive_mpc.toml").changed({"scene.duration": 1.0})
    converged = scene.changed({"scene.step": scene.step / 16, "coupling.startup_step": scene.control.startup_step / 16})
    me, cs = cosim.simulate(scene, model_exchange=True), cosim.simulate(converged)
    times = me["time"]
    assert times[-1] == pytest.approx(1.0) and len(times) == round(1.0 / scene.step) + 1
    for dof in POSE:
        assert np.abs(me[f"pose.{dof}"] - np.interp(times, cs["time"], cs[f"pose.{dof}"])).max() < 1e-5, dof
    for leg in LEGS:
        reference = np.interp(times, cs["time"], cs[f"torque[{leg}]"])
        assert np.abs(me[f"torque[{leg}]"] - reference).max() < 0.02 * np.ptp(reference), leg


def test_what_cannot_run_as_model_exchange_is_one_line(tmp_path, capsys):
    with pytest.raises(UsageError, match="not with real_time"):
        cosim.simulate("meng_eq35", model_exchange=True, real_time=1.0)
    assert main(["run", str(tmp_path / "x.ssp"), "--me"]) == 2
    assert "--me: for a scene" in capsys.readouterr().err


def test_the_model_exchange_export_is_one_strongly_coupled_system(tmp_path, capsys):
    """`cosim export SCENE --ssp FILE --me`: a schema-valid archive (write_ssp validates it) whose
    FMUs are the Model Exchange ones inside one system annotated for OMSimulator's CVODE master;
    our engine names what it does not read back, and the options that do not apply are one line."""
    import zipfile

    from lxml import etree

    from cosim.engine.ssp import NS
    archive = tmp_path / "meng.ssp"
    assert main(["export", "meng_eq35", "--ssp", str(archive), "--me"]) == 0
    with zipfile.ZipFile(archive) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
        inner = root.find("ssd:System/ssd:Elements/ssd:System", NS)
        assert inner is not None and inner.find(".//oms:VariableStepSolver", NS).get("description") == "cvode"
        assert len(inner.findall("ssd:Elements/ssd:Component", NS)) == 8
        for component in inner.iterfind("ssd:Elements/ssd:Component", NS):
            with z.open(component.get("source")) as fmu, zipfile.ZipFile(fmu) as f:
                assert b"<ModelExchange" in f.read("modelDescription.xml")
    capsys.readouterr()
    assert main(["run", str(archive), "--no-plots", "--out", str(tmp_path / "out")]) == 2
    assert "nested systems are not supported (an export of Model Exchange FMUs" in capsys.readouterr().err
    assert main(["export", "meng_eq35", "--osp", str(tmp_path / "osp"), "--me"]) == 2
    assert "export --me: an SSP archive alone" in capsys.readouterr().err


def test_a_model_exchange_run_shows_how_far_it_got(tmp_path):
    """`cosim run --me` shows its progress as a co-simulation does (the same observer): off a terminal
    a line per `every` seconds with the fraction and the simulated time, ending at the stop time."""
    import io
    from dataclasses import replace
    from cosim.engine.observers import Progress
    from cosim.engine.monolithic import integrate_plan
    from cosim.platform.run.compile import compile_scene, model_exchange_plan
    plan, _ = model_exchange_plan(compile_scene(load_scene("meng_eq35").changed({"scene.duration": 0.25})))
    stream = io.StringIO()
    outcome = integrate_plan(plan, progress=[Progress("meng_eq35", every=0.0, stream=stream)])
    lines = stream.getvalue().splitlines()
    assert outcome.failure is None and len(lines) >= 2
    fractions = [float(line.split(": ")[1].split(" %")[0]) for line in lines]
    assert fractions == sorted(fractions) and fractions[-1] == 100.0 and "t = 0.25 s" in lines[-1]


def test_the_solver_takes_each_fmus_own_nominals():
    """The run's absolute tolerance per state is its relative one times the FMU's nominal of it (as
    fmpy and fmusim set it): the MPC cueing alone, live on the car drive's braking and lane change
    (12 s, 600 solves), integrated at rtol 1e-6 (fixed here) gives its Co-Simulation's exact 1 ms
    steps to 2e-3 of each output's range (measured at most 7.7e-4), the perceived angular-rate
    errors included, whose canal states are far below 1 (with nominals of at least 1, as this run
    took them before, those were 3.6e-3 to 7.3e-3 off)."""
    from fmpy import simulate_fmu
    from cosim.engine.artifacts import fmu_path
    from cosim.engine.monolithic import integrate
    from cosim.engine.structure import Component, Experiment, SystemStructure
    values = {"vehicle.file": str(ROOT / "examples/vehicle/drive.csv"), "algorithm": 2}
    outputs = [f"mpc.perceived_error.{k}.{a}" for k in ("specific_force", "angular_rate") for a in "xyz"]
    outputs += [f"pose_ref.{dof}" for dof in POSE]
    structure = SystemStructure("mpc", [Component("cueing", fmu_path("cueing", model_exchange=True), values)], [],
                                experiment=Experiment(0.0, 12.0, 1e-3))
    me = integrate(structure, 12.0, [("cueing", o) for o in outputs], names=outputs, relative_tolerance=1e-6)
    assert me.failure is None
    cs = simulate_fmu(str(fmu_path("cueing")), stop_time=12.0, step_size=1e-3, output_interval=1e-3, output=outputs,
                      start_values=values)
    for o in outputs:
        reference = np.interp(me.result["time"], cs["time"], cs[o])
        assert np.abs(me.result[o] - reference).max() < 2e-3 * np.ptp(reference), o
