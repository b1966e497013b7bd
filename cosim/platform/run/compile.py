"""A scene compiled into the platform's system, once per run (`compile_scene`): per leg the drive
FMU (ours or the user's) and its parameters (designed for the leg's plant where the scene asks,
checked against its static load), the mechanics' values, the wiring (cosim.platform.run.system),
what is recorded, and the engine's plan of the run. Everything downstream of a run (its report,
plots, real-time plan) reads the one `CompiledScene`."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ...engine import Algorithm, Experiment, SystemStructure
from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.run import Plan
from ...engine.settings import output_settings, to_strings
from ..ports import DRIVES, LEGS, POSE
from ..scene import Scene, SceneError
from ..scene.parameter_sets import drive_set, envelope_margins, scene_mechanics
from ..scene.signals import scene_trajectory
from .system import columns, platform_structure
from .tuning import SizingError, check_limit, check_sizing, design, hold_currents, leg_plants, summary


@dataclass(frozen=True)
class CompiledScene:
    """A scene made into its run: the mechanics FMU's values, per leg the drive FMU and its values
    as run (designed where the scene asks), the designed gains' summary, the notes on the user's
    drives, the system and the engine's plan."""
    scene: Scene
    mechanics: dict
    fmus: list[Path]
    legs: list[dict]
    tuning: str | None
    notes: list[str]
    structure: SystemStructure
    plan: Plan


def compile_scene(scene: Scene) -> CompiledScene:
    """The scene compiled: its values read and its drives designed once, its system and plan made
    from them. Raises what scene_design and the wiring raise (a SceneError, an engine error that
    cosim.platform.run.errors maps to the scene's line)."""
    mechanics, drives = scene_values(scene)
    fmus = drive_fmus(scene)
    legs, tuning, notes = scene_design(scene, (mechanics, drives), fmus)
    notes = [*notes, *vehicle_notes(scene)]
    record, algorithm = scene_record(scene, fmus), scene_algorithm(scene)
    structure = _wire(scene, legs, mechanics, fmus, record, algorithm)
    plan = Plan(structure, algorithm, scene.control, scene.duration, *record, scene.output_interval, clock="mechanics")
    return CompiledScene(scene, mechanics, fmus, legs, tuning, notes, structure, plan)


def vehicle_notes(scene: Scene) -> list[str]:
    """What a vehicle's drive that fits its scene badly makes of the run, said where a user may mean
    it: a drive that ends before the scene (its last row held: the car as it was, cued as standing
    or cruising), and one whose times look like milliseconds (the scene would cue its first instants
    alone). The table's faults are the cueing FMU's to refuse (its file and line)."""
    if scene.vehicle is None:
        return []
    try:
        with open(scene.vehicle, encoding="utf-8-sig", errors="replace") as file:
            times = [float(line.split(",", 1)[0]) for line in file
                     if line.strip() and not line.lstrip().startswith("#") and line[:1].strip(" -.0123456789") == ""]
    except (OSError, ValueError):
        return []
    if len(times) < 2:
        return []
    last, spacing = times[-1], (times[-1] - times[0]) / (len(times) - 1)
    where = f"{scene.document.where('motion.vehicle')}: motion.vehicle"
    if spacing >= 1.0 and last >= 100 * scene.duration:
        return [f"{where}: its rows are {spacing:g} apart and it ends at {last:g}: are its times milliseconds? the "
                "scene reads them as seconds (divide them by 1000)"]
    if last < scene.duration:
        return [f"{where}: the drive ends at {last:g} s, the scene at {scene.duration:g} s: its last row is held "
                "for the rest"]
    return []


DRIVE_WORDS = {"pmsm": "PMSM drives", "linear": "linear motors"}


