"""A user's mistake that only shows when the scene's system is built or started (a value an FMU
refuses, a step that does not fit, a platform the values do not build, a recorded output the FMU
lacks), named at the scene's file, line and key."""

from __future__ import annotations

import re

from ...engine import FmuError, NoStep, ParameterError
from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.schema import line_of
from ..core import LayoutImpossible, SingularPose
from ..scene import Scene, SceneError
from .compile import drive_fmus

BUILD_ERRORS = (ParameterError, FmuError, NoStep, KeyError, LayoutImpossible, SingularPose)  # what scene_error maps


def scene_key(component: str, variable: str) -> tuple[str, str]:
    """The scene table and key that a component's parameter comes from."""
    if component == "mechanics":
        return "mechanics.parameters", variable
    if component == "cueing":
        return ("motion", "vehicle") if variable.startswith("vehicle.") else ("cueing.parameters", variable)
    if component == "trajectory":
        if variable.startswith("load."):
            return "load", "pulses"
        if variable.startswith("table."):
            return "trajectory", "table"
        dof, rest = variable.split(".", 1)
        return f"trajectory.{dof}", {"sine": "sines", "step": "steps", "ramp": "ramps"}.get(rest.split("[")[0], rest)
    return "drive.parameters", variable


def located(scene: Scene, component: str, variable: str) -> str:
    """'file:line: table.key' for a component's parameter (file:0 when the scene does not set it,
    the value then comes from the parameter set or the FMU's default)."""
    table, key = scene_key(component, variable)
    line = line_of(scene.text, table, key)
    if table.endswith(".parameters"):
        shown = f'{table}."{key}"'
    elif table == "load":
        shown = f"load.pulses ({variable})"
    elif table == "motion":
        shown = "motion.vehicle"
    else:  # x.sine[1].amplitude -> trajectory.x.sines[1].amplitude
        rest = variable.split(".", 1)[1]
        item = re.match(r"(sine|step|ramp)\[(\d+)\]\.(\w+)$", rest)
        shown = f"{table}.{item.group(1)}s[{item.group(2)}].{item.group(3)}" if item else f"{table}.{rest}"
    given = scene.document.given_for(shown.split(" (")[0])
    if given:
        return f"{given} (over {scene.path}): {shown}"
    return f"{scene.path}:{line}: {shown}" + ("" if line else f" (from parameter set {scene.parameter_set})")


def component_fmu(scene: Scene, component: str):
    """The FMU of a scene's component by its name (a drive's by its leg number), None if unknown."""
    if component in ("trajectory", "mechanics", "cueing"):
        return fmu_path(component)
    leg = re.fullmatch(r"\D+([1-6])", component)
    return drive_fmus(scene)[int(leg.group(1)) - 1] if leg else None


def scene_error(scene: Scene, error: Exception) -> SceneError | None:
    """A one-line SceneError with the scene's file and line for a user error found when the
    system is built or started, or None for anything else (a bug)."""
    if isinstance(error, ParameterError):
        return SceneError(f"{located(scene, error.component, error.variable)} = {error.value!r}: {error.reason} "
                          f"({error.fmu})")
    if isinstance(error, FmuError) and error.call.startswith(("fmi2Instantiate", "fmi2Set", "fmi2Enter", "fmi2Exit",
                                                             "fmi2Setup")):
        detail = "; ".join(m.text for m in error.messages) or "the FMU logged no reason"
        # the variable the FMU names (opening its message, or quoted), if it is one of its variables: a
        # table's fault opens with the file's parameter, and may quote a column named as an input
        # (of several it names, such as mpc.horizon against mpc.period, the first the scene sets)
        fmu = component_fmu(scene, error.instance)
        names = set(variables(fmu)) if fmu is not None else set()
        found = [m.group(1) for m in (re.match(r"([\w.\[\]]+)[ :]", detail), re.search(r"'([^']+)'", detail),
                                      *re.finditer(r"([\w.\[\]]+) =", detail))
                 if m is not None and m.group(1) in names]
        named = next((n for n in found if line_of(scene.text, *scene_key(error.instance, n))), found[0] if found
                     else None)
        where = located(scene, error.instance, named) if named else f"{scene.path}"
        return SceneError(f"{where}: rejected by {error.instance}: {detail}")
    if isinstance(error, NoStep):
        return SceneError(f"{scene.document.where('scene.step')}: scene.step = "
                          f"{scene.step:g} s, duration {scene.duration:g} s: {error}")
    if isinstance(error, (LayoutImpossible, SingularPose)):  # the platform the scene asks for, at its start pose
        return SceneError(f"{scene.document.where('mechanics.parameters')}: the platform "
                          f"of [mechanics] at its start pose: {error}")
    if isinstance(error, KeyError) and "no variable" in str(error):  # a recorded output the FMU lacks
        names = set(scene.outputs_mechanics)
        key = "mechanics" if any(f"'{n}'" in str(error) for n in names) else "drive"
        return SceneError(f"{scene.document.where(f'outputs.{key}')}: 'outputs.{key}': "
                          f"{error.args[0]}")
    return None
