"""Scenes: one TOML file describes a run (see scenes/ for the shipped ones).

    [scene]       name, duration [s], step [s]
    [drive]       kind = "pmsm" | "linear" (the one line that swaps the drives), tuning = "auto" (the
                  loops designed for this platform; the default for a drive swapped onto another
                  platform) | "defaults" (the FMU's, the default on the drive's own platform);
                  parameter_set = "sumnu2015_pmsm" | ... | "none" (a drive sized for another paper's
                  platform, params/<platform>_<kind>.toml; the default for a swapped drive when the
                  project has one); [drive.parameters] (explicit values win over the set and the design);
                  fmu = "my_drive.fmu" (relative to the scene: a drive FMU of your own that keeps the
                  drive ports of INTERFACES.md; its kind comes from its ports, its parameters are its
                  own, checked against it, and it keeps its own gains), continuous_limit = "<its
                  parameter>" (the continuous torque or force the sizing check holds it to)
    [drive.leg.<i>]  i in 1..6: fmu, parameters = {...}, continuous_limit: leg i's own drive FMU (the
                  same kind as the others), or parameters on top of [drive.parameters]
    [mechanics]   parameter_set = "meng2010" | "sumnu2015", mass_set; [mechanics.parameters]
    [coupling]    algorithm = "gauss-seidel" | "jacobi", order = 0 | 1 | 2,
                  step_control = "fixed" (default: scene.step throughout) | "doubling" (local error by
                  step doubling, with rollback) | "energy" (ECCO: the power bonds' energy residual),
                  rtol, atol, h_min, h_max (of the adaptive controls; atol in m and rad of the legs'
                  outputs for doubling, in J for energy); startup_time, startup_step (fixed: the
                  first startup_time seconds at the finer startup_step, for the start-up shock);
                  edge_time (fixed, with startup_step: the edge_time seconds after each load pulse's
                  edges at startup_step too, for the drives' answer to a jumping load);
                  threads = 2 (the drives of a Gauss-Seidel step on two threads, bit for bit the
                  same: faster only while the second core is free); interface_jacobian = true (each
                  drive's slope d effort / d flow goes to the mechanics with the flow the drive saw:
                  the drives' damping integrated implicitly, stable at longer steps); feedthrough =
                  true (after each macro step, outputs that depend on inputs at the same communication
                  point, such as the mechanics' leg references on pose_ref, are read again with those
                  inputs' new values, as OMSimulator does)
    [trajectory]  table = "file.csv" (relative to the scene; columns time and any of x, y, z, roll,
                  pitch, yaw, added to the signals below), interpolation = "cubic" | "linear"
    [trajectory.<dof>]  dof in x, y, z, roll, pitch, yaw: offset (a number, or "neutral": the
                  platform's neutral pose, computed from its geometry), sines = [{amplitude, frequency [Hz],
                  phase [rad]}] (up to 3), steps = [{time, height}] (2), ramps = [{start, end, slope}] (2)
    [load]        pulses = [{component = "force.z" | ..., value, start, end, frame = "base" | "platform"}]
                  (2 per component; "platform": a follower load along the platform's own axes)
    [outputs]     mechanics = [...] (mechanics outputs recorded besides pose and pose_ref),
                  drive = [...] (per drive; default: effort, speed or velocity, current),
                  interval [s] (write results every interval; default: every macro step)

The signals become parameters of the trajectory FMU (fmu/trajectory/), so a scene is FMUs and
connections only.

A wrong key or value is reported with its name and the line it stands on.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...engine.errors import InputError
from ...engine.tomlfile import line_of, read
from ...engine.settings import Algorithm, EnergyControl, FixedStep, SettingsError, StepControl, StepDoubling
from .drive_fmu import KIND_NAMES
from ..ports import DRIVES, POSE
from ..run.system import default_algorithm

FRAMES = {"base": 1, "platform": 2}  # as the trajectory FMU's pulse[k].frame numbers them
WRENCH_COMPONENTS = ("force.x", "force.y", "force.z", "torque.x", "torque.y", "torque.z")


class SceneError(InputError):
    """A scene file that cannot be run: the message names the file, the key and its line."""


@dataclass
class Sine:
    amplitude: float
    frequency: float
    phase: float = 0.0


@dataclass
class Step:
    time: float
    height: float


@dataclass
class Ramp:
    start: float
    end: float
    slope: float


@dataclass
class Signal:
    offset: float = 0.0
    sines: list[Sine] = field(default_factory=list)
    steps: list[Step] = field(default_factory=list)
    ramps: list[Ramp] = field(default_factory=list)


@dataclass
class Pulse:
    component: str
    value: float
    start: float
    end: float
    frame: str = "base"  # or "platform": a follower load that turns with the platform


@dataclass
class Scene:
    path: Path
    name: str
    duration: float
    step: float
    drive: str
    drive_parameters: dict[str, Any]
    parameter_set: str
    mass_set: str
    mechanics_parameters: dict[str, Any]
    algorithm: str
    order: int
    trajectory: dict[str, Signal]
    pulses: list[Pulse]
    table: Path | None = None
    interpolation: str = "cubic"
    step_control: str = "fixed"
    rtol: float | None = None  # None: the step control's default (cosim.engine.settings)
    atol: float | None = None
    h_min: float | None = None
    h_max: float | None = None
    outputs_mechanics: list[str] = field(default_factory=list)
    outputs_drive: list[str] | None = None  # None: the drive kind's default
    output_interval: float | None = None
    threads: int = 1  # 2: the six drives of a Gauss-Seidel step on two threads (a free core needed)
    startup_time: float = 0.0  # [s] the first seconds at the finer startup_step (fixed step control)
    startup_step: float = 0.0
    edge_time: float = 0.0  # [s] after each load pulse's edges at startup_step too
    interface_jacobian: bool = False  # the drives' slopes d effort / d flow wired to the mechanics
    feedthrough: bool = False  # outputs that depend on inputs read again at each communication point
    tuning: str = "defaults"  # or "auto": the drives' loops designed for this platform (cosim.platform.run.tuning)
    drive_set: str | None = None  # params/<name>.toml: a drive sized for this platform (parameter_sets.drive_set)
    overrides: dict[str, Any] = field(default_factory=dict)  # the dotted keys load_scene set over the file
    drive_fmu: Path | None = None  # [drive] fmu: a drive FMU of the user's own on every leg (None: ours)
    leg_fmus: dict[int, Path] = field(default_factory=dict)  # [drive.leg.<i>] fmu: leg i's own drive FMU
    leg_parameters: dict[int, dict[str, Any]] = field(default_factory=dict)  # [drive.leg.<i>] parameters
    continuous_limit: dict[int, str] = field(default_factory=dict)  # per leg: the user's drive's parameter
    #                                      that holds its continuous torque or force, for the sizing check

    def leg_fmu(self, leg: int) -> Path | None:
        """Leg `leg`'s (1..6) drive FMU when it is not ours."""
        return self.leg_fmus.get(leg, self.drive_fmu)


