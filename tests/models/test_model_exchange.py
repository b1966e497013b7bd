"""The Model Exchange FMUs (FMI 2.0 build/fmus_me/, FMI 3.0 build/fmus3_me/; fmu/common/fmi2_me.c):
every model that offers it passes fmpy's validation, carries the same binaries and GUID as its
Co-Simulation twin, the FMI 3.0 one runs bit for bit as the FMI 2.0 one,
and, integrated by fmpy's CVODE, gives what its Co-Simulation twin converges to: the mechanics to
round-off of its fall, the drives as their inner step shrinks (their error falling with it, to
1e-5 of each output's range), the trajectory's load pulses exactly at their edges (its time
events), the cueing's washout what its exact steps converge to as they shrink and its MPC what
they give (its solves time events). A Model Exchange instance refuses Co-Simulation's calls and
the reverse (and a Co-Simulation instance the Model Exchange states' value references); a configuration with events the FMU does not give (the PMSM drive's switching
inverter) is refused at initialization with its reason; the cueing's guard steps at time events as
its Co-Simulation at that step."""

from __future__ import annotations

import ctypes
import zipfile
from xml.etree import ElementTree

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from cosim.engine.artifacts import ROOT, fmu_path

MODEL_EXCHANGE = ("mechanics", "pmsm_drive", "linear_motor", "trajectory", "cueing")
DRIVE = str(ROOT / "examples/vehicle/drive.csv")  # the shipped car drive at the occupant's head
GRID = np.linspace(0.0, 1.0, 101)


def description(path) -> ElementTree.Element:
    with zipfile.ZipFile(path) as archive:
        return ElementTree.fromstring(archive.read("modelDescription.xml"))


def simulate(name: str, stop: float, outputs: list[str], values: dict, me: bool, step: float | None = None):
    """The FMU through fmpy: Model Exchange by CVODE (rtol 1e-10), or Co-Simulation at `step`;
    the outputs on 101 points over the run."""
    path = fmu_path(name, model_exchange=me)
    if me:
        result = simulate_fmu(str(path), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10,
                              stop_time=stop, output_interval=stop / 100, output=outputs, start_values=values)
    else:
        result = simulate_fmu(str(path), stop_time=stop, step_size=step, output_interval=stop / 100, output=outputs,
                              start_values=values)
    return {o: np.interp(GRID * stop, result["time"], result[o]) for o in outputs}


@pytest.mark.parametrize("fmi", (2, 3))
@pytest.mark.parametrize("name", MODEL_EXCHANGE)
def test_each_is_valid_and_the_twin_of_its_co_simulation(name, fmi):
    path = fmu_path(name, fmi=fmi, model_exchange=True)
    assert not validate_fmu(str(path)), validate_fmu(str(path))
    me, cs = description(path), description(fmu_path(name, fmi=fmi))
    token = "guid" if fmi == 2 else "instantiationToken"
    assert me.get(token) == cs.get(token)
    assert me.find("ModelExchange").get("modelIdentifier") == cs.find("CoSimulation").get("modelIdentifier")
    with zipfile.ZipFile(path) as a, zipfile.ZipFile(fmu_path(name, fmi=fmi)) as b:
        binaries = [n for n in a.namelist() if n.startswith("binaries/") and not n.endswith("/")]
        assert binaries and all(a.read(n) == b.read(n) for n in binaries)  # the same binaries, both interfaces
    states = [v for v in me.iter() if (v.get("name") or "").startswith("ode.x[")]
    derivatives = (me.findall("ModelStructure/Derivatives/Unknown") if fmi == 2 else
                   me.findall("ModelStructure/ContinuousStateDerivative"))
    assert len(states) == len(derivatives)


