"""Reads a design study file into a `Study`: the schema checks every key's type and range
(cosim.platform.design.spec.schema), this module what depends on the platform family and on other
keys; a motion given as a time series (a scene's reference, or a table) is played by the
trajectory FMU here. Every mistake is one line naming the file, the line and the full key."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ....engine.schema import Document, read
from ...ports import POSE
from .motion import LONGEST, ramp_and_cruise
from .schema import RECORDED, SCHEMA, StudyError
from .study import (DOFS, FAMILIES, ROTATIONS, Actuator, ConfirmSpec, Motion, Motor, OptimiseSpec, ParetoSpec,
                    Recorded, Study, Thresholds, WorkspaceSpec, parameter_set)

MOST_PER_AXIS = 2000


def load_study(path: str | Path) -> Study:
    """Reads and checks a study file (studies/*.toml); every mistake is a StudyError naming the
    file, the line and the key."""
    doc = read(SCHEMA, path)
    family_name = doc.value("study", "parameter_set")
    family = FAMILIES[family_name]
    config = parameter_set(family_name)
    design_values = family.design_values(config)
    fixed = _fixed(doc, design_values, family.may_be_zero)
    axes = _axes(doc, design_values, family.fixed_only, family.may_be_zero)
    motion, recorded = _motion(doc)
    actuators = [_actuator(doc, k, family.mechanics(config, design_values)) for k in range(len(doc.entries("actuator")))]
    payload_mass, payload_inertia = family.payload(config)
    names = [a.name for a in actuators]
    limits = {key: math.radians(doc.value("study", key)) for key in
              ("joint_angle_limit_deg", "top_joint_angle_limit_deg", "bottom_joint_angle_limit_deg")
              if doc.value("study", key) is not None}
    study = Study(doc.path, str(doc.value("study", "name", doc.path.stem)), family_name, axes, motion, actuators,
                  limits["joint_angle_limit_deg"], float(doc.value("study", "payload_mass", payload_mass)),
                  tuple(float(v) for v in doc.value("study", "payload_inertia", payload_inertia)),
                  _margins(doc), doc.value("study", "force_margins_mode"), int(doc.value("study", "samples")),
                  fixed=fixed, workspace=_workspace(doc, axes, names), optimise=_optimise(doc, names),
                  confirm=_confirm(doc, axes, names), recorded=recorded,
                  top_joint_limit=limits.get("top_joint_angle_limit_deg"),
                  bottom_joint_limit=limits.get("bottom_joint_angle_limit_deg"),
                  thresholds=Thresholds(float(doc.value("thresholds", "condition_number")),
                                        float(doc.value("thresholds", "singular_distance_factor"))),
                  payload_from=_payload_from(doc, family_name))
    study.chosen = _point(doc, "study", axes, key="chosen") if doc.value("study", "chosen") is not None else None
    study.pareto = _pareto(doc, actuators)
    _not_degenerate(doc, study)
    return study


def _margins(doc: Document) -> tuple[float, float]:
    """[study] force_margins, leaving some force under the mode they are read in."""
    friction, other = (float(v) for v in doc.value("study", "force_margins"))
    if doc.value("study", "force_margins_mode") == "subtract" and friction + other >= 1:
        raise doc.fail("study.force_margins", "leave no force: read as 'subtract', friction + other must be below 1",
                       [friction, other])
    return friction, other


def _payload_from(doc: Document, family_name: str) -> str:
    """Where the payload comes from: the study's words (payload_from), else which file gives its
    mass and which its inertia."""
    if doc.value("study", "payload_from") is not None:
        return str(doc.value("study", "payload_from"))
    source = {key: "the study file" if doc.value("study", key) is not None else f"params/{family_name}.toml"
              for key in ("payload_mass", "payload_inertia")}
    if len(set(source.values())) == 1:
        return source["payload_mass"]
    return f"the mass from {source['payload_mass']}, the inertia from {source['payload_inertia']}"


def _not_degenerate(doc: Document, study: Study) -> None:
    """Every corner of the grid (and each design the study names) builds a platform whose legs hold
    it at its neutral pose: a finite neutral and a leg Jacobian there that is not singular."""
    from ...core import Core
    from .study import platform_values
    (row_key, rows), (column_key, columns) = list(study.axes.items())
    named = [(f"study.chosen", study.chosen), ("workspace.point", study.workspace and study.workspace.point),
             ("confirm.point", study.confirm and study.confirm.point)]
    corners = [("axes", {row_key: float(r), column_key: float(c)}) for r in (rows[0], rows[-1])
               for c in (columns[0], columns[-1])]
    core = Core(actuators=False, motors=False, friction=False)
    for key, point in corners + [(k, p) for k, p in named if p]:
        problem = degenerate(core, platform_values(study, point))
        if problem:
            where = ", ".join(f"{k} = {v:g}" for k, v in point.items())
            raise doc.fail(key, f"makes a degenerate platform at {where}: {problem}")


def degenerate(core, values: dict) -> str | None:
    """Why the platform of these mechanics values cannot be a design (None if it can): its neutral
    pose not finite, or its leg Jacobian there singular (condition number above 1e6)."""
    with np.errstate(all="ignore"):
        try:
            core.use_start_values(values)
            neutral = core.neutral_pose
            jacobian = core.pose_kinematics(neutral[None], jacobian=True)["jacobian"][0]
        except (ValueError, RuntimeError) as error:
            return str(error)
        if not np.all(np.isfinite(neutral)) or not np.all(np.isfinite(jacobian)):
            return "its neutral pose is not finite"
        singular = np.linalg.svd(jacobian, compute_uv=False)
        if not singular[-1] > 1e-6 * singular[0]:
            return (f"its legs' Jacobian is singular at the neutral pose (condition number "
                    f"{singular[0] / singular[-1] if singular[-1] > 0 else math.inf:.3g})")
    return None


def _fixed(doc: Document, design_values: dict[str, float], may_be_zero: tuple[str, ...]) -> dict[str, float]:
    """[study] fixed: design values held at their own values (positive numbers; 0 for one that is
    not a size)."""
    fixed = doc.value("study", "fixed", {})
    for key, number in fixed.items():
        if key not in design_values:
            raise doc.fail(f"study.fixed.{key}", f"is not a design value of {doc.value('study', 'parameter_set')} "
                           f"({', '.join(sorted(design_values))})")
        if isinstance(number, bool) or not isinstance(number, (int, float)) or not math.isfinite(number) or number < 0 \
                or (number == 0 and key not in may_be_zero):
            raise doc.fail(f"study.fixed.{key}", "must be a non-negative number" if key in may_be_zero else
                           "must be a positive number (a size)", number)
    return {k: float(v) for k, v in fixed.items()}


def _axes(doc: Document, design_values: dict[str, float], fixed_only: tuple[str, ...],
          may_be_zero: tuple[str, ...]) -> dict[str, np.ndarray]:
    """[axes]: two design values of the family, each from, to, step (from above 0 for a size)."""
    given = doc.family("axes.<value>")
    known = ", ".join(sorted(design_values))
    if len(given) != 2:
        raise doc.fail("axes", f"must name two design values of {doc.value('study', 'parameter_set')}, each "
                       f"{{from, to, step}} ({known})")
    axes = {}
    for key, spec in given.items():
        if key not in design_values:
            raise doc.fail(f"axes.{key}", f"is not a design value of {doc.value('study', 'parameter_set')} ({known})")
        if key in fixed_only:
            raise doc.fail(f"axes.{key}", "is one value per study: set it in [study] fixed")
        low, high, step = (float(spec[k]) for k in ("from", "to", "step"))
        if low == 0 and key not in may_be_zero:
            raise doc.fail(f"axes.{key}.from", f"must be above 0: {key} is a size", spec["from"])
        if not high >= low:
            raise doc.fail(f"axes.{key}.to", f"must not be below from = {low:g}", spec["to"])
        count = int(round((high - low) / step)) + 1
        if count < 2:
            raise doc.fail(f"axes.{key}", f"has one value ({low:g}): a map needs at least two an axis (to above "
                           f"from by a step or more)")
        if count > MOST_PER_AXIS:
            raise doc.fail(f"axes.{key}", f"has {count} values; at most {MOST_PER_AXIS} per axis")
        axes[key] = np.round(low + step * np.arange(count), 10)
    return axes


def _motion(doc: Document) -> tuple[Motion | None, Recorded | None]:
    """[motion]: the basic motions (half ranges and limits), or one motion as a time series."""
    motion = doc.table("motion")
    if set(RECORDED) & set(motion):
        sources = [k for k in ("scene", "table", "vehicle") if k in motion]
        if len(sources) != 1:
            raise doc.fail(f"motion.{(sorted(set(motion) & set(RECORDED)) or ['samples'])[0] if not sources else sources[1]}",
                           "needs one of 'scene' (a scene's reference motion), 'table' (a recorded motion) or "
                           "'vehicle' (a vehicle's motion through the cueing), not " + ("none" if not sources else
                                                                                      "several"))
        others = sorted(set(motion) - set(RECORDED))
        if others:
            raise doc.fail(f"motion.{others[0]}", f"belongs to the basic motions; the motion here is the "
                           f"{sources[0]}'s")
        if "cueing" in motion and sources[0] != "vehicle":
            raise doc.fail("motion.cueing", "tunes the motion cueing of a vehicle's motion (motion.vehicle)")
        source = motion[sources[0]]
        cueing = _cueing(doc) if sources[0] == "vehicle" else {}
        try:
            return None, recorded_motion(doc.path, sources[0], source, int(doc.value("motion", "samples")), cueing)
        except StudyError as error:
            raise doc.fail(f"motion.{sources[0]}", str(error), source) from None
    ranges = {d: float(doc.value("motion", d)) for d in DOFS if d not in ROTATIONS}
    ranges.update({d: math.radians(doc.value("motion", f"{d}_deg")) for d in ROTATIONS})
    if not any(ranges.values()):
        raise doc.fail("motion", "gives no range: name at least one of surge, sway, heave, roll_deg, pitch_deg, "
                       "yaw_deg (or a scene or table)")
    limits = {}
    for key in ("velocity", "acceleration", "angular_velocity_deg", "angular_acceleration_deg"):
        if doc.value("motion", key) is None:
            raise doc.fail(f"motion.{key}", "is missing: the basic motions need their speed and acceleration limits")
        limits[key] = float(doc.value("motion", key))
    motion = Motion(ranges, limits["velocity"], limits["acceleration"], math.radians(limits["angular_velocity_deg"]),
                    math.radians(limits["angular_acceleration_deg"]))
    for dof, half in ranges.items():  # each basic motion must end: the confirmation plays it step by step
        rotation = dof in ROTATIONS
        t_ramp, t_cruise = ramp_and_cruise(2 * half, motion.angular_velocity if rotation else motion.velocity,
                                           motion.angular_acceleration if rotation else motion.acceleration)
        if 2 * t_ramp + t_cruise > LONGEST:
            key = ("angular_" if rotation else "") + ("acceleration" if 2 * t_ramp > t_cruise else "velocity") \
                + ("_deg" if rotation else "")
            raise doc.fail(f"motion.{key}", f"makes the {dof} motion last {2 * t_ramp + t_cruise:.3g} s; a basic "
                           f"motion lasts at most {LONGEST:g} s (raise the limit, or shorten the range)",
                           limits[key])
    return motion, None


def _actuator(doc: Document, k: int, transmission: dict[str, float]) -> Actuator:
    """The k-th [[actuator]] (0 the first); a motor's torques and speed through the family's screw
    (K_FT, i_theta)."""
    entry, where = doc.entries("actuator")[k], f"actuator[{k + 1}]"
    force_torque, screw_ratio = transmission["transmission.force_torque"], transmission["transmission.screw_ratio"]
    limits = {}
    for force, torque, factor in (("continuous_force", "continuous_torque", force_torque),
                                  ("peak_force", "peak_torque", force_torque),
                                  ("speed", "motor_speed", 1.0 / screw_ratio)):
        if force in entry and torque in entry:
            raise doc.fail(f"{where}.{torque}", f"and '{force}' both given: one of them")
        if torque in entry:  # the motor's side, through the family's screw (K_FT, i_theta)
            if force_torque == 1.0 and screw_ratio == 1.0:
                raise doc.fail(f"{where}.{torque}", f"needs a screw: {doc.value('study', 'parameter_set')}'s legs are "
                               f"driven by force (give '{force}')")
            limits[force] = float(entry[torque]) * factor
        elif force in entry:
            limits[force] = float(entry[force])
    if "continuous_force" not in limits:
        raise doc.fail(f"{where}.continuous_force", "is missing (or give continuous_torque)")
    motor = None
    if "continuous_torque" in entry:
        given = {key: float(entry[key]) if key in entry else None for key in ("peak_torque", "motor_speed", "rotor_inertia")}
        motor = Motor(float(entry["continuous_torque"]), *given.values(), force_torque / screw_ratio)
    elif "rotor_inertia" in entry:
        raise doc.fail(f"{where}.rotor_inertia", "belongs to an actuator given by its motor (continuous_torque)")
    return Actuator(entry["name"], float(entry["stroke"]), float(entry["running_length_min"]),
                    limits["continuous_force"], limits.get("peak_force"), limits.get("speed"), motor,
                    2 * math.pi / screw_ratio if motor else None, entry.get("drive", "pmsm" if motor else "force"))


def _point(doc: Document, table: str, axes: dict[str, np.ndarray], actuators: list[str] | None = None,
           key: str = "point") -> dict[str, float]:
    """[workspace] or [confirm] (a design, a positive value of each axis, and one of the
    actuators), or [study] chosen (a design)."""
    point = doc.value(table, key)
    if set(point) != set(axes):
        raise doc.fail(f"{table}.{key}", f"must give the design as {{{', '.join(f'{k} = ...' for k in axes)}}}")
    for name, number in point.items():
        if isinstance(number, bool) or not isinstance(number, (int, float)) or not math.isfinite(number) \
                or not number > 0:
            raise doc.fail(f"{table}.{key}.{name}", "must be a positive number", number)
    if actuators is not None and doc.value(table, "actuator") not in actuators:
        raise doc.fail(f"{table}.actuator", f"is not one of the study's actuators ({', '.join(actuators)})",
                       doc.value(table, "actuator"))
    return {k: float(v) for k, v in point.items()}


def _workspace(doc: Document, axes: dict[str, np.ndarray], actuators: list[str]) -> WorkspaceSpec | None:
    if "workspace" not in doc.data:
        return None
    return WorkspaceSpec(_point(doc, "workspace", axes, actuators), doc.value("workspace", "actuator"),
                         float(doc.value("workspace", "spacing")), math.radians(doc.value("workspace", "angle_step_deg")))


def _optimise(doc: Document, actuators: list[str]) -> OptimiseSpec | None:
    if "optimise" not in doc.data:
        return None
    if doc.value("optimise", "actuator") not in actuators:
        raise doc.fail("optimise.actuator", f"is not one of the study's actuators ({', '.join(actuators)})",
                       doc.value("optimise", "actuator"))
    return OptimiseSpec(doc.value("optimise", "actuator"), int(doc.value("optimise", "seed")),
                        int(doc.value("optimise", "iterations")))


def _pareto(doc: Document, actuators: list[Actuator]) -> ParetoSpec | None:
    """[pareto]: distinct objectives, a catalogue of the study's actuators, a lead range where one
    of them is given by its motor."""
    if "pareto" not in doc.data:
        return None
    objectives = doc.value("pareto", "objectives")
    if len(set(objectives)) != len(objectives):
        raise doc.fail("pareto.objectives", "names an objective twice", objectives)
    names = [a.name for a in actuators]
    catalogue = doc.value("pareto", "actuators", names)
    for name in catalogue:
        if name not in names:
            raise doc.fail("pareto.actuators", f"names {name!r}, not one of the study's actuators ({', '.join(names)})",
                           catalogue)
    lead = doc.value("pareto", "screw_lead")
    if lead is not None:
        if not lead[1] >= lead[0]:
            raise doc.fail("pareto.screw_lead", "must run from a lead to one not below it", lead)
        if not any(a.motor for a in actuators if a.name in catalogue):
            raise doc.fail("pareto.screw_lead", "needs an actuator given by its motor (continuous_torque) in the "
                           "catalogue", lead)
    return ParetoSpec(tuple(objectives), tuple(catalogue), None if lead is None else (float(lead[0]), float(lead[1])),
                      int(doc.value("pareto", "population")), int(doc.value("pareto", "generations")),
                      int(doc.value("pareto", "seed")), float(doc.value("pareto", "workspace_spacing")),
                      bool(doc.value("pareto", "confirm")))


def _confirm(doc: Document, axes: dict[str, np.ndarray], actuators: list[str]) -> ConfirmSpec | None:
    if "confirm" not in doc.data:
        return None
    return ConfirmSpec(_point(doc, "confirm", axes, actuators), doc.value("confirm", "actuator"),
                       doc.value("confirm", "drive"))


def _cueing(doc: Document) -> dict[str, Any]:
    """[motion] cueing: the cueing FMU's parameter values, checked against its modelDescription."""
    from ....engine.artifacts import fmu_path
    from ....engine.checks import ParameterError, check_values
    given = doc.value("motion", "cueing", {})
    try:
        check_values("motion.cueing", fmu_path("cueing"), given)
    except ParameterError as error:
        raise doc.fail(f'motion.cueing."{error.variable}"', f"{error.reason} (cueing)", error.value) from None
    if given.get("algorithm", 1) != 1:
        raise doc.fail('motion.cueing."algorithm"', "a study plays one cueing reference for all its designs, which "
                       "the classical washout (1) gives; the MPC (2) keeps the one platform it is given in its "
                       "envelope: run it per design with `cosim run` and [cueing] algorithm = \"mpc\"", given["algorithm"])
    return dict(given)


def recorded_motion(study_path: Path, kind: str, source: Any, samples: int, cueing: dict | None = None) -> Recorded:
    """[motion] scene = "<name or path>": the scene's reference motion less its platform's neutral
    pose; [motion] table = "<csv>": a recorded motion (columns time and any of x, y, z, roll, pitch,
    yaw: displacements from the neutral pose, m and rad), played by the trajectory FMU (cubic
    interpolation), the one reader of tables; [motion] vehicle = "<csv>": a vehicle's motion at
    the head through the cueing FMU with `cueing` values (played at 1 ms, the displacements its
    pose reference less its neutral pose). Each sampled `samples` times evenly over its duration (at
    least 4); the rates and accelerations are the samples' second-order differences. Raises
    StudyError with the reason (the caller adds the file and line)."""
    from ...core import neutral_pose
    from ...run.compile import scene_values
    from ...scene import SceneError, Signal, load_scene, shipped
    from ...run.alone import play
    from ...scene.signals import scene_trajectory, trajectory_parameters
    given = study_path.parent / source
    if kind == "scene":
        found = given if given.is_file() else shipped(source, "scenes")
        if found is None:
            raise StudyError("no such scene (relative to the study's folder, or a shipped scene's name)")
        try:
            scene = load_scene(found)
            neutral = neutral_pose(scene_values(scene)[0])
            values, duration, name = scene_trajectory(scene), scene.duration, found.stem
        except (SceneError, ValueError) as error:
            raise StudyError(str(error)) from None
    else:
        if not given.is_file():
            raise StudyError("no such file (relative to the study's folder)")
        lines = [line for line in given.read_text(errors="replace").splitlines() if line.strip()]
        columns = "the vehicle's motion" if kind == "vehicle" else f"any of {', '.join(POSE)}"
        try:
            duration = float(lines[-1].split(",")[0])
        except (IndexError, ValueError):
            raise StudyError(f"its last line gives no time (a CSV with columns time and {columns})") from None
        values = trajectory_parameters({axis: Signal(offset=0.0) for axis in POSE}, table=given, interpolation="cubic")
        neutral, name = np.zeros(6), given.stem
    if not duration > 0:
        raise StudyError(f"lasts {duration:g} s; a motion needs a positive duration")
    step = duration / (samples - 1)
    try:
        if kind == "vehicle":
            times, poses = _through_cueing(given, cueing or {}, duration, step)
        else:
            times, poses, _ = play(values, duration, step)
    except StudyError:
        raise
    except Exception as error:  # the FMU's refusal (a bad table: its file and line)
        raise StudyError(str(error)) from None
    displacement = poses - neutral
    return Recorded(name, times, displacement, np.gradient(displacement, step, axis=0, edge_order=2),
                    second_difference(displacement, step))


def _through_cueing(vehicle: Path, cueing: dict, duration: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    """A vehicle's motion through the cueing FMU (its neutral pose at zero: the pose reference is
    the displacement), played at 1 ms (or `step`, if finer) and taken at every `step`."""
    from ...run.alone import play_cueing
    values = {**cueing, "vehicle.file": vehicle.resolve(), **{f"neutral.{a}": 0.0 for a in POSE}}
    fine = min(step, 1e-3)
    times, poses, _, _ = play_cueing(values, duration, fine)
    at = np.linspace(0.0, duration, int(round(duration / step)) + 1)
    return at, np.column_stack([np.interp(at, times, poses[:, k]) for k in range(6)])


def second_difference(x: np.ndarray, step: float) -> np.ndarray:
    """The second derivative of evenly sampled rows, to second order: central differences inside,
    the one-sided four-point formula (2, -5, 4, -1) at both ends."""
    out = np.empty_like(x)
    out[1:-1] = x[2:] - 2 * x[1:-1] + x[:-2]
    out[0] = 2 * x[0] - 5 * x[1] + 4 * x[2] - x[3]
    out[-1] = 2 * x[-1] - 5 * x[-2] + 4 * x[-3] - x[-4]
    return out / step ** 2