def run_label(scene: Scene) -> str:
    """What a run of the scene runs, for its reports' titles: the scene's name and, in brackets, the
    platform (its parameter set and mass set), the drives as run (their kind and drive set, or the
    user's FMU and its legs) and the cueing, read from the scene as compiled (its name alone may say
    other drives than a `--set drive.kind=...` runs)."""
    platform = scene.parameter_set + (f", {scene.mass_set} masses" if scene.parameter_set == "sumnu2015" else "")
    ours = DRIVE_WORDS.get(scene.drive, f"{scene.drive} drives") + (f" ({scene.drive_set})" if scene.drive_set else "")
    users: dict[str, list[int]] = {}
    for leg in LEGS:
        if scene.leg_fmu(leg) is not None:
            users.setdefault(scene.leg_fmu(leg).name, []).append(leg)
    drives = "; ".join(f"the user's {name} on leg{'s' if len(legs) > 1 else ''} {', '.join(map(str, legs))}"
                       for name, legs in users.items())
    if sum(len(legs) for legs in users.values()) < len(LEGS):
        drives = f"{drives}, {ours} on the others" if drives else ours
    cueing = f", {scene.cueing_algorithm} cueing of {Path(str(scene.vehicle)).name}" if scene.vehicle is not None else ""
    return f"{scene.name} [run: {platform}, {drives}{cueing}]"


def drive_fmus(scene: Scene) -> list[Path]:
    """Per leg, the drive FMU: the user's where the scene names one, ours for its kind otherwise."""
    return [scene.leg_fmu(leg) or fmu_path(DRIVES[scene.drive].fmu, fmi=scene.fmi) for leg in LEGS]


def scene_record(scene: Scene, fmus: list[Path] | None = None) -> tuple[list[tuple[str, str]], list[str]]:
    """What the scene records: its [outputs], or by default the drive kind's effort, flow and
    current (the current where every leg's drive FMU has it; fmus: the legs' drive FMUs, if known)."""
    if scene.outputs_drive is not None:
        drive_outputs = scene.outputs_drive
    else:
        has = [variables(fmu) for fmu in set(fmus or drive_fmus(scene))]
        drive_outputs = [n for n in DRIVES[scene.drive].outputs if all(n in found for found in has)]
    return columns(scene.drive, scene.outputs_mechanics, drive_outputs, applied=scene.interface_jacobian,
                   cueing=scene.vehicle is not None)


def scene_values(scene: Scene) -> tuple[dict, dict]:
    """The mechanics' and our drives' parameter values: the platform's set, the envelope's margins
    for its drive kind (params/envelope.toml), the drive set (a drive sized for this platform),
    then the scene's own, which win."""
    drive_values, drive_mechanics = drive_set(scene.drive_set) if scene.drive_set else ({}, {})
    drive_mechanics = {**envelope_margins(scene.parameter_set, scene.drive), **drive_mechanics}
    mechanics_values = scene_mechanics(scene.parameter_set, scene.mass_set, drive_mechanics, scene.mechanics_parameters)
    return mechanics_values, {**drive_values, **(scene.drive_parameters if scene.drive_fmu is None else {})}


