"""FMUs under hostile use (issue 14): every finding of the random call-sequence runs is a test here.
Each call returns within a bounded time (an alarm turns a hang into a failure), refuses what the
FMI 2.0 standard does not allow with fmi2Error and a log line, and leaves the instance usable."""

from __future__ import annotations

import ctypes
import signal
import sys
from contextlib import contextmanager

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from cosim.engine.artifacts import fmu_path
from shipped import MODELS
from cosim.engine.fmi import FmuError, FmuInstance

FMUS = list(MODELS)


@contextmanager
def within(seconds: int):
    """Fails the test instead of hanging when the block takes longer than `seconds`."""
    def alarm(signum, frame):
        raise TimeoutError(f"took longer than {seconds} s")
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@pytest.fixture
def make():
    made = []

    def instance(name: str, start=None, initialize=True, **setup) -> FmuInstance:
        fmu = FmuInstance(fmu_path(name), f"{name}_{len(made)}")
        made.append(fmu)
        if initialize:
            fmu.initialize(start or {})
        return fmu

    yield instance
    for fmu in made:
        fmu.free()


def errors(fmu: FmuInstance) -> list[str]:
    return [m.text for m in fmu.messages if m.status == "error"]


# -- bounded work -------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["pmsm_drive", "mechanics", "linear_motor"])
@pytest.mark.parametrize("h", [1e308, 1e4])
def test_a_huge_communication_step_is_refused_not_run(make, name, h):
    """h = 1e308 once overflowed the internal step count and never returned; 1e4 s at 0.1 ms would
    be 10^8 RK4 steps. Both are refused at once: the work of one DoStep is capped at 2 x 10^5
    internal steps."""
    fmu = make(name)
    raw = fmu.fmu
    with within(10), pytest.raises(FMICallException):
        raw.fmi2DoStep(raw.component, 0.0, h, 0)
    assert any("more than 200000 internal steps" in e for e in errors(fmu)), errors(fmu)


@pytest.mark.parametrize("name,parameter,value", [("pmsm_drive", "solver.step", 1e-9),
                                                  ("mechanics", "solver.step", 1e-9),
                                                  ("pmsm_drive", "inverter.hysteresis_band", 1e-6),
                                                  ("pmsm_drive", "inverter.max_step", 1e-9)])
def test_step_sizes_that_would_take_minutes_are_outside_their_bounds(make, name, parameter, value):
    fmu = make(name, initialize=False)
    with pytest.raises(FmuError, match=f"'{parameter}' = .* rejected: outside"):
        fmu.set({parameter: value})


@pytest.mark.parametrize("path,reason", [("/dev/zero", "is not a regular file"), ("/dev/urandom", "is not a regular file"),
                                         ("/", "is not a regular file")])
def test_a_table_that_is_no_file_is_refused_at_once(make, path, reason):
    fmu = make("trajectory", initialize=False)
    with within(10), pytest.raises(FmuError, match=reason):
        fmu.initialize({"table.file": path})


# -- states that are not trusted ----------------------------------------------------------------

