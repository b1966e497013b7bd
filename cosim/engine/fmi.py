"""One FMI 2.0 co-simulation instance, driven through fmpy, with names resolved once.

`FmuInstance` wraps fmpy's FMU2Slave: it resolves variable names to value references, keeps the
FMU's log lines, and turns a failed FMI call into an `FmuError` that names the instance, the call,
the simulation time and what the FMU logged. `RealGroup` is a preallocated set of real variables
read or written in one FMI call, so a stepping loop makes no per-step allocations.
"""

from __future__ import annotations

import atexit
import ctypes
import shutil
import time as clock
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np
from fmpy import extract, read_model_description

from .interrupts import callback
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Integer,
    fmi2Real,
    fmi2ValueReference,
)

_STATUS = ["ok", "warning", "discard", "error", "fatal", "pending"]
_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]


@dataclass(frozen=True)
class LogMessage:
    status: str
    category: str
    text: str
    time: float = float("nan")  # the instance's time when it logged [s]


class FmuError(RuntimeError):
    """A failed FMI call, with the instance, call, time and the FMU's own log lines."""

    def __init__(self, instance: str, call: str, time: float, messages: Sequence[LogMessage]):
        self.instance, self.call, self.time = instance, call, time
        self.messages = list(messages)
        detail = "; ".join(m.text for m in self.messages) or "the FMU logged no reason"
        super().__init__(f"{instance}: {call} failed at t = {time:.9g} s: {detail}")


_LOADED: dict[tuple[str, int, int], tuple[object, Path]] = {}


def loaded(fmu_path: str | Path) -> tuple[object, Path]:
    """The FMU's model description and its extraction, read once per process for each version of
    the file (path, size, modification time): a run, or a sweep's thousandth point on a worker,
    parses and unzips nothing. The extractions are removed when the process ends."""
    path = Path(fmu_path).resolve()
    status = path.stat()
    key = (str(path), status.st_size, status.st_mtime_ns)
    if key not in _LOADED:
        _LOADED[key] = (read_model_description(str(path)), Path(extract(str(path))))
    return _LOADED[key]


@atexit.register
def _remove_extractions() -> None:
    for _, folder in _LOADED.values():
        shutil.rmtree(folder, ignore_errors=True)


class FmuInstance:
    """An instantiated co-simulation FMU. `unzip_dir` gives an extraction of the FMU to use instead
    of the process's own (cosim.engine.fmi.loaded)."""

    def __init__(self, fmu_path: str | Path, instance_name: str, unzip_dir: str | Path | None = None,
                 logging_on: bool = False, warnings: bool = True):
        """logging_on: the FMU's debug logging (every category); warnings: at least its warnings
        (category logStatusWarning); errors are always reported."""
        self.path = Path(fmu_path)
        self.name = instance_name
        if unzip_dir:
            self.model_description, self.unzip_dir = read_model_description(str(self.path)), Path(unzip_dir)
        else:
            self.model_description, self.unzip_dir = loaded(self.path)
        self.variables = {v.name: v for v in self.model_description.modelVariables}
        self.messages: list[LogMessage] = []
        self.time = 0.0
        self.fmi_seconds = 0.0  # wall time spent inside FMI calls (for the master-overhead share)
        self._callbacks = fmi2CallbackFunctions()
        self._logger = fmi2CallbackLoggerTYPE(self._on_log)  # kept alive with the instance
        self._callbacks.logger = self._logger
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
        self.fmu = FMU2Slave(guid=self.model_description.guid, unzipDirectory=str(self.unzip_dir),
                             modelIdentifier=self.model_description.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self.clock = None  # a function giving the instance's time while a native loop runs it
        self._call("fmi2Instantiate", self.fmu.instantiate, callbacks=self._callbacks, loggingOn=logging_on)
        if warnings and not logging_on and "logStatusWarning" in self.log_categories:
            self._call("fmi2SetDebugLogging", self.fmu.setDebugLogging, True, ["logStatusWarning"])

    # -- plumbing --------------------------------------------------------------------------------

    @callback
    def _on_log(self, env, instance_name, status, category, message) -> None:
        self.messages.append(LogMessage(_STATUS[status] if 0 <= status < 6 else str(status),
                                        (category or b"").decode(), (message or b"").decode(),
                                        self.clock() if self.clock else self.time))

    def _call(self, call: str, function, *args, **kwargs):
        logged_before = len(self.messages)
        start = clock.perf_counter()
        try:
            return function(*args, **kwargs)
        except FMICallException as error:
            raise FmuError(self.name, call, self.time, self.messages[logged_before:]) from error
        except Exception as error:  # fmpy raises a bare Exception when instantiation fails
            if call == "fmi2Instantiate":
                raise FmuError(self.name, call, self.time, self.messages[logged_before:]) from error
            raise
        finally:
            self.fmi_seconds += clock.perf_counter() - start

    def vr(self, name: str) -> int:
        try:
            return self.variables[name].valueReference
        except KeyError:
            raise KeyError(f"{self.name}: no variable '{name}' in {self.path.name}") from None

    # -- values ----------------------------------------------------------------------------------

    def set(self, values: Mapping[str, float | int | bool]) -> None:
        """Sets variables by name, each with the FMI call of its type."""
        for name, value in values.items():
            kind = self.variables[name].type if name in self.variables else None
            vr = [self.vr(name)]
            if kind == "Real":
                self._call(f"fmi2SetReal({name})", self.fmu.setReal, vr, [float(value)])
            elif kind in ("Integer", "Enumeration"):
                self._call(f"fmi2SetInteger({name})", self.fmu.setInteger, vr, [int(value)])
            elif kind == "Boolean":
                self._call(f"fmi2SetBoolean({name})", self.fmu.setBoolean, vr, [bool(value)])
            elif kind == "String":
                self._call(f"fmi2SetString({name})", self.fmu.setString, vr, [str(value)])
            else:
                raise TypeError(f"{self.name}: cannot set '{name}' of type {kind}")

    @property
    def log_categories(self) -> list[str]:
        return [c.name if hasattr(c, "name") else str(c) for c in (self.model_description.logCategories or [])]

    @property
    def can_interpolate_inputs(self) -> bool:
        return bool(self.model_description.coSimulation.canInterpolateInputs)

    @property
    def max_output_derivative_order(self) -> int:
        return int(self.model_description.coSimulation.maxOutputDerivativeOrder or 0)

    def get(self, name: str) -> float | str:
        kind, vr = self.variables[name].type if name in self.variables else None, [self.vr(name)]
        if kind == "Real":
            return self._call(f"fmi2GetReal({name})", self.fmu.getReal, vr)[0]
        if kind in ("Integer", "Enumeration"):
            return self._call(f"fmi2GetInteger({name})", self.fmu.getInteger, vr)[0]
        if kind == "String":
            return self._call(f"fmi2GetString({name})", self.fmu.getString, vr)[0].decode()
        return self._call(f"fmi2GetBoolean({name})", self.fmu.getBoolean, vr)[0]

    def real_group(self, names: Sequence[str]) -> "RealGroup":
        return RealGroup(self, names)

    # -- life cycle ------------------------------------------------------------------------------

    def initialize(self, start_values: Mapping[str, float | int | bool] | None = None,
                   start_time: float = 0.0) -> None:
        self.time = start_time
        self._call("fmi2SetupExperiment", self.fmu.setupExperiment, startTime=start_time)
        if start_values:
            self.set(start_values)
        self._call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)
        self._call("fmi2ExitInitializationMode", self.fmu.exitInitializationMode)

    def do_step(self, step: float) -> None:
        self._call("fmi2DoStep", self.fmu.doStep, self.time, step)
        self.time += step

    def set_input_derivatives(self, names: Sequence[str], derivatives: Sequence[float], order: int = 1) -> None:
        self._call("fmi2SetRealInputDerivatives", self.fmu.setRealInputDerivatives,
                   [self.vr(n) for n in names], [order] * len(names), [float(d) for d in derivatives])

    def get_state(self):
        return self._call("fmi2GetFMUstate", self.fmu.getFMUstate), self.time

    def set_state(self, state) -> None:
        fmu_state, self.time = state
        self._call("fmi2SetFMUstate", self.fmu.setFMUstate, fmu_state)

    def free_state(self, state) -> None:
        self._call("fmi2FreeFMUstate", self.fmu.freeFMUstate, state[0])

    def serialize_state(self, state) -> bytes:
        return self._call("fmi2SerializeFMUstate", self.fmu.serializeFMUstate, state[0])

    def deserialize_state(self, data: bytes, time: float):
        return self._call("fmi2DeSerializeFMUstate", self.fmu.deSerializeFMUstate, data), time

    def terminate(self) -> None:
        self._call("fmi2Terminate", self.fmu.terminate)

    def free(self) -> None:
        self.fmu.freeInstance()