def scene_design(scene: Scene, values: tuple[dict, dict] | None = None,
                 fmus: list[Path] | None = None) -> tuple[list[dict], str | None, list[str]]:
    """Per leg, the drive parameters, with a summary of the designed gains and notes on the
    drives of the user's own. Our drives: designed for the platform (tuning = "auto"), or the
    defaults with the PMSM starting to hold its leg (initial.current_q from the static load,
    unless the scene gives it). A drive FMU of the user's own keeps its own parameters (the
    scene's [drive.parameters] where it is the [drive] FMU, and its leg's). Raises SceneError when
    a drive cannot hold its leg (sizing: ours always, a user's by its continuous_limit). values
    and fmus: scene_values and drive_fmus, where already read."""
    mechanics_values, ours = values or scene_values(scene)
    fmus = fmus or drive_fmus(scene)
    plants = leg_plants(mechanics_values)
    legs = [{**({} if leg in scene.leg_fmus else scene.drive_parameters if scene.drive_fmu else ours),
             **scene.leg_parameters.get(leg, {})} for leg in LEGS]
    own = [k for k, leg in enumerate(LEGS) if scene.leg_fmu(leg) is None]  # our drives
    try:
        for k in own:
            check_sizing(scene.drive, [plants[k]], legs[k], leg=k + 1)
    except SizingError as error:
        raise SceneError(f"{scene.document.where('drive.kind')}: drive.kind = "
                         f"{scene.drive!r} on {scene.parameter_set}: {error}") from None
    notes, unchecked = user_drive_notes(scene), []
    for k, leg in enumerate(LEGS):
        fmu = scene.leg_fmu(leg)
        if fmu is None:
            continue
        if leg not in scene.continuous_limit:
            unchecked.append(leg)
            continue
        name = scene.continuous_limit[leg]
        limit = float(legs[k].get(name, variables(fmu)[name].start))
        try:
            check_limit(scene.drive, plants[k], limit, f"{fmu.name}'s {name}", leg)
        except SizingError as error:
            table = f"drive.leg.{leg}" if scene.document.value(f"drive.leg.{leg}", "continuous_limit") else "drive"
            raise SceneError(f"{scene.document.where(f'{table}.continuous_limit')}: {error}") from None
    if unchecked:
        notes.append(f"sizing not checked for legs {', '.join(map(str, unchecked))}: name the parameter that holds "
                     "the drive's continuous torque or force with drive.continuous_limit")
    if scene.tuning != "auto" or not own:
        if scene.drive == "pmsm":
            for k in own:
                if "initial.current_q" not in legs[k]:
                    legs[k]["initial.current_q"] = hold_currents([plants[k]], legs[k])[0]
        return legs, None, notes
    designed = [design(scene.drive, [plants[k]], legs[k])[0] for k in own]
    for k, values in zip(own, designed):
        legs[k] = values
    return legs, summary(scene.drive, designed), notes


def user_drive_notes(scene: Scene) -> list[str]:
    """For the run report: each drive FMU of the user's own, its tool, legs, what fmpy's
    validation says of it and what the master does not do with it."""
    from ..scene.drive_fmu import inspect
    notes = []
    for fmu in dict.fromkeys(f for f in (scene.leg_fmu(leg) for leg in LEGS) if f is not None):
        drive = inspect(fmu)
        legs = [leg for leg in LEGS if scene.leg_fmu(leg) == fmu]
        limits = drive.limits(scene.interface_jacobian)
        notes.append(f"drive FMU {drive.name} ({drive.model}, {drive.tool}) on legs {', '.join(map(str, legs))}"
                     + (f"; switched off: {'; '.join(limits)}" if limits else ""))
        notes += [f"{drive.name}: fmpy's validation: {problem}" for problem in drive.problems]
    return notes


def scene_structure(scene: Scene) -> SystemStructure:
    """The scene's system (compile_scene's), for what needs the system alone (an export, a check)."""
    return compile_scene(scene).structure


def _wire(scene: Scene, legs: list[dict], mechanics_values: dict, fmus: list[Path],
          record: tuple[list[tuple[str, str]], list[str]], algorithm: Algorithm) -> SystemStructure:
    """The scene as a system: FMUs, parameter values (the drives' per leg as designed),
    connections, power bonds, experiment, and the settings (algorithm, step control, recorded
    outputs) as the SSP annotation carries them."""
    structure = platform_structure(scene.drive, mechanics_values, {}, scene_trajectory(scene), leg_values=legs,
                                   name=scene.path.stem, experiment=Experiment(0.0, scene.duration, scene.step),
                                   interface_jacobian=scene.interface_jacobian, drive_fmus=fmus,
                                   cueing_values=guarded_cueing(scene_cueing(scene, mechanics_values), scene.step),
                                   fmi=scene.fmi)
    structure.settings = {**to_strings(algorithm, scene.control), **output_settings(*record, scene.output_interval)}
    return structure