@pytest.mark.parametrize("name, outputs, values", [
    ("mechanics", ["pose.z", "pose.roll"], {}),
    ("pmsm_drive", ["torque", "voltage.q"], {"angle_ref": 0.5}),
    ("trajectory", ["load.force.x", "pose_ref.z"], {"load.force.x.pulse[1].value": 100.0,
                                                   "load.force.x.pulse[1].start": 0.01,
                                                   "load.force.x.pulse[1].end": 0.03}),
    ("cueing", ["pose_ref.x", "pose_ref.pitch", "mpc.perceived_error.specific_force.x"],
     {"vehicle.file": DRIVE, "algorithm": 2}),
], ids=["mechanics", "pmsm_drive", "trajectory", "cueing_mpc"])
def test_fmi3_model_exchange_is_fmi2_model_exchange_bit_for_bit(name, outputs, values):
    """The FMI 3.0 layer maps each Model Exchange call onto the FMI 2.0 one: under fmpy's CVODE
    the same run, to the last bit."""
    runs = [simulate_fmu(str(fmu_path(name, fmi=fmi, model_exchange=True)), fmi_type="ModelExchange", solver="CVode",
                         relative_tolerance=1e-10, stop_time=0.05, output_interval=5e-4, output=outputs,
                         start_values=values) for fmi in (2, 3)]
    for o in outputs:
        assert np.array_equal(runs[0][o], runs[1][o]), o


def test_the_mechanics_falls_as_its_co_simulation_does():
    """The platform let go (no torques) for 0.2 s: CVODE on the Model Exchange FMU and the FMU's
    own solver at 0.1 ms agree to 1e-9 m and rad on a fall of centimetres."""
    outputs = ["pose.x", "pose.z", "pose.roll", "pose.pitch"]
    me = simulate("mechanics", 0.2, outputs, {}, me=True)
    cs = simulate("mechanics", 0.2, outputs, {}, me=False, step=1e-4)
    assert np.ptp(cs["pose.z"]) > 0.01
    for o in outputs:
        assert np.abs(me[o] - cs[o]).max() < 1e-9, o


@pytest.mark.parametrize("name, outputs, values", [
    ("pmsm_drive", ["torque", "current.q", "voltage.q"], {"angle_ref": 0.5}),
    ("linear_motor", ["force", "current"], {"position_ref": 0.05}),
], ids=["pmsm_drive", "linear_motor"])
def test_a_drive_is_what_its_co_simulation_converges_to(name, outputs, values):
    """A step of the reference (the controllers saturating on the way): the Co-Simulation twin
    on its RK4 at inner steps of 10, 1 and 0.1 us comes closer to the Model Exchange run with every
    step, to within 1e-5 of each output's range at the finest (fixed numerics stated here)."""
    me = simulate(name, 0.05, outputs, values, me=True)
    errors = []
    for inner in (1e-5, 1e-6, 1e-7):
        cs = simulate(name, 0.05, outputs, {**values, "solver.exponential": False, "solver.step": inner}, me=False,
                      step=5e-4)
        errors.append([np.abs(me[o] - cs[o]).max() / np.ptp(cs[o]) for o in outputs])
    errors = np.array(errors)
    assert (errors[1:] < errors[:-1]).all() or (errors[-1] < 1e-9).all(), errors
    assert (errors[-1] < 1e-5).all(), errors


def test_the_load_pulses_are_time_events():
    """A pulse from 0.3 s to 0.55 s: the Model Exchange run stops at both edges (fmpy records each
    event's time) and holds the pulse exactly in between, as the Co-Simulation twin does."""
    values = {"load.force.x.pulse[1].value": 100.0, "load.force.x.pulse[1].start": 0.3,
              "load.force.x.pulse[1].end": 0.55}
    result = simulate_fmu(str(fmu_path("trajectory", model_exchange=True)), fmi_type="ModelExchange", solver="CVode",
                          stop_time=1.0, output_interval=0.1, output=["load.force.x"], start_values=values)
    times = result["time"]
    assert (np.isclose(times, 0.3).sum(), np.isclose(times, 0.55).sum()) == (2, 2)
    inside = (times >= 0.3) & (times <= 0.55)
    assert (result["load.force.x"][inside] == 100.0).all() and (result["load.force.x"][~inside] == 0.0).all()


