"""The shared FMI layer through pmsm_drive: FMU state round trips, bad input, call sequence."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.engine.fmi import FmuError

OUTPUTS = ["torque", "current.d", "current.q", "voltage.d", "voltage.q", "power.electrical",
           "energy.electrical", "current.a", "speed_ref"]


def drive_inputs(k: int) -> list[float]:
    """A deterministic, varying duty for step k: angle_ref, angle, speed."""
    t = 1e-3 * k
    return [3.0 * np.sin(9.0 * t), 2.5 * np.sin(9.0 * t - 0.2), 22.5 * np.cos(9.0 * t - 0.2)]


def run_steps(drive, first: int, count: int, step: float = 1e-3) -> np.ndarray:
    inputs, outputs = drive.real_group(["angle_ref", "angle", "speed"]), drive.real_group(OUTPUTS)
    rows = []
    for k in range(first, first + count):
        inputs.write(drive_inputs(k))
        drive.do_step(step)
        rows.append(outputs.read().copy())
    return np.array(rows)


SETTINGS = [
    {"inverter.model": 2},
    {"inverter.model": 2, "solver.method": 1, "solver.step": 1e-4},
    {"inverter.model": 3},
]
IDS = ["averaged-dopri", "averaged-rk4", "switching"]


@pytest.mark.parametrize("settings", SETTINGS, ids=IDS)
def test_get_set_state_continues_bit_identically(make_drive, settings):
    drive = make_drive(settings)
    run_steps(drive, 0, 30)
    state = drive.get_state()
    first = run_steps(drive, 30, 30)
    drive.set_state(state)
    again = run_steps(drive, 30, 30)
    drive.free_state(state)
    assert np.array_equal(first, again)


@pytest.mark.parametrize("settings", SETTINGS, ids=IDS)
def test_serialized_state_restores_in_another_instance(make_drive, settings):
    drive = make_drive(settings, name="original")
    run_steps(drive, 0, 30)
    state = drive.get_state()
    data = drive.serialize_state(state)
    drive.free_state(state)
    first = run_steps(drive, 30, 30)

    other = make_drive(settings, name="restored")
    restored = other.deserialize_state(data, time=0.03)
    other.set_state(restored)
    other.free_state(restored)
    assert np.array_equal(first, run_steps(other, 30, 30))


def logged(drive) -> str:
    return " | ".join(m.text for m in drive.messages)


@pytest.mark.parametrize("name,value", [
    ("motor.resistance", 0.0), ("motor.inductance_q", 0.0), ("motor.inductance_d", 0.0),
    ("limit.current", 0.0), ("motor.torque_constant", 0.0),
])
def test_non_positive_parameter_is_refused_when_set(make_drive, name, value):
    """"> 0" is the variable table's (its min, FMU_POSITIVE), so the value is refused where any
    out-of-bounds value is: by fmi2SetReal, before initialization, naming it."""
    drive = make_drive(initialize=False)
    with pytest.raises(FmuError) as error:
        drive.initialize({name: value})
    assert "fmi2SetReal" in str(error.value)
    assert f"'{name}' = 0" in str(error.value) and "must be > 0" in str(error.value)


@pytest.mark.parametrize("name,value", [
    ("motor.resistance", -0.7), ("motor.inductance_q", -1e-3), ("limit.current", -42.0),
    ("limit.speed", -600.0), ("limit.voltage", -1.0), ("inverter.model", 4), ("solver.rtol", 0.0),
])
def test_out_of_range_parameter_is_rejected_when_set(make_drive, name, value):
    drive = make_drive(initialize=False)
    with pytest.raises(FmuError) as error:
        drive.set({name: value})
    assert f"'{name}'" in str(error.value) and "outside" in str(error.value)
    drive._call("fmi2SetupExperiment", drive.fmu.setupExperiment, startTime=0.0)
    drive._call("fmi2EnterInitializationMode", drive.fmu.enterInitializationMode)  # values readable from here
    assert drive.get(name) == float(drive.variables[name].start)  # nothing was changed


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("name", ["speed", "angle", "angle_ref", "torque_ff"])
def test_non_finite_input_is_rejected_and_loses_nothing(make_drive, name, value):
    drive = make_drive()
    run_steps(drive, 0, 5)
    before = drive.get(name)
    with pytest.raises(FmuError) as error:
        drive.set({name: value})
    assert f"'{name}'" in str(error.value) and "not a finite number" in str(error.value)
    assert drive.get(name) == before
    drive.do_step(1e-3)  # the instance goes on
    assert np.isfinite(drive.get("torque"))


def test_fixed_parameter_cannot_change_after_initialization(make_drive):
    drive = make_drive()
    with pytest.raises(FmuError) as error:
        drive.set({"motor.resistance": 1.0})
    assert "fixed parameter" in str(error.value) and "'motor.resistance'" in str(error.value)


def test_tunable_parameter_change_is_validated_and_undone_when_invalid(make_drive):
    drive = make_drive()
    drive.set({"control.speed_kp": 5.0})
    assert drive.get("control.speed_kp") == 5.0
    with pytest.raises(FmuError) as error:
        drive.set({"limit.current": 0.0})
    assert "'limit.current'" in str(error.value)
    assert drive.get("limit.current") == 42.0


def test_outputs_cannot_be_set(make_drive):
    drive = make_drive()
    with pytest.raises(FmuError) as error:
        drive.set({"torque": 1.0})
    assert "'torque' is an output" in str(error.value)


def test_calls_in_the_wrong_state_are_errors(make_drive):
    drive = make_drive(initialize=False)
    with pytest.raises(FmuError) as error:
        drive.do_step(1e-3)
    assert "fmi2DoStep: illegal call sequence" in str(error.value)
    drive.initialize()
    with pytest.raises(FmuError) as error:
        drive._call("fmi2EnterInitializationMode", drive.fmu.enterInitializationMode)
    assert "illegal call sequence" in str(error.value)
    drive.terminate()
    with pytest.raises(FmuError) as error:
        drive.do_step(1e-3)
    assert "state 'terminated'" in str(error.value)


def test_step_from_the_wrong_time_is_an_error(make_drive):
    drive = make_drive()
    drive.time = 0.5  # the master thinks it is elsewhere
    with pytest.raises(FmuError) as error:
        drive.do_step(1e-3)
    assert "communication point" in str(error.value)


def test_foreign_bytes_do_not_deserialize(make_drive):
    drive = make_drive()
    state = drive.get_state()
    data = bytearray(drive.serialize_state(state))
    data[0:4] = b"JUNK"
    with pytest.raises(FmuError) as error:
        drive.deserialize_state(bytes(data), 0.0)
    assert "not a state of this build" in str(error.value)
    with pytest.raises(FmuError):
        drive.deserialize_state(bytes(data[:100]), 0.0)


def test_diverging_solver_fails_the_step_and_keeps_the_last_good_state(make_drive):
    """RK4 at 1 ms on the averaged inverter (tau_v = 0.1 ms) is far outside its stability region
    (h |lambda| <= 2.8): the states blow up within a few dozen steps. The step that produces a
    non-finite value fails with fmi2Error naming the time, and the instance keeps the values of the
    last good communication point."""
    drive = make_drive({"inverter.model": 2, "solver.method": 1, "solver.step": 1e-3, "control.mode": 3})
    drive.set({"torque_ff": 10.0})
    last_good = None
    with pytest.raises(FmuError) as error:
        for _ in range(1000):
            drive.do_step(1e-3)
            last_good = (drive.time, drive.get("current.q"))
    assert "fmi2DoStep" in str(error.value) and "t = " in str(error.value)
    assert last_good is not None
    assert np.isfinite(drive.get("current.q"))
    assert drive.get("current.q") == last_good[1]


def test_warnings_follow_logging_on_and_make_do_step_return_warning():
    """FMI 2.0 logging: with loggingOn false and no category enabled the FMU reports errors and
    the warnings a call returns (their reason, as FMI 3.0 requires and FMI 2.0 permits), and with
    logStatusWarning enabled the same. A DoStep that raised a warning returns fmi2Warning (1)
    either way; the next quiet step returns fmi2OK again."""
    from cosim.engine.fmi import FmuInstance
    from cosim.engine.artifacts import fmu_path
    statuses, counts = {}, {}
    for warnings in (False, True):
        mechanics = FmuInstance(fmu_path("mechanics"), "mechanics", warnings=warnings)
        try:
            mechanics.initialize({"limit.leg_length_max": 1.85})  # every leg (1.86 m) is past the stroke
            raw = mechanics.fmu
            statuses[warnings] = raw.fmi2DoStep(raw.component, 0.0, 1e-3, 0)
            delivered = [m for m in mechanics.messages if m.status == "warning"]
            assert delivered and "outside the stroke" in delivered[0].text, delivered
            counts[warnings] = len(delivered)
        finally:
            mechanics.free()
    assert statuses == {False: 1, True: 1} and counts[False] == counts[True]
    mechanics = FmuInstance(fmu_path("mechanics"), "mechanics")
    try:
        mechanics.initialize()
        raw = mechanics.fmu
        assert raw.fmi2DoStep(raw.component, 0.0, 1e-3, 0) == 0
        mechanics.time = 1e-3
        raw.fmi2SetDebugLogging(raw.component, 0, 0, None)  # all debug logging off: errors still come
        from fmpy.fmi1 import FMICallException
        with pytest.raises(FMICallException, match="status 3"):
            raw.fmi2DoStep(raw.component, 1e-3, -1.0, 0)
        assert any(m.status == "error" and "step size" in m.text for m in mechanics.messages)
    finally:
        mechanics.free()
