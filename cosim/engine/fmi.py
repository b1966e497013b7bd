"""One FMI 2.0 or FMI 3.0 co-simulation instance, driven through fmpy, with names resolved once.

`FmuInstance` wraps fmpy's FMU2Slave (or FMU3Slave for an FMI 3.0 FMU, whose description is read
with FMI 2.0's type names, Real for Float64 and Integer for Int32, so that the rest of the engine
knows one kind of FMU; it takes no input derivatives and holds its inputs over a step): it resolves variable names to value references, keeps the
FMU's log lines, and turns a failed FMI call into an `FmuError` that names the instance, the call,
the simulation time and what the FMU logged. `RealGroup` is a preallocated set of real variables
read or written in one FMI call, so a stepping loop makes no per-step allocations.
"""

from __future__ import annotations

import atexit
import ctypes
import functools
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
    parses and unzips nothing. The extractions are removed when the process ends. An FMI 3.0
    description is read as the engine reads an FMI 2.0 one (fmi2_kinds)."""
    path = Path(fmu_path).resolve()
    status = path.stat()
    key = (str(path), status.st_size, status.st_mtime_ns)
    if key not in _LOADED:
        _LOADED[key] = (fmi2_kinds(read_model_description(str(path))), Path(extract(str(path), include=_runs)))
    return _LOADED[key]


def forget(fmu_path: str | Path) -> None:
    """The extractions `loaded` made of the FMU at fmu_path (every version of it) removed, and
    forgotten: for an FMU written for one run and gone after it (`cosim run --me`), so that a
    process running many such keeps none of them."""
    path = str(Path(fmu_path).resolve())
    for key in [key for key in _LOADED if key[0] == path]:
        shutil.rmtree(_LOADED.pop(key)[1], ignore_errors=True)


def _runs(member: str) -> bool:
    """Whether an archive member is one an instance can use here: everything but the sources, the
    documentation and other platforms' binaries (a third of an FMU's extraction time, whose binaries
    for other platforms and sources are most of its bytes)."""
    from fmpy import platform, platform_tuple
    top, _, rest = member.partition("/")
    if top in ("sources", "documentation"):
        return False
    return top != "binaries" or rest.split("/")[0] in ("", platform, platform_tuple)


_FMI3_KINDS = {"Float64": "Real", "Float32": "Real", **{k: "Integer" for k in (
    "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")}}


def fmi2_kinds(description):
    """An FMI 3.0 model description as the engine reads an FMI 2.0 one: each variable's type by its
    FMI 2.0 name (Float64 as Real, Int32 as Integer), the independent variable left out, no input
    derivatives (FMI 3.0 has none). An FMI 2.0 description as it is."""
    if not str(description.fmiVersion).startswith("3"):
        return description
    description.modelVariables = [v for v in description.modelVariables if v.causality != "independent"]
    for v in description.modelVariables:
        v.type = _FMI3_KINDS.get(v.type, v.type)
    description.coSimulation.canInterpolateInputs = False
    return description


_SIGNATURES: dict[type, list[tuple[str, list, list, object]]] = {}


class _SignaturesOnce:
    """fmpy's FMU classes read every FMI function's signature (inspect) for each instance, about
    3 ms each, eight times for a platform: read here once per class (the signatures are the
    class's, not the library's) and set on each instance's library functions."""

    def _loadFunctions(self) -> None:
        known = _SIGNATURES.get(type(self))
        if not known:  # the first instance, or an fmpy that keeps them otherwise (its own reading, every time)
            super()._loadFunctions()
            if type(self) not in _SIGNATURES:
                try:
                    _SIGNATURES[type(self)] = [(name, f.argnames, f.argtypes, f.restype)
                                               for name, f in self._functions.items()]
                except AttributeError:
                    _SIGNATURES[type(self)] = []
            return
        for name, argnames, argtypes, restype in known:
            function = getattr(self.dll, name)
            function.argnames, function.argtypes, function.restype = argnames, argtypes, restype
            self._functions[name] = function


class FMU2SlaveOnce(_SignaturesOnce, FMU2Slave):  # fmpy takes the FMI version from the class name's start
    pass