def instantiated(name: str, me: bool):
    """fmpy's FMU2Model (Model Exchange) or FMU2Slave on the FMU, instantiated; its log printed."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model, FMU2Slave
    path = fmu_path(name, model_exchange=me)
    model = read_model_description(str(path))
    kind = FMU2Model if me else FMU2Slave
    fmu = kind(guid=model.guid, unzipDirectory=extract(str(path)),
               modelIdentifier=(model.modelExchange if me else model.coSimulation).modelIdentifier,
               instanceName=name)
    fmu.instantiate(loggingOn=True)
    return fmu, {v.name: v.valueReference for v in model.modelVariables}


def test_the_interfaces_refuse_each_others_calls(capsys):
    me, _ = instantiated("mechanics", True)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    do_step = me.dll.fmi2DoStep
    do_step.argtypes, do_step.restype = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int], ctypes.c_int
    assert do_step(me.component, 0.0, 1e-3, 0) == 3  # fmi2Error
    cs, _ = instantiated("mechanics", False)
    cs.setupExperiment(startTime=0.0)
    cs.enterInitializationMode()
    cs.exitInitializationMode()
    derivatives = cs.dll.fmi2GetDerivatives
    derivatives.argtypes, derivatives.restype = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t], ctypes.c_int
    assert derivatives(cs.component, None, 0) == 3
    state = next(int(v.get("valueReference")) for v in description(fmu_path("mechanics", model_exchange=True)).iter()
                 if v.get("name") == "ode.x[1]")  # a Model Exchange value reference, not in the CS description
    assert me.getReal([state])[0] == me.getReal([state])[0]  # the ME instance answers it ...
    with pytest.raises(Exception):
        cs.getReal([state])  # ... the CS instance does not (FMI 2.0 section 2.1.2: a wrong reference is an error)
    log = capsys.readouterr().out
    assert "fmi2DoStep: this instance is Model Exchange" in log
    assert "fmi2GetDerivatives: this instance is Co-Simulation" in log
    me.terminate(), me.freeInstance(), cs.terminate(), cs.freeInstance()


@pytest.mark.parametrize("as_ok", [False, True])
def test_a_completed_step_returns_its_warning_as_a_step_does(as_ok, capsys):
    """A leg past its stroke: fmi2CompletedIntegratorStep logs it and returns fmi2Warning, as the
    Co-Simulation fmi2DoStep does, or fmi2OK with fmi.warnings_as_ok (the warning logged either way)."""
    fmu, vr = instantiated("mechanics", True)
    fmu.setupExperiment(startTime=0.0)
    fmu.setReal([vr["limit.leg_length_max"]], [1.6])  # the start pose's legs are longer: outside
    fmu.setBoolean([vr["fmi.warnings_as_ok"]], [as_ok])
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setTime(1e-3)
    completed = fmu.dll.fmi2CompletedIntegratorStep
    completed.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int)]
    completed.restype = ctypes.c_int
    event, terminate = ctypes.c_int(0), ctypes.c_int(0)
    assert completed(fmu.component, 1, ctypes.byref(event), ctypes.byref(terminate)) == (0 if as_ok else 1)
    assert "is outside the stroke" in capsys.readouterr().out
    fmu.terminate(), fmu.freeInstance()


def test_a_state_comes_back_in_the_mode_it_was_taken_in(capsys):
    """An FMU state taken in Continuous-Time Mode, set back after the instance went to Event Mode,
    restores Continuous-Time Mode with it (fmusim's --initial-fmu-state-file relies on it): states are
    set and an integrator step completed at once, as before the state was taken."""
    fmu, _ = instantiated("mechanics", True)
    x = np.zeros(17)  # the mechanics' states (MODEL_N_STATES)
    pointer, n = x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(x)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.getContinuousStates(pointer, n)
    state = fmu.getFMUstate()
    fmu.enterEventMode()
    fmu.setFMUstate(state)
    fmu.setTime(1e-3)
    fmu.setContinuousStates(pointer, n)  # Continuous-Time Mode's calls, allowed at once
    fmu.completedIntegratorStep()
    fmu.enterEventMode()
    again = fmu.getFMUstate()  # and one taken in Event Mode comes back in Event Mode
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setFMUstate(again)
    fmu.newDiscreteStates()
    fmu.freeFMUstate(state), fmu.freeFMUstate(again)
    assert "not allowed" not in capsys.readouterr().out
    fmu.terminate(), fmu.freeInstance()


def test_each_mode_takes_the_calls_the_standard_allows_in_it(capsys):
    """FMI 2.0's Model Exchange state machine (section 3.2.3): after initialization an instance is
    in Event Mode, where states are not set and no integrator step is completed; in Continuous-Time
    Mode no discrete states are updated; the time is set in neither before initialization. Each
    call out of its mode is fmi2Error with its reason, and the instance goes on in its mode."""
    from fmpy.fmi1 import FMICallException
    fmu, _ = instantiated("cueing", True)
    x = np.zeros(27)
    pointer, n = x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(x)
    fmu.setupExperiment(startTime=0.0)
    with pytest.raises(FMICallException):
        fmu.setTime(0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.getContinuousStates(pointer, n)
    event_mode = [lambda: fmu.setContinuousStates(pointer, n), fmu.completedIntegratorStep]
    continuous_time_mode = [fmu.newDiscreteStates, fmu.enterContinuousTimeMode]
    for call in event_mode:
        with pytest.raises(FMICallException):
            call()
    fmu.enterEventMode()  # allowed in either mode
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    for call in continuous_time_mode:
        with pytest.raises(FMICallException):
            call()
    fmu.setTime(1e-3)
    fmu.setContinuousStates(pointer, n)
    fmu.completedIntegratorStep()
    fmu.enterEventMode()
    fmu.newDiscreteStates()
    log = capsys.readouterr().out
    assert "fmi2SetTime: illegal call sequence: not allowed in state 'instantiated'" in log
    assert "fmi2SetContinuousStates: not allowed in Event Mode (fmi2EnterContinuousTimeMode first)" in log
    assert "fmi2CompletedIntegratorStep: not allowed in Event Mode" in log
    assert "fmi2NewDiscreteStates: not allowed in Continuous-Time Mode (fmi2EnterEventMode first)" in log
    assert "fmi2EnterContinuousTimeMode: not allowed in Continuous-Time Mode" in log
    fmu.terminate(), fmu.freeInstance()


def test_the_switching_inverter_is_refused_with_its_reason(capsys):
    from fmpy.fmi1 import FMICallException
    drive, vrs = instantiated("pmsm_drive", True)
    drive.setupExperiment(startTime=0.0)
    drive.enterInitializationMode()
    drive.setInteger([vrs["inverter.model"]], [3])
    with pytest.raises(FMICallException):
        drive.exitInitializationMode()
    assert "inverter.model = 3 (switching) has the hysteresis comparators' events" in capsys.readouterr().out
    drive.freeInstance()


def test_the_cueings_guard_steps_as_model_exchange_as_its_co_simulation(tmp_path):
    """The cueing's guard as Model Exchange: its steps time events guard.period apart, the reference
    between them its motion carried from the last (its acceleration constant), as the Co-Simulation
    steps it at that communication step. A car braking at 8 m/s^2, strongly cued (the washout alone
    takes Meng's joints past 20 deg: tests/models/test_cueing.py): integrated by CVODE, the guard
    holds the same steps back by the same limit as the Co-Simulation at 1 ms, the reference within
    1e-6 of its range of it, and the joints within their 20 deg at every millisecond."""
    from cosim.platform.core import Core
    t = np.arange(0.0, 3.0 + 1e-9, 0.01)
    braking = -8.0 * np.clip((t - 0.5) / 0.15, 0.0, 1.0)
    motion = np.column_stack([t, braking, 0 * t, np.full_like(t, 9.80665), 0 * t, 0 * t, 0 * t])
    np.savetxt(tmp_path / "braking.csv", motion, delimiter=",", comments="", fmt="%.10g",
               header="time," + ",".join(f"specific_force.{a}" for a in "xyz") + "," +
               ",".join(f"angular_rate.{a}" for a in "xyz"))
    values = {"vehicle.file": str(tmp_path / "braking.csv"), "translation.x.gain": 1.0, "translation.x.limit": 10.0,
              "translation.x.frequency": 1.0, "tilt.gain": 1.0, "tilt.rate_limit": 0.3, "guard": True,
              "guard.period": 1e-3}
    held = [f"guard.held.{kind}" for kind in ("stroke", "joint", "leg_velocity", "leg_acceleration", "return")]
    me = simulate_fmu(str(fmu_path("cueing", model_exchange=True)), fmi_type="ModelExchange", solver="CVode",
                      relative_tolerance=1e-10, stop_time=3.0, output_interval=1e-3, output=POSE_REF + held,
                      start_values=values)
    cs = simulate_fmu(str(fmu_path("cueing")), stop_time=3.0, step_size=1e-3, output_interval=1e-3,
                      output=POSE_REF + held, start_values=values)
    assert me["guard.held.joint"][-1] > 1000
    for name in held:
        assert me[name][-1] == cs[name][-1], name
    for name in POSE_REF:
        assert np.abs(np.interp(cs["time"], me["time"], me[name]) - cs[name]).max() <= 1e-6 * (np.ptp(cs[name]) + 1e-3)
    kinematics = Core().pose_kinematics(np.column_stack([me[name] for name in POSE_REF]))
    assert np.maximum(kinematics["lower_angle"], kinematics["upper_angle"]).max() <= np.radians(20.0) + 1e-12


def events(fmu, times: tuple[float, ...]) -> list[bool]:
    """valuesOfContinuousStatesChanged of the FMU's event at each time (time moved on there)."""
    changed = []
    for t in times:
        fmu.setTime(t)
        fmu.enterEventMode()
        changed.append(bool(fmu.newDiscreteStates()[3]))
        fmu.enterContinuousTimeMode()
    return changed


def test_an_event_that_changes_nothing_lets_the_solver_step_on():
    """A time event reports valuesOfContinuousStatesChanged where it changes the right-hand side, so
    that an importer's solver restarts there, and not where it changes nothing, so that it steps on:
    the cueing's guard passing the car drive's motion on (its 1 ms steps) changes nothing, its first
    step and the vehicle table's 10 ms corners do; a load pulse's edges change the trajectory's
    wrench, another time does not."""
    cueing, vrs = instantiated("cueing", True)
    cueing.setupExperiment(startTime=0.0)
    cueing.enterInitializationMode()
    cueing.setString([vrs["vehicle.file"]], [DRIVE])
    cueing.setBoolean([vrs["guard"]], [True])
    cueing.exitInitializationMode()
    cueing.newDiscreteStates()
    cueing.enterContinuousTimeMode()
    assert events(cueing, (0.001, 0.002, 0.003, 0.01, 0.011, 0.0115)) == [True, False, False, True, False, False]
    cueing.terminate()
    cueing.freeInstance()
    trajectory, vrs = instantiated("trajectory", True)
    trajectory.setupExperiment(startTime=0.0)
    trajectory.enterInitializationMode()
    names = [f"load.force.z.pulse[1].{key}" for key in ("value", "start", "end")]
    trajectory.setReal([vrs[n] for n in names], [100.0, 0.5, 0.7])
    trajectory.exitInitializationMode()
    trajectory.newDiscreteStates()
    trajectory.enterContinuousTimeMode()
    assert events(trajectory, (0.3, 0.5, 0.6, 0.7, 0.8)) == [False, True, False, True, False]
    trajectory.terminate()
    trajectory.freeInstance()


POSE_REF = [f"pose_ref.{dof}" for dof in ("x", "y", "z", "roll", "pitch", "yaw")]
TILT_RATE = float(np.radians(3.0))  # the tilt's rate limit these tests state (the default has a margin below it)
POSE_REF_RATE = [f"pose_ref_rate.{dof}" for dof in ("x", "y", "z", "roll", "pitch", "yaw")]


def cueing_runs(algorithm: int, stop: float, steps: tuple[float, ...], outputs: list[str],
                relative_tolerance: float = 1e-10, extra: dict | None = None):
    """The cueing on the car drive (the MPC reading it 3 s ahead; the tilt's rate limit 3 deg/s, as
    the bounds below were measured with): Model Exchange by CVODE (at `relative_tolerance`, its
    absolute tolerance that times each state's nominal, as fmpy sets it), and Co-Simulation at each
    communication step; each output on 1001 points, and its range in the Co-Simulation run (`extra`:
    more start values)."""
    values = {"vehicle.file": DRIVE, "algorithm": algorithm, "tilt.rate_limit": TILT_RATE,
              **({"mpc.preview": 3.0} if algorithm == 2 else {}), **(extra or {})}
    grid = np.linspace(0.0, stop, 1001)
    me = simulate_fmu(str(fmu_path("cueing", model_exchange=True)), fmi_type="ModelExchange", solver="CVode",
                      relative_tolerance=relative_tolerance, stop_time=stop, output_interval=stop / 1000,
                      output=outputs, start_values=values)
    runs = [simulate_fmu(str(fmu_path("cueing")), stop_time=stop, step_size=h, output_interval=h, output=outputs,
                         start_values=values) for h in steps]
    on_grid = lambda run, o: np.interp(grid, run["time"], run[o])  # noqa: E731
    return ({o: on_grid(me, o) for o in outputs}, [{o: on_grid(run, o) for o in outputs} for run in runs],
            {o: np.ptp(runs[-1][o]) for o in outputs})


@pytest.mark.parametrize("extra", [{}, {"tilt.pitch_rate_limit": float(np.radians(4.0))}],
                         ids=["the tilt vector's limit", "pitch's own limit"])
def test_the_washout_is_what_its_exact_steps_converge_to(extra):
    """The classical washout through the car drive's braking and lane change (20 s): its filters
    stepped exactly by Co-Simulation agree with CVODE on the same equations to 1e-7 of each
    channel's range at any step; the tilt's rate limit (the tilt vector's, or with pitch's own their
    ellipse) acts once a step in Co-Simulation and
    continuously in Model Exchange, so the rolled and pitched pose comes closer as the step shrinks
    from 1 to 0.1 ms, to within 1e-4 of its range, and the rates (which reverse at the limit within
    a step) within 1e-3 of theirs on average (fixed numerics stated here)."""
    outputs = POSE_REF + POSE_REF_RATE
    me, (coarse, fine), scale = cueing_runs(1, 20.0, (1e-3, 1e-4), outputs, extra=extra)
    for o in ("pose_ref.x", "pose_ref.y", "pose_ref.yaw", "pose_ref_rate.x", "pose_ref_rate.y", "pose_ref_rate.yaw"):
        assert np.abs(me[o] - coarse[o]).max() < 1e-7 * scale[o], o
    for o in ("pose_ref.roll", "pose_ref.pitch"):
        errors = [np.abs(me[o] - run[o]).max() / scale[o] for run in (coarse, fine)]
        assert errors[1] < errors[0] and errors[1] < 1e-4, (o, errors)
    for o in ("pose_ref_rate.roll", "pose_ref_rate.pitch"):
        assert np.abs(me[o] - fine[o]).mean() < 1e-3 * scale[o], o


@pytest.mark.parametrize("relative_tolerance, bound", [(1e-10, 1e-6), (1e-6, 1e-3)])
def test_the_mpc_is_what_its_co_simulation_gives(relative_tolerance, bound):
    """The MPC cueing through the car drive's braking (5 s, 250 solves): its solves time events of
    the Model Exchange FMU, its motion and perception integrated by CVODE between them, give the
    Co-Simulation's exact steps at 1 ms (the same to 1e-14 at 0.25 ms) to 1e-6 of each output's
    range at rtol 1e-10 (measured 8e-8), and to 1e-3 at fmpy's everyday 1e-6 (measured 3e-4), the
    perceived errors included: the canals' states are far smaller than 1 (their output weighs the
    fastest by about 2200), and the FMU gives each organ state's nominal (mpc_state_nominals) so that
    the solver's absolute tolerance is theirs (with nominals of 1 the perceived angular-rate errors
    were up to 4e-5 of their range off at rtol 1e-10, and the pitch channel's 1.6e-2 at 1e-6)."""
    rates = [f"mpc.perceived_error.angular_rate.{a}" for a in "xyz"]
    outputs = POSE_REF + POSE_REF_RATE + [f"mpc.perceived_error.specific_force.{a}" for a in "xyz"] + rates
    me, (cs,), scale = cueing_runs(2, 5.0, (1e-3,), outputs, relative_tolerance)
    for o in outputs:
        assert np.abs(me[o] - cs[o]).max() < bound * scale[o], o


def test_the_mpc_states_nominals_are_the_organs_scale():
    """fmi2GetNominalsOfContinuousStates of the MPC: 1 for the platform's motion (12 states); for
    each organ state the size that moves the perceived error by 0.1 (m/s^2, rad/s), from 0.045 (the
    canals' fastest mode) down to 5e-5; the washout's all 1."""
    from fmpy import extract, instantiate_fmu, read_model_description
    path = str(fmu_path("cueing", model_exchange=True))
    description = read_model_description(path)
    unzipped = extract(path)
    nominals = {}
    for algorithm in (1, 2):
        fmu = instantiate_fmu(unzipped, description, fmi_type="ModelExchange")
        try:
            fmu.setupExperiment(startTime=0.0)
            vrs = {v.name: v.valueReference for v in description.modelVariables}
            fmu.setString([vrs["vehicle.file"]], [DRIVE])
            fmu.setInteger([vrs["algorithm"]], [algorithm])
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            x = np.zeros(description.numberOfContinuousStates)
            fmu.getNominalsOfContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(x))
            nominals[algorithm] = x
        finally:
            fmu.terminate()
            fmu.freeInstance()
    assert np.all(nominals[1] == 1.0)
    mpc = nominals[2]
    assert np.all(mpc[:12] == 1.0) and np.all(mpc[12:] < 1.0)
    assert 1e-5 < mpc[12:].min() < 1e-4


@pytest.mark.parametrize("algorithm", (1, 2))
def test_fmusims_cvode_follows_the_vehicles_table_through_its_corners(algorithm, tmp_path):
    """Reference-FMUs' fmusim (CVODE, no maximum step, restarted only where an event says the states
    changed) on the cueing through the car drive's first 8 s (cruise, braking, lane change; the MPC
    reading it 3 s ahead): the
    table's rows (the corners of its linear interpolation) and the MPC's solves are time events after
    which the solver restarts, so at fmusim's relative tolerance 1e-6 the reference pose is the
    Co-Simulation's at 1 ms to 1e-3 of each channel's range (before, CVODE stepped on past the
    braking at the zero of the cruise: 71 % of pose_ref.x's range off, with no error)."""
    import subprocess
    from peers import fmusim
    stop, out = 8.0, tmp_path / "fmusim.csv"
    done = subprocess.run([str(fmusim()), "--interface-type", "me", "--solver", "cvode", "--tolerance", "1e-6",
                           "--stop-time", repr(stop), "--output-interval", "0.01", "--start-value", "vehicle.file",
                           DRIVE, "--start-value", "algorithm", str(algorithm), "--start-value", "mpc.preview", "3",
                           "--start-value", "tilt.rate_limit", repr(TILT_RATE), "--output-file", str(out),
                           str(fmu_path("cueing", model_exchange=True))], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    me = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    cs = simulate_fmu(str(fmu_path("cueing")), stop_time=stop, step_size=1e-3, output_interval=1e-3,
                      output=POSE_REF, start_values={"vehicle.file": DRIVE, "algorithm": algorithm, "mpc.preview": 3.0,
                                                     "tilt.rate_limit": TILT_RATE})
    for o in POSE_REF:
        scale = np.ptp(cs[o])
        if scale > 0:
            assert np.abs(me[o] - np.interp(me["time"], cs["time"], cs[o])).max() < 1e-3 * scale, o
    assert np.ptp(me["pose_ref.x"]) > 0.1  # the braking's surge is there
