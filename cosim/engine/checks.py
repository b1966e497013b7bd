"""Parameter values checked against each FMU's modelDescription before anything is instantiated:
the variable exists and may be set before initialization, and the value has the variable's type
(a Boolean only true or false, an Integer only a whole number, a Real only a finite number, a
String only text) and lies within its declared min and max. The first problem is a
`ParameterError` naming the component, variable, value and reason, so that a system never starts
from a value that Python silently converted (bool("false") is True, int(4.7) is 4).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping


from .settings import SettingsError
from .structure import SystemStructure, Value

SETTABLE = {"parameter", "input"}


@dataclass
class ParameterError(ValueError):
    component: str
    variable: str
    value: object
    reason: str
    fmu: str

    def __str__(self) -> str:
        return f"{self.component}.{self.variable} = {self.value!r}: {self.reason} ({self.fmu})"


class CapabilityError(SettingsError):
    """A component whose FMU cannot do what the step control asks (its capability flags)."""


def variables(path: Path) -> dict:
    """The FMU's variables by name (its model description read once per process and file
    version: cosim.engine.fmi.loaded)."""
    from .fmi import loaded
    return {v.name: v for v in loaded(path)[0].modelVariables}


def _bound(text) -> float | None:
    return None if text in (None, "") else float(text)


def problem(variable, value: Value) -> str | None:
    """Why `value` cannot be given to `variable`, or None."""
    if variable.causality not in SETTABLE or variable.variability == "constant":
        return f"is {variable.causality} ({variable.variability}), not a parameter that can be set"
    kind = variable.type
    if kind == "Boolean":
        return None if isinstance(value, bool) else "must be true or false"
    if kind in ("Integer", "Enumeration"):
        whole = (isinstance(value, int) and not isinstance(value, bool)) or \
            (isinstance(value, float) and math.isfinite(value) and value.is_integer())
        if not whole:
            return "must be a whole number"
    elif kind == "Real":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return "must be a finite number"
    elif kind == "String":
        return None if isinstance(value, (str, Path)) else "must be text"
    else:
        return f"has type {kind}, which cannot be set"
    low = _bound(variable.min) if variable.min is not None else _bound(getattr(variable.declaredType, "min", None))
    high = _bound(variable.max) if variable.max is not None else _bound(getattr(variable.declaredType, "max", None))
    if (low is not None and value < low) or (high is not None and value > high):
        unit = variable.unit or getattr(variable.declaredType, "unit", None) or ""
        opening = "(0" if low == sys.float_info.min else f"[{'-inf' if low is None else f'{low:g}'}"  # > 0
        return f"outside {opening}, {'inf' if high is None else f'{high:g}'}]" + (f" {unit}" if unit else "")
    return None


def check_parameters(structure: SystemStructure) -> None:
    """Raises ParameterError for the first parameter value its FMU cannot take."""
    for component in structure.components:
        check_values(component.name, component.fmu, component.parameters)


def check_values(component: str, fmu: Path, values: Mapping[str, Value]) -> None:
    """Raises ParameterError for the first of `values` (by variable name) that the FMU cannot take
    (none given: its description is not read)."""
    if not values:
        return
    known = variables(fmu)
    for name, value in values.items():
        if name not in known:
            close = [n for n in known if n.lower() == name.lower() or _near(n, name)]
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise ParameterError(component, name, value, f"no such variable{hint}", fmu.stem)
        reason = problem(known[name], value)
        if reason:
            raise ParameterError(component, name, value, reason, fmu.stem)


def capability_problem(fmu: Path, control: object, instances: int = 1) -> str | None:
    """Why an FMU cannot run under this step control (a cosim.engine.settings control), as `instances`
    components of one system, or None: its modelDescription's capability flags decide. Step
    doubling takes steps back (canGetAndSetFMUstate); the adaptive controls and a fixed step with a
    finer start or edge windows change the step (canHandleVariableCommunicationStepSize); an FMU
    that can be instantiated only once per process cannot be several components."""
    from .fmi import loaded
    from .settings import FixedStep, StepDoubling
    flags = loaded(fmu)[0].coSimulation
    if flags is None:
        return "is not a Co-Simulation FMU (Model Exchange only)"
    if isinstance(control, StepDoubling) and not flags.canGetAndSetFMUstate:
        return ("cannot get and set its state (canGetAndSetFMUstate = false), which step doubling needs to take a "
                "step back: use the fixed step or the energy control")
    varies = not isinstance(control, FixedStep) or bool(control.windows) or \
        (control.startup_time > 0 and 0 < control.startup_step < control.step)
    if varies and not flags.canHandleVariableCommunicationStepSize:
        return ("takes one communication step size only (canHandleVariableCommunicationStepSize = false): use a fixed "
                "step without a finer start or edge windows")
    if instances > 1 and flags.canBeInstantiatedOnlyOncePerProcess:
        return f"can be instantiated only once per process (canBeInstantiatedOnlyOncePerProcess), not {instances} times"
    return None


def check_capabilities(structure: SystemStructure, control: object) -> None:
    """Raises CapabilityError for the first component whose FMU cannot run under `control`."""
    count: dict[Path, int] = {}
    for component in structure.components:
        count[Path(component.fmu)] = count.get(Path(component.fmu), 0) + 1
    for component in structure.components:
        reason = capability_problem(Path(component.fmu), control, count[Path(component.fmu)])
        if reason:
            raise CapabilityError(f"{component.name} ({Path(component.fmu).name}) {reason}")


def _near(a: str, b: str) -> bool:
    """One edit apart (a typo), for the hint."""
    if abs(len(a) - len(b)) > 1 or a == b:
        return False
    if len(a) == len(b):
        return sum(x != y for x, y in zip(a, b)) == 1
    short, long_ = sorted((a, b), key=len)
    return any(long_[:i] + long_[i + 1:] == short for i in range(len(long_)))