@pytest.mark.parametrize("name", FMUS)
def test_altered_state_bytes_are_refused(make, name):
    """A serialized state with a valid header and an altered payload (one byte in the middle) is
    refused; so is a state of a different FMU handed to SetFMUstate (a smaller snapshot: never
    copied whole)."""
    fmu = make(name)
    state = fmu.get_state()
    data = bytearray(fmu.serialize_state(state))
    data[len(data) // 2] ^= 0x40
    with pytest.raises(FmuError, match="altered"):
        fmu.deserialize_state(bytes(data), 0.0)
    other = make("trajectory" if name != "trajectory" else "linear_motor")
    foreign = other.get_state()
    with pytest.raises(FmuError, match="not a state of this build"):
        fmu.set_state(foreign)
    other.free_state(foreign)
    fmu.free_state(state)
    fmu.do_step(1e-3)  # the instance is still usable


@pytest.mark.parametrize("name", FMUS)
def test_every_byte_of_the_state_that_is_read_back_is_checked(make, name):
    """The tag's outputs_stale flag (bytes 32-35) is inside the checksum: one bit flipped there
    was accepted before, and fmi2GetReal right after fmi2SetFMUstate then returned the outputs of
    before the last fmi2SetReal instead of those at fmi2GetFMUstate."""
    fmu = make(name)
    state = fmu.get_state()
    data = bytes(fmu.serialize_state(state))
    for offset in range(32, 36):
        for bit in range(8):
            flipped = bytearray(data)
            flipped[offset] ^= 1 << bit
            with pytest.raises(FmuError, match="altered"):
                fmu.deserialize_state(bytes(flipped), 0.0)
    fmu.free_state(state)
    fmu.do_step(1e-3)


def test_a_restored_snapshot_is_validated(make):
    """A snapshot whose checksum matches but whose values break the variable table (as memory
    corruption or a hand-made state would) is refused and leaves the instance as it was."""
    fmu = make("pmsm_drive")
    state = fmu.get_state()
    size = ctypes.c_size_t()
    raw = fmu.fmu
    raw.fmi2SerializedFMUstateSize(raw.component, state[0], ctypes.byref(size))
    data = bytearray(fmu.serialize_state(state))
    # the layer's tag: magic (8), GUID hash, size, checksum (3 x 8), outputs_stale (4, padded to 8)
    tag = 8 + 3 * 8 + 8
    import struct
    snapshot = bytearray(data[tag:])
    time_offset = 8  # after the phase (int, padded): the communication point
    snapshot[time_offset:time_offset + 8] = struct.pack("<d", float("nan"))
    checksum = 1469598103934665603
    for byte in bytes(snapshot) + bytes(data[32:36]):  # the snapshot, then the outputs_stale flag
        checksum = ((checksum ^ byte) * 1099511628211) % 2 ** 64
    data[8 + 16:8 + 24] = struct.pack("<Q", checksum)
    data[tag:] = snapshot
    bad = fmu.deserialize_state(bytes(data), 0.0)
    with pytest.raises(FmuError, match="time is not finite"):
        fmu.set_state(bad)
    fmu.do_step(1e-3)
    assert np.isfinite(fmu.get("torque"))


def test_a_state_restored_into_a_fresh_trajectory_brings_its_table(make, tmp_path):
    """The table is model data outside the snapshot; restoring a state into a fresh instance
    (which never read the table) reloads it, so the outputs are the original's."""
    path = tmp_path / "heave.csv"
    t = np.linspace(0.0, 1.0, 101)
    np.savetxt(path, np.c_[t, 0.1 * np.sin(6 * t)], delimiter=",", header="time,z", comments="")
    first = make("trajectory", {"table.file": str(path), "z.offset": 0.0})
    for _ in range(300):
        first.do_step(1e-3)
    state = first.get_state()
    data = first.serialize_state(state)
    fresh = make("trajectory")
    restored = fresh.deserialize_state(data, first.time)
    fresh.set_state(restored)
    assert fresh.get("pose_ref.z") == first.get("pose_ref.z") != 0.0
    fresh.do_step(1e-3)
    first.do_step(1e-3)
    assert fresh.get("pose_ref.z") == first.get("pose_ref.z")


def test_outputs_right_after_set_state_equal_those_at_get_state(make):
    """With input derivatives given before the step, the outputs at the step's end use them; a
    state taken then and restored later gives the same outputs, not ones recomputed without."""
    drive = make("pmsm_drive")
    inputs = drive.real_group(["angle_ref", "angle", "speed"])
    inputs.write([1.0, 0.0, 0.0])
    inputs.write_derivatives([50.0, 0.0, 30.0], 1)
    drive.do_step(1e-3)
    outputs = drive.real_group(["torque", "current.q", "speed_ref"])
    at_get = outputs.read().copy()
    state = drive.get_state()
    drive.do_step(1e-3)
    drive.set_state(state)
    assert np.array_equal(outputs.read(), at_get)


# -- NULL pointers ------------------------------------------------------------------------------

def test_null_out_pointers_are_errors_not_crashes(make):
    drive = make("pmsm_drive")
    raw, c = drive.fmu, drive.fmu.component
    lib = raw.dll
    lib.fmi2SetRealInputDerivatives.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p,
                                                ctypes.c_void_p]
    lib.fmi2SetDebugLogging.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t, ctypes.c_void_p]
    lib.fmi2SerializedFMUstateSize.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.fmi2GetRealStatus.argtypes = lib.fmi2GetBooleanStatus.argtypes = [ctypes.c_void_p, ctypes.c_int,
                                                                          ctypes.c_void_p]
    assert lib.fmi2SetRealInputDerivatives(c, None, 2, None, None) == 3
    assert lib.fmi2SetDebugLogging(c, 1, 2, None) == 3
    assert lib.fmi2SerializedFMUstateSize(c, None, None) == 3
    assert lib.fmi2GetRealStatus(c, 2, None) == 3
    assert lib.fmi2GetBooleanStatus(c, 3, None) == 3
    drive.do_step(1e-3)  # still usable
    assert len(errors(drive)) == 5