class RealGroup:
    """Real variables read or written together in one FMI call, into or from `values`."""

    def __init__(self, instance: FmuInstance, names: Sequence[str]):
        self.instance, self.names = instance, list(names)
        n = len(self.names)
        self._vr = (fmi2ValueReference * n)(*[instance.vr(name) for name in self.names])
        self.values = np.zeros(n)
        self._pointer = self.values.ctypes.data_as(ctypes.POINTER(fmi2Real))

    def read(self) -> np.ndarray:
        self.instance._call("fmi2GetReal", self.instance.fmu.fmi2GetReal, self.instance.fmu.component,
                            self._vr, len(self.names), self._pointer)
        return self.values

    def write(self, values: Iterable[float] | None = None) -> None:
        if values is not None:
            self.values[:] = values
        self.instance._call("fmi2SetReal", self.instance.fmu.fmi2SetReal, self.instance.fmu.component,
                            self._vr, len(self.names), self._pointer)

    def read_derivatives(self, order: int) -> np.ndarray:
        """fmi2GetRealOutputDerivatives of the given order for these (output) variables."""
        n = len(self.names)
        if not hasattr(self, "_read_orders"):
            self._read_orders = {k: (fmi2Integer * n)(*([k] * n)) for k in (1, 2)}
            self._rates = np.zeros(n)
            self._rates_pointer = self._rates.ctypes.data_as(ctypes.POINTER(fmi2Real))
        self.instance._call("fmi2GetRealOutputDerivatives", self.instance.fmu.fmi2GetRealOutputDerivatives,
                            self.instance.fmu.component, self._vr, n, self._read_orders[order], self._rates_pointer)
        return self._rates.copy()

    def write_derivatives(self, derivatives: Iterable[float], order: int = 1) -> None:
        """fmi2SetRealInputDerivatives of the given order for these (input) variables."""
        n = len(self.names)
        if not hasattr(self, "_derivatives"):
            self._derivatives = np.zeros(n)
            self._derivative_pointer = self._derivatives.ctypes.data_as(ctypes.POINTER(fmi2Real))
            self._orders = {k: (fmi2Integer * n)(*([k] * n)) for k in (1, 2)}
        self._derivatives[:] = derivatives
        self.instance._call("fmi2SetRealInputDerivatives", self.instance.fmu.fmi2SetRealInputDerivatives,
                            self.instance.fmu.component, self._vr, n, self._orders[order], self._derivative_pointer)