SCHEMA: dict[str, set[str]] = {
    "": {"scene", "drive", "mechanics", "coupling", "trajectory", "load", "outputs"},
    "scene": {"name", "duration", "step"},
    "drive": {"kind", "parameters", "tuning", "parameter_set", "fmu", "continuous_limit", "leg"},
    "drive.leg.*": {"fmu", "parameters", "continuous_limit"},
    "mechanics": {"parameter_set", "mass_set", "parameters"},
    "coupling": {"algorithm", "order", "step_control", "rtol", "atol", "h_min", "h_max", "startup_time",
                 "startup_step", "edge_time", "threads", "interface_jacobian", "feedthrough"},
    "trajectory": {*POSE, "table", "interpolation"},
    "trajectory.*": {"offset", "sines", "steps", "ramps"},
    "load": {"pulses"},
    "outputs": {"mechanics", "drive", "interval"},
}
ITEM_KEYS = {"sines": {"amplitude", "frequency", "phase"}, "steps": {"time", "height"},
             "ramps": {"start", "end", "slope"}, "pulses": {"component", "value", "start", "end", "frame"}}
CAPACITY = {"sines": 3, "steps": 2, "ramps": 2, "pulses": 2}  # what the trajectory FMU holds
STEP_CONTROLS = ("fixed", "doubling", "energy")
NATIVE_DRIVE = {"meng2010": "pmsm", "sumnu2015": "linear"}  # the drive each platform's papers use


