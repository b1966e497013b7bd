"""Reads a scene file into a `Scene` (cosim.platform.scene.model): the schema checks every key's
type and range (cosim.platform.scene.schema), this module what a key means beyond them, each
mistake one line naming the file, the line and the full key. The signals become parameters of
the trajectory FMU (cosim.platform.scene.signals), so a scene is FMUs and connections only.

`derive` is what a Scene is made of: its drives (ours, or FMUs of the user's own), the platform's
values, the engine's settings objects (the coupling and the macro-step control with its finer
start and edge windows), the signals and what is recorded.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Mapping

from ...engine.artifacts import fmu_path
from ...engine.checks import ParameterError, capability_problem, check_values, variables
from ...engine.schema import Document, read
from ...engine.settings import Algorithm, EnergyControl, FixedStep, SettingsError, StepControl, StepDoubling
from ..ports import DRIVES, POSE, platform_algorithm
from .drive_fmu import KIND_NAMES, DriveFmu, DriveFmuError, inspect
from .model import Pulse, Ramp, Scene, Signal, Sine, Step
from .schema import CAPACITY, NATIVE_DRIVE, SCHEMA, SceneError

# Step doubling's error scale on what the mechanics hands the drives (leg angles and speeds, or
# lengths and velocities: m, rad, m/s, rad/s) when the scene gives no atol.
DOUBLING_ATOL = 1e-3


def shipped_scenes(folder: str = "scenes") -> list[str]:
    """The names of the shipped scenes (scenes/<name>.toml), which load_scene takes by name (or
    of the shipped sweep files, "sweeps", or studies, "studies")."""
    from ...engine.artifacts import ROOT
    return sorted(p.stem for p in (ROOT / folder).glob("*.toml"))


def shipped(name: str, folder: str = "scenes") -> Path | None:
    """The shipped scene (or sweep file, or study: `folder`) of this name, or None; for a name,
    an install without its data says so in one line (ArtifactMissing)."""
    if Path(name).suffix or len(Path(name).parts) != 1:
        return None
    from ...engine.artifacts import data_dir
    path = data_dir(folder) / f"{name}.toml"
    return path if path.is_file() else None


def load_scene(path: str | Path, overrides: Mapping[str, Any] | None = None,
               given: Mapping[str, str] | None = None) -> Scene:
    """Reads and checks a scene file, or a shipped scene by its name (`meng_eq35`); `overrides`
    sets values at dotted keys of its document first (a sweep's point), checked as if the file
    said them; `given`: how some of them were given ('--set step=-1e-3'), which their errors name
    instead of the file's line."""
    path = Path(path)
    if not path.exists() and path.suffix == "" and len(path.parts) == 1:  # a shipped scene's name
        path = shipped(str(path)) or path
    if not path.exists():
        import difflib
        near = difflib.get_close_matches(path.stem, shipped_scenes(), 1)
        raise SceneError(f"{path}: no such scene file" + (f" (a shipped scene is named {near[0]!r})" if near else ""))
    if path.is_dir():
        raise SceneError(f"{path}: is a folder, not a scene file (the shipped scenes are scenes/*.toml)")
    file = read(SCHEMA, path)
    return Scene(path, file.text, file.data, dict(overrides or {}), dict(given or {}))


def derive(scene: Scene) -> dict[str, Any]:
    """Every derived field of a scene (cosim.platform.scene.model.Scene) from its file and
    overrides; raises SceneError, one line, for anything that cannot run."""
    doc = read(SCHEMA, scene.path, scene.overrides, text=scene.text, data=dict(scene.data), given=scene.given)
    out: dict[str, Any] = {"document": doc, "name": doc.value("scene", "name", scene.path.stem),
                           "duration": float(doc.value("scene", "duration")), "fmi": int(doc.value("scene", "fmi"))}
    out.update(_drives(doc))
    out.update(_platform(doc, out))
    out["trajectory"], out["neutral"] = _signals(doc)
    out["table"], out["interpolation"] = _table(doc), doc.value("trajectory", "interpolation")
    out["vehicle"], out["cueing_parameters"] = _vehicle(doc), _parameters(doc, "cueing", "cueing")
    if "gravity" in out["cueing_parameters"]:
        raise doc.fail('cueing.parameters."gravity"', "is the platform's, one gravity for every FMU: give it as "
                       "the mechanics' environment.gravity_x/y/z in [mechanics.parameters]",
                       out["cueing_parameters"]["gravity"])
    out["head"] = tuple(float(c) for c in doc.value("cueing", "head"))
    out["cueing_algorithm"] = doc.value("cueing", "algorithm")
    out["cueing_preview"] = float(doc.value("cueing", "preview"))
    if "mpc.preview" in out["cueing_parameters"]:
        raise doc.fail('cueing.parameters."mpc.preview"', "is the scene's [cueing] preview: give it there",
                       out["cueing_parameters"]["mpc.preview"])
    if out["vehicle"] is not None and out["cueing_algorithm"] == "mpc":
        _mpc_checks(doc, out["cueing_parameters"], float(doc.value("scene", "step")))
    out["cueing_ranges"] = _cueing_ranges(doc)
    out["cueing_search"] = tuple(int(doc.value("cueing.tune", k)) for k in ("iterations", "population", "seed"))
    out["cueing_judge"] = doc.value("cueing.tune", "judge")
    out["pulses"] = _pulses(doc)
    out["algorithm"], out["control"] = _settings(doc, out["drive"], out["duration"], out["pulses"])
    out["interface_jacobian"] = doc.value("coupling", "interface_jacobian")
    out["outputs_mechanics"] = tuple(doc.value("outputs", "mechanics", ()))
    drive_outputs = doc.value("outputs", "drive")
    out["outputs_drive"] = tuple(drive_outputs) if drive_outputs is not None else None
    interval = doc.value("outputs", "interval")
    out["output_interval"] = float(interval) if interval is not None else None
    _check_capabilities(doc, out)
    if out["neutral"]:
        out["trajectory"] = _at_neutral(doc, out)
    return out


def _drives(doc: Document) -> dict[str, Any]:
    """The drive kind, its tuning and drive set, its parameters, and the drive FMUs of the
    user's own (every leg's, or one leg's) with their continuous limits."""
    top = _user_fmu(doc, "drive")
    legs = doc.family("drive.leg.<i>")
    leg_fmus = {int(leg): found for leg in legs if (found := _user_fmu(doc, f"drive.leg.{leg}")) is not None}
    if top is not None:
        kind = top.kind
        if doc.table("drive").get("kind", kind) != kind:
            raise doc.fail("drive.kind", f"but drive.fmu {top.name} has the {KIND_NAMES[kind]} drive's ports (kind "
                           f"{kind!r}); leave kind out with an fmu", doc.value("drive", "kind"))
    else:
        kind = doc.value("drive", "kind")
    for leg, found in leg_fmus.items():
        if found.kind != kind:
            raise doc.fail(f"drive.leg.{leg}.fmu", f"has the {KIND_NAMES[found.kind]} drive's ports, the other legs' "
                           f"drives are {KIND_NAMES[kind]}: one platform's legs take one kind (the transmission is "
                           "the platform's)", found.name)
    platform = doc.value("mechanics", "parameter_set")
    # a drive on the platform its defaults were designed for keeps them; a swapped one is designed
    tuning = doc.value("drive", "tuning", "defaults" if NATIVE_DRIVE.get(platform) == kind or top else "auto")
    if tuning == "auto" and (top is not None or len(leg_fmus) == 6):
        raise doc.fail("drive.tuning", "designs the loops of our drives (pmsm_drive, linear_motor) only; a drive FMU "
                       "of your own keeps its own gains", tuning)
    from .parameter_sets import PARAMS, drive_set_name
    drive_set = doc.value("drive", "parameter_set", drive_set_name(platform, kind)
                          if NATIVE_DRIVE.get(platform) != kind else None)
    drive_set = None if drive_set == "none" else drive_set
    drive_sets = [p.stem for p in sorted(PARAMS.glob("*_*.toml"))]  # <platform>_<drive kind>.toml
    if drive_set is not None and drive_set not in drive_sets:
        raise doc.fail("drive.parameter_set", f"is not one of the project's drive sets (known: "
                       f"{', '.join(drive_sets) or 'none'}, or 'none'; a platform's set goes in [mechanics])", drive_set)
    parameters = _parameters(doc, "drive", top.path if top else DRIVES[kind].fmu)
    leg_parameters = {int(leg): _parameters(doc, f"drive.leg.{leg}", (leg_fmus.get(int(leg)) or top).path
                                            if (leg_fmus.get(int(leg)) or top) else DRIVES[kind].fmu) for leg in legs}
    return {"drive": kind, "tuning": tuning, "drive_set": drive_set, "drive_parameters": parameters,
            "drive_fmu": top.path if top else None, "leg_fmus": {leg: f.path for leg, f in leg_fmus.items()},
            "leg_parameters": leg_parameters, "continuous_limit": _limits(doc, top, leg_fmus)}


def _user_fmu(doc: Document, table: str) -> DriveFmu | None:
    """A user's drive FMU named at <table>.fmu, inspected (cosim.platform.scene.drive_fmu), or None."""
    given = doc.value(table, "fmu")
    if given is None:
        return None
    try:
        return inspect(doc.path.parent / given)
    except DriveFmuError as error:
        raise doc.fail(f"{table}.fmu", str(error), given) from None


def _parameters(doc: Document, table: str, fmu: str | Path) -> dict[str, Any]:
    """[<table>.parameters] checked against the FMU's modelDescription (ours by name, or a user's
    by path): names, types, bounds."""
    given = doc.value(table, "parameters", {})
    try:
        check_values(table, fmu if isinstance(fmu, Path) else fmu_path(fmu), given)
    except ParameterError as error:
        where = doc.where(f'{table}.parameters."{error.variable}"')
        raise SceneError(f"{where}: {table}.parameters.\"{error.variable}\" = {error.value!r}: "
                         f"{error.reason} ({error.fmu})") from None
    return dict(given)


def _limits(doc: Document, top: DriveFmu | None, leg_fmus: dict[int, DriveFmu]) -> dict[int, str]:
    """Per leg, the parameter of its own drive FMU that holds its continuous torque or force."""
    limits = {}
    for leg in range(1, 7):
        table = f"drive.leg.{leg}" if doc.value(f"drive.leg.{leg}", "continuous_limit") is not None else "drive"
        name = doc.value(table, "continuous_limit")
        if name is None:
            continue
        own = leg_fmus.get(leg, top)
        if own is None:
            if table == "drive" and leg_fmus:
                continue  # [drive]'s limit is for the legs that take its FMU
            raise doc.fail(f"{table}.continuous_limit", "our drives' limits are known (the sizing check reads them); "
                           "continuous_limit names the parameter of a drive FMU of your own", name)
        if name not in own.parameters:
            raise doc.fail(f"{table}.continuous_limit", f"is not a Real parameter of {own.name} (it has: "
                           f"{', '.join(sorted(own.parameters)) or 'none'})", name)
        limits[leg] = name
    return limits


def _platform(doc: Document, drives: Mapping[str, Any]) -> dict[str, Any]:
    """The platform's parameter set, mass set and the mechanics FMU's values the scene gives."""
    from .parameter_sets import read_parameter_set
    platform = doc.value("mechanics", "parameter_set")
    mass_set = doc.value("mechanics", "mass_set")
    known = tuple(read_parameter_set(platform).get("mass_sets", {"heavy": None}))
    if mass_set not in known:
        raise doc.fail("mechanics.mass_set", f"is not a mass set of {platform} ({', '.join(map(repr, known))})",
                       mass_set)
    return {"parameter_set": platform, "mass_set": mass_set,
            "mechanics_parameters": _parameters(doc, "mechanics", "mechanics")}


def _signals(doc: Document) -> tuple[dict[str, Signal], tuple[str, ...]]:
    """Per DOF its signal, and the DOFs whose offset is the platform's neutral pose (set later)."""
    signals, neutral = {}, []
    for dof, spec in doc.family("trajectory.<dof>").items():
        offset = spec.get("offset", 0.0)
        if offset == "neutral":
            neutral.append(dof)
        entries = {kind: tuple(cls(**{k: float(v) for k, v in entry.items()}) for entry in spec.get(kind, []))
                   for kind, cls in (("sines", Sine), ("steps", Step), ("ramps", Ramp))}
        signals[dof] = Signal(0.0 if offset == "neutral" else float(offset), **entries)
    return signals, tuple(neutral)


def _table(doc: Document) -> Path | None:
    given = doc.value("trajectory", "table")
    if given is None:
        return None
    if not (doc.path.parent / given).is_file():
        raise doc.fail("trajectory.table", "no such file (relative to the scene's folder)", given)
    return (doc.path.parent / given).resolve()


def _vehicle(doc: Document) -> Path | None:
    """[motion] vehicle: the recorded motion cueing turns into the pose reference, which then
    comes from nowhere else."""
    given = doc.value("motion", "vehicle")
    if given is None:
        if doc.table("cueing"):
            raise doc.fail("cueing", "tunes the motion cueing of a [motion] vehicle, and this scene has none")
        return None
    if not (doc.path.parent / given).is_file():
        raise doc.fail("motion.vehicle", "no such file (relative to the scene's folder)", given)
    posed = [f"trajectory.{dof}" for dof in doc.family("trajectory.<dof>")] + \
        (["trajectory.table"] if doc.value("trajectory", "table") is not None else [])
    if posed:
        raise doc.fail("motion.vehicle", f"gives the pose reference through motion cueing, and [{posed[0]}] gives one "
                       "too: keep one", given)
    return (doc.path.parent / given).resolve()


def _mpc_checks(doc: Document, given: Mapping[str, Any], step: float) -> None:
    """What the MPC cueing would take silently and cannot mean: a solve period that is no whole
    number of the scene's steps (the solves would drift against the steps that carry them), and
    both weights of what is felt 0 (nothing to be close to: the platform stands still)."""
    defaults = {v.name: v.start for v in variables(fmu_path("cueing")).values()}
    value = lambda name: float(given.get(name, defaults[name]))  # noqa: E731
    period = value("mpc.period")
    if abs(period / step - round(period / step)) > 1e-9 * period / step or round(period / step) < 1:
        key = 'cueing.parameters."mpc.period"' if "mpc.period" in given else "scene.step"
        raise doc.fail(key, f"the MPC solves every mpc.period = {period:g} s, which is no whole number of the scene's "
                       f"steps of {step:g} s: make it one", given.get("mpc.period", step))
    tracked = ("mpc.weight.specific_force", "mpc.weight.angular_rate")  # what is felt; the rest hold it back
    if all(value(name) == 0.0 for name in tracked):
        zeroed = next((name for name in tracked if name in given), tracked[0])
        raise doc.fail(f'cueing.parameters."{zeroed}"', "mpc.weight.specific_force and mpc.weight.angular_rate are "
                       "both 0: the MPC would have nothing felt to bring close and hold the platform still (give one "
                       "a weight > 0)", 0.0)


def _cueing_ranges(doc: Document) -> dict[str, tuple[float, float]] | None:
    """[cueing.tune] ranges: Real parameters of the cueing FMU, each [low, high] with both ends
    values the FMU takes (checked against its modelDescription) and low < high."""
    given = doc.value("cueing.tune", "ranges")
    if given is None:
        return None
    fmu = variables(fmu_path("cueing"))
    out = {}
    for name, span in given.items():
        key = f'cueing.tune.ranges."{name}"'
        variable = fmu.get(name)
        if variable is None or variable.causality != "parameter" or variable.type != "Real":
            raise doc.fail(key, "is not a Real parameter of the cueing FMU", name)
        if name == "gravity":
            raise doc.fail(key, "is the platform's gravity, not a cueing parameter to tune", name)
        if not (isinstance(span, list) and len(span) == 2 and all(isinstance(v, (int, float)) and
                                                                  not isinstance(v, bool) for v in span)):
            raise doc.fail(key, "must be [low, high]", span)
        try:
            check_values("cueing", fmu_path("cueing"), {name: float(span[0])})
            check_values("cueing", fmu_path("cueing"), {name: float(span[1])})
        except ParameterError as error:
            raise doc.fail(key, f"{error.reason} at an end", span) from None
        if not span[0] < span[1]:
            raise doc.fail(key, "must run from a value to a larger one", span)
        out[name] = (float(span[0]), float(span[1]))
    if not out:
        raise doc.fail("cueing.tune.ranges", "names no parameter", given)
    return out


def _pulses(doc: Document) -> tuple[Pulse, ...]:
    pulses = tuple(Pulse(p["component"], float(p["value"]), float(p["start"]), float(p["end"]), p.get("frame", "base"))
                   for p in doc.value("load", "pulses", []))
    for k, pulse in enumerate(pulses, start=1):
        if sum(p.component == pulse.component for p in pulses[:k]) > CAPACITY["pulses"]:
            raise doc.fail(f"load.pulses[{k}].component", f"one pulse too many on it: the trajectory FMU holds "
                           f"{CAPACITY['pulses']} per component", pulse.component)
    return pulses


def _settings(doc: Document, drive: str, duration: float, pulses: tuple[Pulse, ...]) -> tuple[Algorithm, StepControl]:
    """The scene's coupling and macro-step control: the engine's settings objects (the SSP
    annotation and the OSP export carry them), each refusal of theirs named at its key. Step
    doubling measures the error on the mechanics' outputs to the drives; a fixed step takes its
    finer start and the edge windows after each load pulse's edges."""
    order = doc.value("coupling", "order")
    if doc.value("coupling", "interface_jacobian") and order == 0:
        raise doc.fail("coupling.interface_jacobian", "needs coupling.order 1 or 2: with inputs held over the step the "
                       "speed a drive was given is off by O(h), and the slope's correction then carries energy its "
                       "drive did not account for (more than the divergence monitor allows)", True)
    try:
        algorithm = dataclasses.replace(platform_algorithm(drive, doc.value("coupling", "algorithm"), int(order)),
                                        threads=int(doc.value("coupling", "threads")),
                                        feedthrough=doc.value("coupling", "feedthrough"))
        return algorithm, _control(doc, duration, pulses)
    except SettingsError as error:  # what the settings objects refuse beyond the schema's checks
        key = {None: "scene.step", "step": "scene.step", "kind": "coupling.algorithm",
               "windows": "coupling.edge_time"}.get(error.setting, f"coupling.{error.setting}")
        raise doc.fail(key, f"is refused: {error}") from None


def _control(doc: Document, duration: float, pulses: tuple[Pulse, ...]) -> StepControl:
    """The macro-step control."""
    step = float(doc.value("scene", "step"))
    if step > duration:
        raise doc.fail("scene.step", f"is longer than the scene's duration ({duration:g} s): the run would not take "
                       "one whole step", step)
    given = {key: float(doc.value("coupling", key)) for key in ("rtol", "h_min", "h_max")
             if doc.value("coupling", key) is not None}
    atol = doc.value("coupling", "atol")
    name = doc.value("coupling", "step_control")
    if name == "doubling":
        return StepDoubling(step, atol={"mechanics": float(atol or DOUBLING_ATOL)}, **given)
    if name == "energy":
        return EnergyControl(step, **given, **({"atol": float(atol)} if atol else {}))
    startup_time, startup_step = float(doc.value("coupling", "startup_time")), doc.value("coupling", "startup_step")
    edge_time = float(doc.value("coupling", "edge_time"))
    if startup_time > 0 and startup_step is None:
        raise doc.fail("coupling.startup_time", "needs startup_step, the finer step of the start", startup_time)
    if startup_time > 0 and not startup_step > 0:
        raise doc.fail("coupling.startup_step", "must be a positive number (the finer step of the start)",
                       startup_step)
    if edge_time > 0 and not startup_time > 0:
        raise doc.fail("coupling.edge_time", "needs startup_time and startup_step (the finer step it is taken at)",
                       edge_time)
    if startup_time > 0 and startup_step < step:
        # the first startup_time seconds, rounded up to whole steps, at the largest whole fraction
        # of the step that is no longer than startup_step (a run at a finer step needs no finer start)
        per = math.ceil(step / startup_step - 1e-9)
        steps = math.ceil(startup_time / step - 1e-9)
        # and the edge_time after each load pulse's edges, where the drives answer a jumping load
        windows = tuple((edge, edge + edge_time) for pulse in pulses for edge in (pulse.start, pulse.end)
                        if edge_time > 0.0 and edge < duration)
        return FixedStep(step, steps * step, step / per, windows)
    return FixedStep(step)


def _check_capabilities(doc: Document, scene: Mapping[str, Any]) -> None:
    """What the user's drive FMUs cannot do limits the step control: refused at its key."""
    fmus = [scene["drive_fmu"], *scene["leg_fmus"].values()]
    for path in dict.fromkeys(f for f in fmus if f is not None):
        legs = sum((scene["leg_fmus"].get(i, scene["drive_fmu"])) == path for i in range(1, 7))
        reason = capability_problem(path, scene["control"], legs)
        if reason:
            key = next((k for k in ("step_control", "edge_time", "startup_time")
                        if k in doc.table("coupling")), "step_control")
            where = "drive.fmu" if path == scene["drive_fmu"] else \
                f"drive.leg.{min(i for i, f in scene['leg_fmus'].items() if f == path)}.fmu"
            raise doc.fail(f"coupling.{key}", f"is refused: {path.name} ({where}) {reason}")


def _at_neutral(doc: Document, scene: Mapping[str, Any]) -> dict[str, Signal]:
    """The signals with the offsets given as "neutral" at the platform's neutral pose."""
    from ..core import neutral_pose
    from .parameter_sets import drive_set, scene_mechanics
    try:
        pose = neutral_pose(scene_mechanics(scene["parameter_set"], scene["mass_set"],
                                            drive_set(scene["drive_set"])[1] if scene["drive_set"] else None,
                                            scene["mechanics_parameters"]))
    except (KeyError, ValueError) as error:
        raise doc.fail(f"trajectory.{scene['neutral'][0]}.offset", f"no neutral pose ({error})", "neutral") from None
    return {dof: dataclasses.replace(signal, offset=float(pose[POSE.index(dof)])) if dof in scene["neutral"] else signal
            for dof, signal in scene["trajectory"].items()}