# the cueing FMU's algorithm parameter per [cueing] algorithm
CUEING_ALGORITHMS = {"classical": 1, "mpc": 2}
# the mechanics' limits the cueing FMU takes by the same names (the MPC's envelope: the guard's, the
# joints' tilt less limit.joint_margin)
CUEING_LIMITS = ("leg_length_min", "leg_length_max", "stroke_margin", "leg_velocity", "joint_angle", "leg_acceleration")
# the cueing FMU's guard limits by the scene's [live] keys (the reference's braking where it is held)
CUEING_GUARD_LIMITS = ("velocity_max", "angular_velocity_max", "acceleration_max", "angular_acceleration_max")


def scene_cueing(scene: Scene, mechanics_values: dict) -> dict | None:
    """The cueing FMU's values for a scene with a [motion] vehicle (None without): the vehicle's
    file, the algorithm, the platform's neutral pose (where the cueing returns it), its gravity
    (one for every FMU: the mechanics'), its joints and limits (the MPC's envelope: the mechanics'
    own, its layout as the mechanics computes it), then [cueing.parameters]."""
    if scene.vehicle is None:
        return None
    from ..core import Core, gravity_of, mechanics_value, neutral_pose
    neutral = dict(zip((f"neutral.{a}" for a in POSE), neutral_pose(mechanics_values).tolist()))
    platform = Core().use_start_values(mechanics_values).p
    joints = {f"geometry.{name}[{leg}].{axis}": float(side[leg - 1][k])
              for name, side in (("base_joint", platform.lower_joint), ("platform_joint", platform.upper_joint))
              for leg in LEGS for k, axis in enumerate("xyz")}
    limits = {f"limit.{name}": float(mechanics_value(mechanics_values, f"limit.{name}")) for name in CUEING_LIMITS}
    limits["limit.joint_angle"] -= float(mechanics_value(mechanics_values, "limit.joint_margin"))  # the guard's
    limits.update({f"guard.{key}": float(scene.document.value("live", key)) for key in CUEING_GUARD_LIMITS})
    return {"vehicle.file": scene.vehicle, "algorithm": CUEING_ALGORITHMS[scene.cueing_algorithm], **neutral,
            "gravity": float(np.linalg.norm(gravity_of(mechanics_values))), **joints, **limits,
            "mpc.preview": scene.cueing_preview, **scene.cueing_parameters}


def guarded_cueing(values: dict | None, step: float) -> dict | None:
    """The cueing FMU's values with its guard on (fmu/cueing/guard.c): its pose reference held within
    the platform's envelope (the limits and joints scene_cueing gives it) at the end of each step
    (as Model Exchange at time events a scene's `step` apart: guard.period), in `cosim run` and in
    every tool its system goes to. Every motion-cueing scene runs so."""
    return None if values is None else {"guard.period": step, **values, "guard": True}


def scene_algorithm(scene: Scene) -> Algorithm:
    """The scene's coupling, with the cueing FMU first in a Gauss-Seidel sequence where it has one."""
    algorithm = scene.algorithm
    if scene.vehicle is not None and algorithm.sequence:
        algorithm = replace(algorithm, sequence=("cueing", *algorithm.sequence))
    return algorithm


def model_exchange_plan(compiled: CompiledScene) -> tuple[Plan, str]:
    """The compiled scene's plan as one system of Model Exchange FMUs under one solver (`cosim run
    --me`): no coupling, the reference a co-simulation is judged against; a component without a
    Model Exchange FMU (a user's drive) is one line (UsageError)."""
    from ...engine.monolithic import RELATIVE_TOLERANCE, model_exchange_structure
    model_exchange_structure(compiled.plan.structure)  # every component has a Model Exchange FMU, or one line
    remark = ("run as one Model Exchange FMU of the scene's FMUs (the connections carried inside its derivatives) "
              f"under CVODE (BDF, relative tolerance {RELATIVE_TOLERANCE:g}): no coupling, no macro step")
    if compiled.scene.vehicle is not None:  # the cueing FMU's guard steps at time events
        remark += (f"; the cueing's reference held within the platform's envelope by its guard, stepped at time "
                   f"events {compiled.scene.step:g} s apart (the scene's step)")
    return replace(compiled.plan, model_exchange=True), remark