def key_path(key: str) -> list[str]:
    """The tables and key a dotted TOML key names: 'drive.parameters."motor.resistance"' ->
    ['drive', 'parameters', 'motor.resistance']. Raises ValueError for text that is not a key."""
    try:
        data = tomllib.loads(f"{key} = 0")
    except tomllib.TOMLDecodeError:
        raise ValueError(f"{key!r} is not a TOML key (quote a name with dots: 'drive.parameters.\"motor.resistance\"')") from None
    parts = []
    while isinstance(data, dict):
        (name, data), = data.items()
        parts.append(name)
    return parts


def with_overrides(data: dict, overrides: dict[str, Any]) -> dict:
    """A copy of a scene's TOML document with values set at dotted keys (tables made as needed)."""
    import copy
    data = copy.deepcopy(data)
    for key, value in overrides.items():
        *tables, name = key_path(key)
        table = data
        for t in tables:
            table = table.setdefault(t, {})
            if not isinstance(table, dict):
                raise ValueError(f"{key!r}: {t!r} is a value in the scene, not a table")
        table[name] = value
    return data


def shipped_scenes(folder: str = "scenes") -> list[str]:
    """The names of the shipped scenes (scenes/<name>.toml), which load_scene takes by name (or
    of the shipped sweep files: folder "sweeps")."""
    from ...engine.artifacts import ROOT
    return sorted(p.stem for p in (ROOT / folder).glob("*.toml"))


def shipped(name: str, folder: str = "scenes") -> Path | None:
    """The shipped scene (or sweep file: folder "sweeps") of this name, or None; for a name, an
    install without its data says so in one line (ArtifactMissing)."""
    if Path(name).suffix or len(Path(name).parts) != 1:
        return None
    from ...engine.artifacts import data_dir
    path = data_dir(folder) / f"{name}.toml"
    return path if path.is_file() else None


