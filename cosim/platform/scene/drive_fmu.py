"""A drive FMU of the user's own: what it is and what it can do, read from its modelDescription.

Any FMI 2.0 or 3.0 Co-Simulation FMU that keeps a drive's ports of ../shared/INTERFACES.md drives a leg: a
rotary drive takes `angle_ref`, `angle`, `speed` and gives `torque` (the wiring of our pmsm_drive),
a linear one takes `position_ref`, `position`, `velocity` and gives `force` (that of our
linear_motor). Its kind follows from those ports. The optional ports (the reference's rate, the
interface Jacobian's slope, currents) are wired and recorded where the FMU has them.

`inspect` refuses, in one line naming the FMU, the port and the reason, what cannot drive a leg:
a file that is not an FMU, FMI 1.0, Model Exchange only, no binary for this machine, a
missing port, a port of the wrong causality or type, a declared unit that contradicts the
contract. What fmpy's validation finds beyond that is kept as `problems` and reported with the run
(exporting tools differ in how strictly they fill ModelStructure; the run does not depend on it).
What the FMU cannot do limits the master: the capability flags are read at the run
(cosim.engine.checks.capability_problem), and `limits` says what the run switched off.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ..ports import DRIVES

# the contract's drive ports: (inputs, output) per kind, and their units as FMI writes them
PORTS = {kind: ((w.reference[1], w.position[1], w.velocity[1]), w.effort[0]) for kind, w in DRIVES.items()}
UNITS = {"angle_ref": "rad", "angle": "rad", "speed": "rad/s", "torque": "N.m",
         "position_ref": "m", "position": "m", "velocity": "m/s", "force": "N"}
KIND_NAMES = {"pmsm": "rotary", "linear": "linear"}


class DriveFmuError(ValueError):
    """An FMU that cannot drive a leg: one line naming the FMU, the port and the reason."""


@dataclass(frozen=True)
class DriveFmu:
    path: Path
    kind: str                 # "pmsm" (the rotary ports) or "linear"
    model: str                # modelName
    tool: str                 # generationTool
    variables: frozenset[str]
    outputs: frozenset[str]
    parameters: frozenset[str]  # its Real parameters
    state: bool               # canGetAndSetFMUstate
    variable_step: bool       # canHandleVariableCommunicationStepSize
    interpolates: bool        # canInterpolateInputs
    problems: tuple[str, ...] = ()  # fmpy's validation, beyond the contract

    @property
    def name(self) -> str:
        return self.path.name

    def limits(self, interface_jacobian: bool = False) -> list[str]:
        """What the master does not do with this FMU, and why (for the run report); with
        interface_jacobian, whether the scene's interface Jacobian is off for it."""
        out = []
        if not self.state:
            out.append("no step doubling (canGetAndSetFMUstate = false)")
        if not self.variable_step:
            out.append("fixed steps only (canHandleVariableCommunicationStepSize = false)")
        if not self.interpolates:
            out.append("no input derivatives: inputs held over each step (canInterpolateInputs = false)")
        slope = DRIVES[self.kind].slope[0]
        if interface_jacobian and slope not in self.outputs:
            out.append(f"no interface Jacobian (no output '{slope}')")
        return out


@lru_cache(maxsize=None)
def _inspect(path: Path, size: int, mtime: int) -> DriveFmu:
    import fmpy
    from fmpy.validation import validate_fmu
    from ...engine.fmi import fmi2_kinds
    name = path.name
    if not zipfile.is_zipfile(path):
        raise DriveFmuError(f"{name} is not an FMU (not a zip archive)")
    try:
        md = fmpy.read_model_description(str(path))
    except Exception as error:  # fmpy raises bare exceptions for a missing or invalid modelDescription.xml
        reason = " ".join(line.strip(" -") for line in str(error).splitlines() if line.strip())
        raise DriveFmuError(f"{name} is not an FMU fmpy can read: {reason}") from None
    if md.fmiVersion not in ("2.0", "3.0"):
        raise DriveFmuError(f"{name} is FMI {md.fmiVersion}; a drive is an FMI 2.0 or 3.0 Co-Simulation FMU")
    if md.coSimulation is None:
        raise DriveFmuError(f"{name} is a Model Exchange FMU only; a drive must be a Co-Simulation FMU")
    md = fmi2_kinds(md)  # FMI 3.0: Float64 read as Real, no input derivatives
    folder = fmpy.platform_tuple if md.fmiVersion == "3.0" else fmpy.platform
    binary = f"binaries/{folder}/{md.coSimulation.modelIdentifier}{fmpy.sharedLibraryExtension}"
    with zipfile.ZipFile(path) as archive:
        held = sorted({n.split("/")[1] for n in archive.namelist() if n.startswith("binaries/") and n.count("/") > 1})
        if binary not in archive.namelist():
            raise DriveFmuError(f"{name} has no binary for this machine ({binary}; it holds "
                                f"{', '.join(held) or 'no binaries'})")
    found = {v.name: v for v in md.modelVariables}
    kinds = [kind for kind, (_, effort) in PORTS.items() if effort in found]
    if not kinds:
        raise DriveFmuError(f"{name} has neither a 'torque' output (a rotary drive) nor a 'force' output (a linear "
                            "drive), the drive ports of INTERFACES.md")
    # of two candidate kinds, the one whose inputs are there
    kind = min(kinds, key=lambda k: sum(port not in found for port in PORTS[k][0]))
    inputs, effort = PORTS[kind]
    for port, causality in [*((p, "input") for p in inputs), (effort, "output")]:
        variable = found.get(port)
        what = f"{name}: the {KIND_NAMES[kind]} drive's {causality} '{port}'"
        if variable is None:
            raise DriveFmuError(f"{what} is missing (it has: {', '.join(sorted(found)[:12])}"
                                f"{', ...' if len(found) > 12 else ''})")
        if variable.causality != causality:
            raise DriveFmuError(f"{what} is declared {variable.causality}")
        if variable.type != "Real":
            raise DriveFmuError(f"{what} is {variable.type}, not Real")
        unit = variable.unit or getattr(variable.declaredType, "unit", None)
        if unit and unit != UNITS[port]:
            raise DriveFmuError(f"{what} is in '{unit}'; the contract's unit is '{UNITS[port]}'")
    problems = tuple(validate_fmu(str(path)))
    flags = md.coSimulation
    return DriveFmu(path, kind, md.modelName, md.generationTool or "unknown tool", frozenset(found),
                    frozenset(n for n, v in found.items() if v.causality == "output"),
                    frozenset(n for n, v in found.items() if v.causality == "parameter" and v.type == "Real"),
                    bool(flags.canGetAndSetFMUstate), bool(flags.canHandleVariableCommunicationStepSize),
                    bool(flags.canInterpolateInputs), problems)


def inspect(path: Path) -> DriveFmu:
    """The drive FMU at `path` (read once per file version); DriveFmuError if it cannot drive a leg."""
    path = Path(path).resolve()
    if not path.is_file():
        raise DriveFmuError(f"{path}: no such file" + (" (a folder)" if path.is_dir() else ""))
    status = path.stat()
    return _inspect(path, status.st_size, status.st_mtime_ns)