@functools.cache
def _slave3() -> type:
    from fmpy.fmi3 import FMU3Slave
    return type("FMU3SlaveOnce", (_SignaturesOnce, FMU3Slave), {})


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
        self.fmi3 = str(self.model_description.fmiVersion).startswith("3")
        if self.model_description.coSimulation is None:
            raise FmuError(instance_name, "instantiation", 0.0,
                           [LogMessage("error", "", f"{self.path.name}: this FMU is Model Exchange only (its "
                                       "modelDescription.xml): a co-simulation steps Co-Simulation FMUs", 0.0)])
        self.clock = None  # a function giving the instance's time while a native loop runs it
        if self.fmi3:
            self.fmu = _slave3()(guid=self.model_description.guid, unzipDirectory=str(self.unzip_dir),
                                 modelIdentifier=self.model_description.coSimulation.modelIdentifier,
                                 instanceName=instance_name)
            self._call("fmi3InstantiateCoSimulation", self.fmu.instantiate, loggingOn=logging_on,
                       logMessage=self._on_log3)
            if warnings and not logging_on and "logStatusWarning" in self.log_categories:
                self._call("fmi3SetDebugLogging", self.fmu.setDebugLogging, True, ["logStatusWarning"])
            return
        self._callbacks = fmi2CallbackFunctions()
        self._logger = fmi2CallbackLoggerTYPE(self._on_log)  # kept alive with the instance
        self._callbacks.logger = self._logger
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
        self.fmu = FMU2SlaveOnce(guid=self.model_description.guid, unzipDirectory=str(self.unzip_dir),
                             modelIdentifier=self.model_description.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self._call("fmi2Instantiate", self.fmu.instantiate, callbacks=self._callbacks, loggingOn=logging_on)
        if warnings and not logging_on and "logStatusWarning" in self.log_categories:
            self._call("fmi2SetDebugLogging", self.fmu.setDebugLogging, True, ["logStatusWarning"])

    # -- plumbing --------------------------------------------------------------------------------

    @callback
    def _on_log(self, env, instance_name, status, category, message) -> None:
        self.messages.append(LogMessage(_STATUS[status] if 0 <= status < 6 else str(status),
                                        (category or b"").decode(), (message or b"").decode(),
                                        self.clock() if self.clock else self.time))

    @callback
    def _on_log3(self, env, status, category, message) -> None:
        self._on_log(env, None, status, category, message)

    def _call(self, call: str, function, *args, **kwargs):
        logged_before = len(self.messages)
        start = clock.perf_counter()
        try:
            return function(*args, **kwargs)
        except FMICallException as error:
            raise FmuError(self.name, call, self.time, self.messages[logged_before:]) from error
        except Exception as error:  # fmpy raises a bare Exception when instantiation fails
            if call in ("fmi2Instantiate", "fmi3InstantiateCoSimulation"):
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
            three = self.fmi3
            if kind == "Real":
                self._call(f"{'fmi3SetFloat64' if three else 'fmi2SetReal'}({name})",
                           self.fmu.setFloat64 if three else self.fmu.setReal, vr, [float(value)])
            elif kind in ("Integer", "Enumeration"):
                self._call(f"{'fmi3SetInt32' if three else 'fmi2SetInteger'}({name})",
                           self.fmu.setInt32 if three else self.fmu.setInteger, vr, [int(value)])
            elif kind == "Boolean":
                self._call(f"fmi{3 if three else 2}SetBoolean({name})", self.fmu.setBoolean, vr, [bool(value)])
            elif kind == "String":
                self._call(f"fmi{3 if three else 2}SetString({name})", self.fmu.setString, vr, [str(value)])
            else:
                raise TypeError(f"{self.name}: cannot set '{name}' of type {kind}")

    @property
    def log_categories(self) -> list[str]:
        return [c.name if hasattr(c, "name") else str(c) for c in (self.model_description.logCategories or [])]

    @property
    def can_interpolate_inputs(self) -> bool:
        """Whether it takes its inputs' derivatives: FMI 2.0's canInterpolateInputs, or an FMI 3.0
        FMU's own derivative inputs (input_derivative_span)."""
        if self.fmi3:
            return self.input_derivative_span > 0
        return bool(self.model_description.coSimulation.canInterpolateInputs)

    @functools.cached_property
    def input_derivative_span(self) -> int:
        """For an FMI 3.0 FMU that takes each Float64 input's first and second derivative as inputs
        of its own (fmi.rate.<input> and fmi.curvature.<input>, at value reference order x span +
        the input's: our FMUs), the span; 0 for any other."""
        if not self.fmi3:
            return 0
        span = 0x100000
        by_name = {v.name: v for v in self.model_description.modelVariables}
        inputs = [v for v in self.model_description.modelVariables if v.causality == "input"
                  and v.type in ("Float64", "Real") and not v.name.startswith(("fmi.rate.", "fmi.curvature."))]
        for v in inputs:
            for order, kind in ((1, "rate"), (2, "curvature")):
                found = by_name.get(f"fmi.{kind}.{v.name}")
                if found is None or found.causality != "input" or int(found.valueReference) != order * span + \
                        int(v.valueReference):
                    return 0
        return span if inputs else 0

    @property
    def extrapolates_inputs(self) -> bool:
        """Whether the FMU extrapolates over a step the inputs it is given no derivatives for, from
        their values at the last communication points (our FMU layer's fmi.extrapolate_inputs, on)."""
        return "fmi.extrapolate_inputs" in self.variables and bool(self.get("fmi.extrapolate_inputs"))

    @property
    def max_output_derivative_order(self) -> int:
        return int(self.model_description.coSimulation.maxOutputDerivativeOrder or 0)

    def get(self, name: str) -> float | str:
        kind, vr = self.variables[name].type if name in self.variables else None, [self.vr(name)]
        three, version = self.fmi3, 3 if self.fmi3 else 2
        if kind == "Real":
            return self._call(f"fmi{version}Get{'Float64' if three else 'Real'}({name})",
                              self.fmu.getFloat64 if three else self.fmu.getReal, vr)[0]
        if kind in ("Integer", "Enumeration"):
            return self._call(f"fmi{version}Get{'Int32' if three else 'Integer'}({name})",
                              self.fmu.getInt32 if three else self.fmu.getInteger, vr)[0]
        if kind == "String":
            text = self._call(f"fmi{version}GetString({name})", self.fmu.getString, vr)[0]
            return text.decode() if isinstance(text, bytes) else text
        return self._call(f"fmi{version}GetBoolean({name})", self.fmu.getBoolean, vr)[0]

    def real_group(self, names: Sequence[str]) -> "RealGroup":
        return RealGroup(self, names)

    # -- life cycle ------------------------------------------------------------------------------

    def initialize(self, start_values: Mapping[str, float | int | bool] | None = None,
                   start_time: float = 0.0) -> None:
        self.time = start_time
        if self.fmi3:  # FMI 3.0: the values in the instantiated state, the experiment at initialization
            if start_values:
                self.set(start_values)
            self._call("fmi3EnterInitializationMode", self.fmu.enterInitializationMode, startTime=start_time)
            self._call("fmi3ExitInitializationMode", self.fmu.exitInitializationMode)
            return
        self._call("fmi2SetupExperiment", self.fmu.setupExperiment, startTime=start_time)
        if start_values:
            self.set(start_values)
        self._call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)
        self._call("fmi2ExitInitializationMode", self.fmu.exitInitializationMode)

    def do_step(self, step: float) -> None:
        self._call(f"fmi{3 if self.fmi3 else 2}DoStep", self.fmu.doStep, self.time, step)
        self.time += step

    def set_input_derivatives(self, names: Sequence[str], derivatives: Sequence[float], order: int = 1) -> None:
        if self.fmi3:
            raise FmuError(self.name, "set input derivatives", self.time,
                           [LogMessage("error", "", "FMI 3.0 has no input derivatives")])
        self._call("fmi2SetRealInputDerivatives", self.fmu.setRealInputDerivatives,
                   [self.vr(n) for n in names], [order] * len(names), [float(d) for d in derivatives])

    def get_state(self):
        if self.fmi3:
            return self._call("fmi3GetFMUState", self.fmu.getFMUState), self.time
        return self._call("fmi2GetFMUstate", self.fmu.getFMUstate), self.time

    def set_state(self, state) -> None:
        fmu_state, self.time = state
        if self.fmi3:
            self._call("fmi3SetFMUState", self.fmu.setFMUState, fmu_state)
        else:
            self._call("fmi2SetFMUstate", self.fmu.setFMUstate, fmu_state)

    def free_state(self, state) -> None:
        if self.fmi3:
            self._call("fmi3FreeFMUState", self.fmu.freeFMUState, state[0])
        else:
            self._call("fmi2FreeFMUstate", self.fmu.freeFMUstate, state[0])

    def serialize_state(self, state) -> bytes:
        if self.fmi3:
            return self._call("fmi3SerializeFMUState", self.fmu.serializeFMUState, state[0])
        return self._call("fmi2SerializeFMUstate", self.fmu.serializeFMUstate, state[0])

    def deserialize_state(self, data: bytes, time: float):
        if self.fmi3:
            return self._call("fmi3DeserializeFMUState", self.fmu.deserializeFMUState, data), time
        return self._call("fmi2DeSerializeFMUstate", self.fmu.deSerializeFMUstate, data), time

    def terminate(self) -> None:
        self._call(f"fmi{3 if self.fmi3 else 2}Terminate", self.fmu.terminate)

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
        fmu, n = self.instance.fmu, len(self.names)
        if self.instance.fmi3:
            self.instance._call("fmi3GetFloat64", fmu.fmi3GetFloat64, fmu.component, self._vr, n, self._pointer, n)
        else:
            self.instance._call("fmi2GetReal", fmu.fmi2GetReal, fmu.component, self._vr, n, self._pointer)
        return self.values

    def write(self, values: Iterable[float] | None = None) -> None:
        if values is not None:
            self.values[:] = values
        fmu, n = self.instance.fmu, len(self.names)
        if self.instance.fmi3:
            self.instance._call("fmi3SetFloat64", fmu.fmi3SetFloat64, fmu.component, self._vr, n, self._pointer, n)
        else:
            self.instance._call("fmi2SetReal", fmu.fmi2SetReal, fmu.component, self._vr, n, self._pointer)

    def read_derivatives(self, order: int) -> np.ndarray:
        """fmi2GetRealOutputDerivatives of the given order for these (output) variables."""
        n = len(self.names)
        if not hasattr(self, "_read_orders"):
            self._read_orders = {k: (fmi2Integer * n)(*([k] * n)) for k in (1, 2)}
            self._rates = np.zeros(n)
            self._rates_pointer = self._rates.ctypes.data_as(ctypes.POINTER(fmi2Real))
        fmu = self.instance.fmu
        if self.instance.fmi3:
            self.instance._call("fmi3GetOutputDerivatives", fmu.fmi3GetOutputDerivatives, fmu.component, self._vr, n,
                                self._read_orders[order], self._rates_pointer, n)
        else:
            self.instance._call("fmi2GetRealOutputDerivatives", fmu.fmi2GetRealOutputDerivatives, fmu.component,
                                self._vr, n, self._read_orders[order], self._rates_pointer)
        return self._rates.copy()

    def write_derivatives(self, derivatives: Iterable[float], order: int = 1) -> None:
        """fmi2SetRealInputDerivatives of the given order for these (input) variables."""
        if self.instance.fmi3:
            self.instance.set_input_derivatives(self.names, derivatives, order)  # refused: FMI 3.0 has none
        n = len(self.names)
        if not hasattr(self, "_derivatives"):
            self._derivatives = np.zeros(n)
            self._derivative_pointer = self._derivatives.ctypes.data_as(ctypes.POINTER(fmi2Real))
            self._orders = {k: (fmi2Integer * n)(*([k] * n)) for k in (1, 2)}
        self._derivatives[:] = derivatives
        self.instance._call("fmi2SetRealInputDerivatives", self.instance.fmu.fmi2SetRealInputDerivatives,
                            self.instance.fmu.component, self._vr, n, self._orders[order], self._derivative_pointer)