# -- silent non-finite results ------------------------------------------------------------------

def test_finite_but_huge_inputs_give_an_error_not_nan(make):
    drive = make("pmsm_drive")
    drive.set({"speed": sys.float_info.max})
    with pytest.raises(FmuError, match="output '.*' is not finite"):
        drive.real_group(["torque"]).read()


def test_a_parameter_that_makes_the_outputs_non_finite_fails_initialization(make):
    trajectory = make("trajectory", initialize=False)
    with pytest.raises(FmuError, match="fmi2ExitInitializationMode: output 'pose_ref.x' is not finite"):
        trajectory.initialize({"x.sine[1].amplitude": 1e308, "x.sine[1].frequency": 1e308, "x.sine[1].phase": 1.0})


# -- calls the standard does not allow -----------------------------------------------------------

def test_get_before_initialization_is_refused(make):
    drive = make("pmsm_drive", initialize=False)
    with pytest.raises(FmuError, match="fmi2GetReal: illegal call sequence: not allowed in state 'instantiated'"):
        drive.get("torque")


@pytest.mark.parametrize("tolerance", [float("nan"), 0.0, -1e-6])
def test_a_bad_tolerance_is_refused(make, tolerance):
    drive = make("pmsm_drive", initialize=False)
    with pytest.raises(FMICallException):
        drive.fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
    assert any("tolerance" in e for e in errors(drive))


def test_a_step_past_the_stop_time_is_refused(make):
    drive = make("pmsm_drive", initialize=False)
    drive.fmu.setupExperiment(startTime=0.0, stopTime=0.002)
    drive.fmu.enterInitializationMode()
    drive.fmu.exitInitializationMode()
    raw = drive.fmu
    assert raw.fmi2DoStep(raw.component, 0.0, 1e-3, 0) == 0
    assert raw.fmi2DoStep(raw.component, 1e-3, 1e-3, 0) == 0
    with pytest.raises(FMICallException):
        raw.fmi2DoStep(raw.component, 2e-3, 1e-3, 0)
    assert any("passes the stop time 0.002 s" in e for e in errors(drive))


def test_status_is_refused_in_the_error_state(make):
    """A failed ExitInitializationMode (non-finite outputs) leaves the instance in the error state,
    where FMI 2.0 allows no status query."""
    trajectory = make("trajectory", initialize=False)
    with pytest.raises(FmuError):
        trajectory.initialize({"x.sine[1].amplitude": 1e308, "x.sine[1].frequency": 1e308, "x.sine[1].phase": 1.0})
    raw = trajectory.fmu
    raw.dll.fmi2GetRealStatus.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p]
    value = ctypes.c_double()
    assert raw.dll.fmi2GetRealStatus(raw.component, 2, ctypes.byref(value)) == 3
    assert any("fmi2GetRealStatus: illegal call sequence: not allowed in state 'error'" in e for e in errors(trajectory))