def load_scene(path: str | Path, overrides: dict[str, Any] | None = None) -> Scene:
    """Reads and checks a scene file, or a shipped scene by its name (`meng_eq35`); `overrides`
    sets values at dotted keys of its document first (a sweep's point), checked as if the file
    said them."""
    path = Path(path)
    if not path.exists() and path.suffix == "" and len(path.parts) == 1:  # a shipped scene's name
        path = shipped(str(path)) or path
    if not path.exists():
        import difflib
        near = difflib.get_close_matches(path.stem, shipped_scenes(), 1)
        raise SceneError(f"{path}: no such scene file" + (f" (a shipped scene is named {near[0]!r})" if near else ""))
    if path.is_dir():
        raise SceneError(f"{path}: is a folder, not a scene file (the shipped scenes are scenes/*.toml)")
    text, data = read(path, "scene file", SceneError)
    if overrides:
        data = with_overrides(data, overrides)

    def fail(table: str, key: str, problem: str) -> SceneError:
        where = f"{table}.{key}" if table else key
        return SceneError(f"{path}:{line_of(text, table, key)}: '{where}' {problem}")

    def check_keys(table: str, values: dict, allowed: set[str]) -> None:
        if not isinstance(values, dict):
            raise fail("", table, f"= {values!r} must be a table")
        for key in values:
            if key not in allowed:
                raise fail(table, key, f"is not a known key (known here: {', '.join(sorted(allowed))})")

    def number(table: str, values: dict, key: str, default: float | None = None, positive: bool = False) -> float:
        if key not in values:
            if default is None:
                raise SceneError(f"{path}: '{table}.{key}' is missing")
            return default
        value = values[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or (positive and not value > 0):
            raise fail(table, key, f"= {value!r} must be a {'positive ' if positive else ''}number")
        if not math.isfinite(value):
            raise fail(table, key, f"= {value!r} must be a finite number")
        return float(value)

    def choice(table: str, values: dict, key: str, default: str, options, what: str) -> str:
        value = values.get(key, default)
        if not isinstance(value, str) or value not in options:
            raise fail(table, key, f"= {value!r} {what} ({', '.join(map(repr, options))})")
        return value

    def parameters(table: str, values: dict, fmu: str | Path) -> dict[str, Any]:
        """[<table>.parameters] checked against the FMU's modelDescription (ours by name, or a
        user's by path): names, types, bounds."""
        given = values.get("parameters", {})
        if not isinstance(given, dict):
            raise fail(table, "parameters", f"= {given!r} must be a table of FMU variable = value")
        from ...engine.artifacts import fmu_path
        from ...engine.checks import ParameterError, check_values
        try:
            check_values(table, fmu if isinstance(fmu, Path) else fmu_path(fmu), given)
        except ParameterError as error:
            raise SceneError(f"{path}:{line_of(text, f'{table}.parameters', error.variable)}: {table}.parameters."
                             f'"{error.variable}" = {error.value!r}: {error.reason} ({error.fmu})') from None
        return dict(given)

    def items(table: str, values: dict, key: str, kind) -> list:
        out = []
        if not isinstance(values.get(key, []), list):
            raise fail(table, key, f"= {values[key]!r} must be a list of inline tables ({', '.join(sorted(ITEM_KEYS[key]))})")
        if key != "pulses" and len(values.get(key, [])) > CAPACITY[key]:
            raise fail(table, key, f"has {len(values[key])} entries; the trajectory FMU holds {CAPACITY[key]}")
        for entry in values.get(key, []):
            if not isinstance(entry, dict):
                raise fail(table, key, "must be a list of inline tables")
            check_keys(table, entry, ITEM_KEYS[key])
            try:
                out.append(kind(**entry))
            except TypeError:
                raise fail(table, key, f"entries need {', '.join(sorted(ITEM_KEYS[key]))}") from None
        return out

    def drive_fmu(table: str, values: dict):
        """A user's drive FMU named at <table>.fmu, inspected (cosim.platform.scene.drive_fmu), or None."""
        given = values.get("fmu")
        if given is None:
            return None
        if not isinstance(given, str):
            raise fail(table, "fmu", f"= {given!r} must be the path of a drive FMU (relative to the scene)")
        from .drive_fmu import DriveFmuError, inspect
        try:
            return inspect(path.parent / given)
        except DriveFmuError as error:
            raise fail(table, "fmu", f"= {given!r}: {error}") from None

    check_keys("", data, SCHEMA[""])
    for table in ("scene", "drive", "mechanics", "coupling", "trajectory", "load", "outputs"):
        if not isinstance(data.get(table, {}), dict):
            raise fail("", table, f"= {data[table]!r} must be a table ([{table}])")
        check_keys(table, data.get(table, {}), SCHEMA[table])
    scene, drive, mechanics = data.get("scene", {}), data.get("drive", {}), data.get("mechanics", {})
    coupling = data.get("coupling", {})
    top, legs = drive_fmu("drive", drive), drive.get("leg", {})
    if not isinstance(legs, dict) or not all(isinstance(v, dict) for v in legs.values()):
        raise fail("drive", "leg", "must be tables [drive.leg.<i>] for legs i = 1..6")
    for leg, values in legs.items():
        if leg not in {str(i) for i in range(1, 7)}:
            raise fail("drive", "leg", f"has a table for leg {leg!r}; the legs are 1..6 ([drive.leg.3])")
        check_keys(f"drive.leg.{leg}", values, SCHEMA["drive.leg.*"])
    leg_fmus = {int(leg): found for leg, values in legs.items()
                if (found := drive_fmu(f"drive.leg.{leg}", values)) is not None}
    if top is not None:
        kind = top.kind
        if drive.get("kind", kind) != kind:
            raise fail("drive", "kind", f"= {drive['kind']!r}, but drive.fmu {top.name} has the {KIND_NAMES[kind]} "
                       f"drive's ports (kind {kind!r}); leave kind out with an fmu")
    else:
        kind = choice("drive", drive, "kind", "pmsm", tuple(DRIVES), "is not a drive kind")
    for leg, found in leg_fmus.items():
        if found.kind != kind:
            raise fail(f"drive.leg.{leg}", "fmu", f"= {found.name} has the {KIND_NAMES[found.kind]} drive's ports, the "
                       f"other legs' drives are {KIND_NAMES[kind]}: one platform's legs take one kind (the "
                       "transmission is the platform's)")
    parameter_set = choice("mechanics", mechanics, "parameter_set", "meng2010", ("meng2010", "sumnu2015"),
                           "is not a platform's parameter set")
    # a drive on the platform its defaults were designed for keeps them; a swapped one is designed
    tuning = drive.get("tuning", "defaults" if NATIVE_DRIVE.get(parameter_set) == kind or top else "auto")
    if tuning not in ("auto", "defaults"):
        raise fail("drive", "tuning", f"= {tuning!r}: use 'auto' (designed for this platform) or 'defaults'")
    if tuning == "auto" and (top is not None or len(leg_fmus) == 6):
        raise fail("drive", "tuning", "= 'auto' designs the loops of our drives (pmsm_drive, linear_motor) only; a "
                   "drive FMU of your own keeps its own gains")
    from .parameter_sets import PARAMS, drive_set_name
    drive_set = drive.get("parameter_set", drive_set_name(parameter_set, kind)
                          if NATIVE_DRIVE.get(parameter_set) != kind else None)
    if drive_set == "none":
        drive_set = None
    drive_sets = [p.stem for p in sorted(PARAMS.glob("*_*.toml"))]  # <platform>_<drive kind>.toml
    if drive_set is not None and (not isinstance(drive_set, str) or drive_set not in drive_sets):
        known = ", ".join(drive_sets) or "none"
        raise fail("drive", "parameter_set", f"= {drive_set!r} is not one of the project's drive sets (known: {known}, "
                   "or 'none'; a platform's set goes in [mechanics])")
    algorithm = coupling.get("algorithm", "gauss-seidel")
    if algorithm not in ("gauss-seidel", "jacobi"):
        raise fail("coupling", "algorithm", f"= {algorithm!r}: use 'gauss-seidel' or 'jacobi'")
    order = coupling.get("order", 1)
    if not isinstance(order, int) or isinstance(order, bool) or order not in (0, 1, 2):
        raise fail("coupling", "order", f"= {order!r}: use 0, 1 or 2")

    step_control = coupling.get("step_control", "fixed")
    if step_control not in STEP_CONTROLS:
        raise fail("coupling", "step_control", f"= {step_control!r}: use {', '.join(map(repr, STEP_CONTROLS))}")
    tolerances = {key: number("coupling", coupling, key, positive=True) for key in ("rtol", "h_min", "h_max")
                  if key in coupling}
    atol = number("coupling", coupling, "atol", positive=True) if "atol" in coupling else None
    threads = coupling.get("threads", 1)
    if not isinstance(threads, int) or isinstance(threads, bool) or threads not in (1, 2):
        raise fail("coupling", "threads", f"= {threads!r}: use 1, or 2 to step the drives on two threads")
    feedthrough = coupling.get("feedthrough", False)
    if not isinstance(feedthrough, bool):
        raise fail("coupling", "feedthrough", f"= {feedthrough!r}: use true or false")
    interface_jacobian = coupling.get("interface_jacobian", False)
    if not isinstance(interface_jacobian, bool):
        raise fail("coupling", "interface_jacobian", f"= {interface_jacobian!r}: use true or false")
    if interface_jacobian and order == 0:
        raise fail("coupling", "interface_jacobian", "= true needs coupling.order 1 or 2: with inputs held over the "
                   "step the speed a drive was given is off by O(h), and the slope's correction then carries "
                   "energy its drive did not account for (more than the divergence monitor allows)")
    startup = {key: number("coupling", coupling, key) for key in ("startup_time", "startup_step") if key in coupling}
    for key, value in startup.items():
        if value < 0:
            raise fail("coupling", key, f"= {value!r} must not be negative (startup_time = 0: no finer start)")
    if startup.get("startup_time", 0.0) == 0.0:
        startup = {}  # no finer start
    elif "startup_step" not in startup:
        raise fail("coupling", "startup_time", "needs startup_step, the finer step of the start")
    elif not startup["startup_step"] > 0:
        raise fail("coupling", "startup_step", f"= {startup['startup_step']!r} must be a positive number (the finer "
                   "step of the start)")
    if "edge_time" in coupling:
        startup["edge_time"] = number("coupling", coupling, "edge_time")
        if startup["edge_time"] < 0 or ("startup_step" not in startup and startup["edge_time"] > 0):
            raise fail("coupling", "edge_time", f"= {startup['edge_time']!r} must not be negative, and needs "
                       "startup_time and startup_step (the finer step it is taken at)")

    trajectory = {}
    signals = dict(data.get("trajectory", {}))
    table_file, interpolation = signals.pop("table", None), signals.pop("interpolation", "cubic")
    if table_file is not None:
        if not isinstance(table_file, str) or not (path.parent / table_file).is_file():
            raise fail("trajectory", "table", f"= {table_file!r}: no such file (relative to the scene's folder)")
        table_file = (path.parent / table_file).resolve()
    if interpolation not in ("cubic", "linear"):
        raise fail("trajectory", "interpolation", f"= {interpolation!r}: use 'cubic' or 'linear'")
    at_neutral: list[str] = []
    for dof, spec in signals.items():
        table = f"trajectory.{dof}"
        check_keys(table, spec, SCHEMA["trajectory.*"])
        neutral = spec.get("offset") == "neutral"  # the platform's neutral pose, computed below
        offset = 0.0 if neutral else number(table, spec, "offset", 0.0)
        if neutral:
            at_neutral.append(dof)
        trajectory[dof] = Signal(offset, items(table, spec, "sines", Sine), items(table, spec, "steps", Step),
                                 items(table, spec, "ramps", Ramp))
    pulses = items("load", data.get("load", {}), "pulses", Pulse)
    for pulse in pulses:
        if pulse.component not in WRENCH_COMPONENTS:
            raise fail("load", "pulses", f"component {pulse.component!r} is not one of {', '.join(WRENCH_COMPONENTS)}")
        if pulse.frame not in FRAMES:
            raise fail("load", "pulses", f"frame {pulse.frame!r}: use 'base' or 'platform'")
        if sum(p.component == pulse.component for p in pulses) > CAPACITY["pulses"]:
            raise fail("load", "pulses", f"has more than {CAPACITY['pulses']} pulses on {pulse.component}; the "
                       "trajectory FMU holds that many per component")
    outputs = data.get("outputs", {})
    names = {}
    for key in ("mechanics", "drive"):
        value = outputs.get(key)
        if value is not None and (not isinstance(value, list) or not all(isinstance(v, str) for v in value)):
            raise fail("outputs", key, "must be a list of variable names")
        names[key] = value
    interval = number("outputs", outputs, "interval", positive=True) if "interval" in outputs else None
    from .parameter_sets import load as load_parameter_set
    mass_set = choice("mechanics", mechanics, "mass_set", "heavy",
                      tuple(load_parameter_set(parameter_set).get("mass_sets", {"heavy": None})), "is not a mass set of "
                      f"{parameter_set}")
    mechanics_parameters = parameters("mechanics", mechanics, "mechanics")
    drive_parameters = parameters("drive", drive, top.path if top else DRIVES[kind].fmu)
    leg_parameters, limits = {}, {}
    for leg, values in legs.items():
        own = leg_fmus.get(int(leg), top)
        leg_parameters[int(leg)] = parameters(f"drive.leg.{leg}", values, own.path if own else DRIVES[kind].fmu)
    for leg in range(1, 7):
        table, values = (f"drive.leg.{leg}", legs[str(leg)]) if "continuous_limit" in legs.get(str(leg), {}) \
            else ("drive", drive)
        if "continuous_limit" not in values:
            continue
        own, name = leg_fmus.get(leg, top), values["continuous_limit"]
        if own is None:
            if table == "drive" and leg_fmus:
                continue  # [drive]'s limit is for the legs that take its FMU
            raise fail(table, "continuous_limit", f"= {name!r}: our drives' limits are known (the sizing check reads "
                       "them); continuous_limit names the parameter of a drive FMU of your own")
        if not isinstance(name, str) or name not in own.parameters:
            raise fail(table, "continuous_limit", f"= {name!r} is not a Real parameter of {own.name} (it has: "
                       f"{', '.join(sorted(own.parameters)) or 'none'})")
        limits[leg] = name
    if at_neutral:
        from .parameter_sets import scene_mechanics
        from ..core import neutral_pose
        try:
            pose = neutral_pose(scene_mechanics(parameter_set, mass_set, drive_set, mechanics_parameters))
        except (KeyError, ValueError) as error:
            raise fail(f"trajectory.{at_neutral[0]}", "offset", f"= 'neutral': no neutral pose ({error})") from None
        for dof in at_neutral:
            trajectory[dof].offset = float(pose[POSE.index(dof)])
    loaded = Scene(path=path, name=scene.get("name", path.stem),
                    duration=number("scene", scene, "duration", positive=True), step=number("scene", scene, "step", 1e-3, positive=True), drive=kind,
                    drive_parameters=drive_parameters, parameter_set=parameter_set,
                    mass_set=mass_set, mechanics_parameters=mechanics_parameters,
                    algorithm=algorithm, order=order, trajectory=trajectory, pulses=pulses, table=table_file,
                    interpolation=interpolation, step_control=step_control, atol=atol, **tolerances,
                    outputs_mechanics=names["mechanics"] or [], outputs_drive=names["drive"], output_interval=interval,
                    tuning=tuning, drive_set=drive_set, overrides=dict(overrides or {}), threads=threads,
                    interface_jacobian=interface_jacobian, feedthrough=feedthrough,
                    drive_fmu=top.path if top else None, leg_fmus={leg: f.path for leg, f in leg_fmus.items()},
                    leg_parameters=leg_parameters, continuous_limit=limits, **startup)
    try:
        scene_settings(loaded)
    except SettingsError as error:  # what the settings object refuses beyond the checks above
        table, key = ("scene", "step") if error.setting in (None, "step") else \
            ("coupling", {"kind": "algorithm", "windows": "edge_time"}.get(error.setting, error.setting))
        raise fail(table, key, f"is refused: {error}") from None
    user = {f.path: f for f in (top, *leg_fmus.values()) if f is not None}
    if user:  # what the user's drive FMUs cannot do limits the step control
        from ...engine.checks import capability_problem
        control = scene_settings(loaded)[1]
        for fmu in user.values():
            reason = capability_problem(fmu.path, control, sum(loaded.leg_fmu(i) == fmu.path for i in range(1, 7)))
            if reason:
                key = "step_control" if "step_control" in coupling else \
                    next((k for k in ("edge_time", "startup_time") if k in coupling), "step_control")
                where = "drive.fmu" if fmu is top else f"drive.leg.{min(i for i, f in leg_fmus.items() if f is fmu)}.fmu"
                raise fail("coupling", key, f"is refused: {fmu.name} ({where}) {reason}")
    return loaded


# Step doubling's error scale on what the mechanics hands the drives (leg angles and speeds, or
# lengths and velocities: m, rad, m/s, rad/s) when the scene gives no atol.
DOUBLING_ATOL = 1e-3


def scene_settings(scene: Scene) -> tuple[Algorithm, StepControl]:
    """The scene's coupling algorithm and macro-step control: the one typed settings object
    (cosim.engine.settings) that the SSP annotation and the OSP export carry, with its own
    defaults for what the scene leaves out. Step doubling measures the error on the mechanics'
    outputs to the drives."""
    algorithm = dataclasses.replace(default_algorithm(scene.drive, scene.algorithm, scene.order), threads=scene.threads,
                                    feedthrough=scene.feedthrough)
    given = {key: getattr(scene, key) for key in ("rtol", "h_min", "h_max") if getattr(scene, key) is not None}
    if scene.step_control == "doubling":
        return algorithm, StepDoubling(scene.step, atol={"mechanics": scene.atol or DOUBLING_ATOL}, **given)
    if scene.step_control == "energy":
        return algorithm, EnergyControl(scene.step, **given, **({"atol": scene.atol} if scene.atol else {}))
    if scene.startup_time and scene.startup_step < scene.step:
        # the first startup_time seconds, rounded up to whole steps, at the largest whole fraction
        # of the step that is no longer than startup_step (a run at a finer step needs no finer start)
        per = math.ceil(scene.step / scene.startup_step - 1e-9)
        steps = math.ceil(scene.startup_time / scene.step - 1e-9)
        # and the edge_time after each load pulse's edges, where the drives answer a jumping load
        windows = tuple((edge, edge + scene.edge_time) for pulse in scene.pulses for edge in (pulse.start, pulse.end)
                        if scene.edge_time > 0.0 and edge < scene.duration)
        return algorithm, FixedStep(scene.step, steps * scene.step, scene.step / per, windows)
    return algorithm, FixedStep(scene.step)
