"""Configuration design of a Stewart platform: Halder et al., Section V.

Which platform carries a motion specification? A study (studies/*.toml) sweeps design variables of
a platform family's geometry (Halder's 6-SBU layout, Eqs 1-4: the base radius r_b and the disc's
neutral height z_p0, in 0.01 m steps) and asks, at every grid point and for each basic motion
(each DOF alone from one end of its range to the other in the shortest time its velocity and
acceleration limits allow):

- kinematic admissibility (Eqs 17-21): the largest and smallest actuated length and the largest top
  and bottom joint angles over the motion, against each actuator's running lengths (its minimum
  running length and that plus its stroke, less the two stubs) and the joint-angle limit;
- dynamic admissibility (Fig 4): the peak leg force of the paper's inverse model (payload only: the
  legs' weight, inertia and friction neglected, Eq 16) against the actuator's continuous force
  less the margins, and the same from the full inverse dynamics (legs, friction) beside it;
- conditioning: the leg Jacobian's smallest singular value and condition number over the motion.

Every pose goes through the mechanics FMU's own dynamics core (fmu/mechanics/platform.c:
platform_pose_kinematics and platform_inverse_dynamics_many, one call per grid point for all its
poses), on the platform the FMU builds from the study's geometry (parameter_sets.halder_mechanics),
so the design map and the co-simulation share one model.

Where the paper is loose (params/halder2013.toml says each choice): the disc's size "0.5mm" is read
as a 0.5 m radius, the design height as the disc's (z_q0, which gives the paper's neutral running
length 1647 mm at z = 1.4 m), Eq 1's even legs as (i - 2) pi/3, Section V's 100 kg payload with
Section VII's inertia scaled by mass (the study file says so), and the margins as the force the
demand may reach: continuous force / ((1 + friction margin)(1 + other margin)).
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..engine.errors import InputError
from ..engine.tomlfile import line_of, read
from .scene.parameter_sets import halder_mechanics, load, meng_mechanics, sumnu_mechanics
from .core import Core
from .ports import POSE

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
ROTATIONS = ("roll", "pitch", "yaw")


class StudyError(InputError):
    """A study file that cannot run: one line naming the file, the line and the reason."""


@dataclass(frozen=True)
class Actuator:
    name: str
    stroke: float              # [m]
    running_length_min: float  # L_min [m]: the leg system, stubs included, at the shortest stroke
    continuous_force: float    # [N], 100 % duty cycle (a study may give the motor's torque: times K_FT)
    peak_force: float | None = None  # [N], what it gives for a moment (checked against the full model)
    speed: float | None = None       # [m/s], the largest extension rate (or the motor's speed / i_theta)

    @property
    def running_length_max(self) -> float:
        return self.running_length_min + self.stroke


@dataclass(frozen=True)
class Motion:
    """Per DOF the half range (m, rad); the limits of speed and acceleration (m/s, m/s^2 for the
    translations, rad/s, rad/s^2 for the rotations)."""
    ranges: dict[str, float]
    velocity: float
    acceleration: float
    angular_velocity: float
    angular_acceleration: float


@dataclass(frozen=True)
class Family:
    """A platform layout a study sweeps: its design values (name -> value, from its parameter set),
    the mechanics start values at a design, the stubs between the actuated length and the
    actuator's running length, the payload (mass, inertia diagonal), and the values a map must
    not vary (one per study: [study] fixed)."""
    describe: str
    design_values: Callable[[dict], dict[str, float]]
    mechanics: Callable[[dict, dict[str, float]], dict[str, float]]
    stubs: Callable[[dict[str, float]], float]
    payload: Callable[[dict], tuple[float, list[float]]]
    fixed_only: tuple[str, ...] = ()


def unit(key: str) -> str:
    """A design value's unit as the parameter sets name them: *_deg in degrees, *_scale a factor,
    the rest lengths."""
    return "deg" if key.endswith("_deg") else "" if key.endswith("_scale") else "m"


def value(key: str, number: float, digits: str = "g") -> str:
    """`key = number unit`, e.g. 'base_radius = 1.1 m'."""
    return f"{key} = {number:{digits}}" + (f" {unit(key)}" if unit(key) else "")


def span(key: str, values: np.ndarray) -> str:
    """`key low-high unit`, e.g. 'base_radius 0.8-1.5 m'."""
    return f"{key} {np.min(values):g}-{np.max(values):g}" + (f" {unit(key)}" if unit(key) else "")


def _scalars(table: dict) -> dict[str, float]:
    return {k: float(v) for k, v in table.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}


def _with_geometry(config: dict, geometry: dict[str, float]) -> dict:
    return {**config, "geometry": {**config["geometry"], **geometry}}


def _sumnu_values(config: dict) -> dict[str, float]:
    return {"base_scale": 1.0, "platform_scale": 1.0, "home_height": float(config["geometry"]["home_pose"][2])}


def _sumnu_mechanics(config: dict, design: dict[str, float]) -> dict[str, float]:
    """Sumnu's joints (irregular, given point by point) scaled in the plane about each frame's
    origin (base joints by base_scale, platform joints by platform_scale; their heights kept), the
    home pose at home_height."""
    g = config["geometry"]
    scaled = {"base_joints": [[design["base_scale"] * x, design["base_scale"] * y, z] for x, y, z in g["base_joints"]],
              "platform_joints": [[design["platform_scale"] * x, design["platform_scale"] * y, z]
                                  for x, y, z in g["platform_joints"]],
              "home_pose": [*g["home_pose"][:2], design["home_height"], *g["home_pose"][3:]]}
    return sumnu_mechanics(_with_geometry(config, scaled))


FAMILIES = {
    "halder2013": Family("Halder's 6-SBU layout (Eqs 1-4): joint pairs on the base circle and the disc, stubs",
                         lambda c: _scalars(c["geometry"]), lambda c, g: halder_mechanics(_with_geometry(c, g)),
                         lambda g: g["top_stub"] + g["bottom_stub"],
                         lambda c: (c["payload"]["mass"], c["payload"]["inertia_diag"]), ("top_stub", "bottom_stub")),
    "meng2010": Family("Meng's layout (Table 1): joint pairs on two circles, the neutral height from the middle leg "
                       "length", lambda c: _scalars(c["geometry"]), lambda c, g: meng_mechanics(_with_geometry(c, g)),
                       lambda g: 0.0, lambda c: (c["platform"]["mass"], c["platform"]["inertia_diag"])),
    "sumnu2015": Family("Sumnu's motion-simulator layout (Section 4.2): joints point by point, scaled in the plane",
                        _sumnu_values, _sumnu_mechanics, lambda g: 0.0,
                        lambda c: (c["mass_sets"]["heavy"]["platform_mass"],
                                   c["mass_sets"]["heavy"]["platform_inertia_diag"])),
}


@dataclass(frozen=True)
class Recorded:
    """A motion given as a time series (a scene's reference or a recorded table): displacements
    from the design's neutral pose (n x 6, m and rad), their rates and accelerations."""
    name: str
    times: np.ndarray
    displacement: np.ndarray
    rates: np.ndarray
    accelerations: np.ndarray


@dataclass
class Study:
    path: Path
    name: str
    parameter_set: str               # the platform family (FAMILIES) and the parameter set it starts from
    axes: dict[str, np.ndarray]      # design value -> values (two axes: the map's rows and columns)
    motion: Motion | None            # the basic motions, or None where `recorded` is the motion
    actuators: list[Actuator]
    joint_angle_limit: float         # [rad], both joints unless one has its own below
    payload_mass: float
    payload_inertia: tuple[float, float, float]
    force_margins: tuple[float, float] = (0.07, 0.20)
    samples: int = 121               # poses per basic motion along its path
    phase_samples: int = 11          # poses per phase (accelerate, cruise, decelerate) of a timed motion
    fixed: dict[str, float] = field(default_factory=dict)  # geometry values over the parameter set's
    # [workspace]: the design whose workspace is mapped, the actuator, the grid spacings
    workspace: dict[str, Any] | None = None
    # [optimise]: the actuator the most robust design is sought for, the seed, the iterations
    optimise: dict[str, Any] | None = None
    # [confirm]: the design run through the co-simulation, every basic motion, and its actuator
    confirm: dict[str, Any] | None = None
    recorded: Recorded | None = None  # [motion] scene or table: one motion, the time series
    top_joint_limit: float | None = None     # [rad] the top (universal) joint's own limit
    bottom_joint_limit: float | None = None  # [rad] the bottom (spherical) joint's own limit

    @property
    def joint_limits(self) -> tuple[float, float]:
        """(top, bottom) joint-angle limits [rad]."""
        return (self.top_joint_limit or self.joint_angle_limit, self.bottom_joint_limit or self.joint_angle_limit)

    def joints_within(self, top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
        """Where the top and bottom joint angles are within their limits (Eq 21)."""
        top_limit, bottom_limit = self.joint_limits
        return (top < top_limit) & (bottom < bottom_limit)

    @property
    def family(self) -> Family:
        return FAMILIES[self.parameter_set]

    def allowed_force(self, actuator: Actuator) -> float:
        friction, other = self.force_margins
        return actuator.continuous_force / ((1 + friction) * (1 + other))


def shortest_time(distance: float, v_max: float, a_max: float, samples: int = 41) -> tuple[np.ndarray, ...]:
    """The shortest-time rest-to-rest move over `distance` under |v| <= v_max, |a| <= a_max:
    accelerate at a_max, cruise at v_max (if reached), decelerate. Returns times, displacements,
    velocities and accelerations sampled in each phase with the phase's own (constant)
    acceleration at both its ends, so the extremes of anything the acceleration drives are seen."""
    t_ramp = min(v_max / a_max, math.sqrt(distance / a_max))
    v_top = a_max * t_ramp
    t_cruise = max(0.0, (distance - a_max * t_ramp ** 2) / v_top) if v_top > 0 else 0.0
    times, s, v, a = [], [], [], []
    for phase, (start, length, accel) in enumerate([(0.0, t_ramp, a_max), (t_ramp, t_cruise, 0.0),
                                                    (t_ramp + t_cruise, t_ramp, -a_max)]):
        if length <= 0.0:
            continue
        tau = np.linspace(0.0, length, samples)
        if phase == 0:
            s0, v0 = 0.0, 0.0
        elif phase == 1:
            s0, v0 = 0.5 * a_max * t_ramp ** 2, v_top
        else:
            s0, v0 = 0.5 * a_max * t_ramp ** 2 + v_top * t_cruise, v_top
        times.append(start + tau)
        s.append(s0 + v0 * tau + 0.5 * accel * tau ** 2)
        v.append(v0 + accel * tau)
        a.append(np.full_like(tau, accel))
    return tuple(np.concatenate(x) for x in (times, s, v, a))


def basic_motions(study: Study, neutral: np.ndarray, timed: bool = False) -> dict[str, tuple[np.ndarray, ...]]:
    """Each DOF from -range to +range about the neutral pose: poses (n x 6) and, with `timed`, the
    shortest-time profile's rates and accelerations (n x 6 each); otherwise `samples` poses evenly
    along the path (what the kinematic limits need)."""
    return {dof: (neutral + offsets, rates, accelerations)
            for dof, (offsets, rates, accelerations) in _displacements(study, timed).items()}


_PROFILES: dict[tuple, dict] = {}


def _displacements(study: Study, timed: bool) -> dict[str, tuple[np.ndarray, ...]]:
    """basic_motions about a zero pose (the same at every design point: computed once), or the
    recorded motion (its every sample, rates and accelerations either way)."""
    if study.recorded is not None:
        r = study.recorded
        return {r.name: (r.displacement, r.rates, r.accelerations)}
    key = (tuple(sorted(study.motion.ranges.items())), study.motion.velocity, study.motion.acceleration,
           study.motion.angular_velocity, study.motion.angular_acceleration, study.samples, study.phase_samples, timed)
    if key in _PROFILES:
        return _PROFILES[key]
    out = {}
    for k, dof in enumerate(DOFS):
        half = study.motion.ranges.get(dof, 0.0)
        if half <= 0.0:
            continue
        rotation = dof in ROTATIONS
        if timed:
            m = study.motion
            _, s, v, a = shortest_time(2 * half, m.angular_velocity if rotation else m.velocity,
                                       m.angular_acceleration if rotation else m.acceleration, study.phase_samples)
            displacement = s - half
        else:
            displacement = np.linspace(-half, half, study.samples)
            v = a = np.zeros_like(displacement)
        offsets = np.zeros((len(displacement), 6))
        offsets[:, k] = displacement
        rates, accelerations = np.zeros_like(offsets), np.zeros_like(offsets)
        rates[:, k], accelerations[:, k] = v, a
        out[dof] = (offsets, rates, accelerations)
    _PROFILES[key] = out
    return out


def platform_values(study: Study, point: dict[str, float], effects: bool = False) -> dict[str, Any]:
    """The mechanics start values of the study's platform at a design point (geometry keys of the
    parameter set's [geometry] table); the payload is the study's. effects: the legs' inertia and
    friction as the parameter set gives them (the full model), or off (the paper's inverse model)."""
    config = _parameter_set(study.parameter_set)
    family = study.family
    values = family.mechanics(config, {**family.design_values(config), **study.fixed, **point})
    values["platform.mass"] = study.payload_mass
    for axis, inertia in zip(("xx", "yy", "zz"), study.payload_inertia):
        values[f"platform.inertia_{axis}"] = inertia
    values.update({"effects.actuator_inertia": effects, "effects.motor_inertia": effects, "effects.friction": effects})
    return values


_SETS: dict[str, dict] = {}


def _parameter_set(name: str) -> dict:
    """The parameter set, read once per process (a map reads it at every grid point)."""
    if name not in _SETS:
        _SETS[name] = copy.deepcopy(load(name))
    return _SETS[name]


def stubs(study: Study) -> float:
    """What the actuator's running length adds to the joint-to-joint (actuated) length [m]."""
    config = _parameter_set(study.parameter_set)
    return study.family.stubs({**study.family.design_values(config), **study.fixed})


@dataclass
class DesignMap:
    """Per grid point (rows: the first axis, columns: the second) and basic motion, the limits
    over the motion; `seconds` the time the map took."""
    study: Study
    motions: list[str]
    length_max: np.ndarray    # [rows, columns, motions]: the largest actuated length [m]
    length_min: np.ndarray
    neutral_length: np.ndarray  # [rows, columns]: the longest actuated length at the neutral
    top_angle: np.ndarray     # the largest top (universal) joint angle [rad]
    bottom_angle: np.ndarray  # the largest bottom (spherical) joint angle [rad]
    smallest_singular: np.ndarray  # the leg Jacobian's smallest singular value over the motion
    condition: np.ndarray     # its largest condition number
    seconds: float = 0.0
    force_paper: np.ndarray | None = None  # [rows, columns, motions] peak |leg force|, payload only [N]
    force_full: np.ndarray | None = None   # the same with the legs' inertia and friction
    leg_speed: np.ndarray | None = None    # [rows, columns, motions] the largest |extension rate| [m/s]

    @property
    def points(self) -> int:
        return self.length_max.shape[0] * self.length_max.shape[1]

    def kinematic_admissible(self, actuator: Actuator) -> dict[str, np.ndarray]:
        """Per constraint, [rows, columns, motions] booleans (Eq 21): max stroke, min stroke, joint angle."""
        s = stubs(self.study)
        return {"max stroke": s + self.length_max < actuator.running_length_max,
                "min stroke": s + self.length_min > actuator.running_length_min,
                "joint angle": self.study.joints_within(self.top_angle, self.bottom_angle)}

    def dynamic_admissible(self, actuator: Actuator) -> dict[str, np.ndarray]:
        """Per limit, [rows, columns, motions] booleans: the paper's peak force (payload only) within
        the continuous force less the margins (Fig 4); where the actuator gives them, the full
        model's peak force within its peak force and the legs' speed within its speed."""
        if self.force_paper is None:
            return {}
        out = {"force": self.force_paper <= self.study.allowed_force(actuator)}
        if actuator.peak_force is not None:
            out["peak force"] = self.force_full <= actuator.peak_force
        if actuator.speed is not None:
            out["speed"] = self.leg_speed <= actuator.speed
        return out

    def admissible(self, actuator: Actuator, dynamic: bool = False) -> np.ndarray:
        """[rows, columns]: every constraint of every basic motion holds (and the forces and
        speed, with dynamic)."""
        ok = np.all([c.all(axis=2) for c in self.kinematic_admissible(actuator).values()], axis=0)
        if dynamic:
            for limit in self.dynamic_admissible(actuator).values():
                ok &= limit.all(axis=2)
        return ok


def design_map(study: Study, dynamic: bool = True) -> DesignMap:
    """The kinematic (and dynamic) map of the study's grid: one call of the dynamics core per grid
    point for all its poses."""
    start = time.perf_counter()
    (row_key, rows), (column_key, columns) = list(study.axes.items())
    shape = (len(rows), len(columns))
    core, full = Core(actuators=False, motors=False, friction=False), Core()
    out: dict[str, np.ndarray] = {}
    motions: list[str] = []
    for r, row in enumerate(rows):
        for c, column in enumerate(columns):
            point = {row_key: float(row), column_key: float(column)}
            core.use_start_values(platform_values(study, point))
            neutral = core.neutral_pose
            paths = basic_motions(study, neutral)
            motions = list(paths)
            poses = np.concatenate([p for p, _, _ in paths.values()])
            k = core.pose_kinematics(poses, jacobian=True)
            split = np.cumsum([len(p) for p, _, _ in paths.values()])[:-1]
            # the Jacobian's singular values at every tenth pose of each path (and its ends): the
            # conditioning varies slowly along a path, and the SVDs would cost more than the rest
            every = np.r_[0:len(poses):10, len(poses) - 1]
            singular = np.full((len(poses), 6), np.nan)
            singular[every] = np.linalg.svd(k["jacobian"][every], compute_uv=False)
            for name, values, reduce in (("length_max", k["length"], np.max), ("length_min", k["length"], np.min),
                                         ("top_angle", k["upper_angle"], np.max),
                                         ("bottom_angle", k["lower_angle"], np.max),
                                         ("smallest_singular", singular[:, -1:], np.nanmin),
                                         ("condition", singular[:, :1] / singular[:, -1:], np.nanmax)):
                out.setdefault(name, np.empty((*shape, len(motions))))[r, c] = \
                    [reduce(part) for part in np.split(values, split)]
            out.setdefault("neutral_length", np.empty(shape))[r, c] = core.leg_lengths(neutral).max()
            if dynamic:
                timed = basic_motions(study, neutral, timed=True)
                arrays = [np.concatenate([m[i] for m in timed.values()]) for i in range(3)]
                split = np.cumsum([len(m[0]) for m in timed.values()])[:-1]
                core.p.force_torque = 1.0  # forces, not torques
                paper = np.abs(core.inverse_dynamics_many(*arrays))
                full.use_start_values(platform_values(study, point, effects=True))
                full.p.force_torque = 1.0
                every = np.abs(full.inverse_dynamics_many(*arrays))
                speed = np.abs(core.leg_velocities_many(arrays[0], arrays[1]))
                out.setdefault("leg_speed", np.empty((*shape, len(motions))))[r, c] = \
                    [part.max() for part in np.split(speed, split)]
                out.setdefault("force_paper", np.empty((*shape, len(motions))))[r, c] = \
                    [part.max() for part in np.split(paper, split)]
                out.setdefault("force_full", np.empty((*shape, len(motions))))[r, c] = \
                    [part.max() for part in np.split(every, split)]
    return DesignMap(study, motions, seconds=time.perf_counter() - start, **out)


def limit_along(design: DesignMap, actuator: Actuator, constraint: str, motion: str, row: float) -> float | None:
    """Halder's points a, b, c: at the grid row nearest `row` (r_b), scanning the column variable
    (z) upward, the last admissible value before the constraint fails (max stroke: the largest
    admissible z) or the first admissible one (min stroke, joint angle: the smallest)."""
    (_, rows), (_, columns) = list(design.study.axes.items())
    r = int(np.argmin(np.abs(rows - row)))
    ok = design.kinematic_admissible(actuator)[constraint][r, :, design.motions.index(motion)]
    if not ok.any():
        return None
    return float(columns[ok][-1] if constraint == "max stroke" else columns[ok][0])


# -- the study file ---------------------------------------------------------------------------------

SCHEMA = {"": {"study", "axes", "motion", "actuator", "workspace", "optimise", "confirm"},
          "confirm": {"point", "actuator", "drive"},
          "optimise": {"actuator", "seed", "iterations"},
          "workspace": {"point", "actuator", "spacing", "angle_step_deg"},
          "study": {"name", "parameter_set", "payload_mass", "payload_inertia", "joint_angle_limit_deg",
                    "top_joint_angle_limit_deg", "bottom_joint_angle_limit_deg",
                    "force_margins", "samples", "fixed"},
          "motion": {*[d for d in DOFS if d not in ROTATIONS], *[f"{d}_deg" for d in ROTATIONS], "velocity",
                     "acceleration", "angular_velocity_deg", "angular_acceleration_deg", "scene", "table", "samples"},
          "actuator": {"name", "stroke", "running_length_min", "continuous_force", "peak_force", "speed",
                       "continuous_torque", "peak_torque", "motor_speed"}}
RECORDED = {"scene", "table", "samples"}  # [motion] keys of a motion given as a time series


def load_study(path: str | Path) -> Study:
    """Reads and checks a study file (studies/*.toml); every mistake is a StudyError naming the
    file and line."""
    path = Path(path)
    text, data = read(path, "study file", StudyError)

    def fail(table: str, key: str, problem: str) -> StudyError:
        return StudyError(f"{path}:{line_of(text, table, key)}: '{table + '.' if table else ''}{key}' {problem}")

    def number(table: str, values: dict, key: str, default: float | None = None, positive: bool = True) -> float:
        if key not in values:
            if default is None:
                raise StudyError(f"{path}: '{table}.{key}' is missing")
            return default
        value = values[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or (positive and not value > 0) or value < 0:
            raise fail(table, key, f"= {value!r} must be a {'positive' if positive else 'non-negative'} number")
        return float(value)

    for table, allowed in SCHEMA.items():
        values = data if table == "" else data.get(table, {})
        for entry in (values if isinstance(values, list) else [values]):
            if not isinstance(entry, dict):
                raise fail("", table, "must be a table" + (" list ([[actuator]])" if table == "actuator" else ""))
            if table == "":
                unknown = [k for k in entry if k not in allowed]
            else:
                unknown = [k for k in entry if k not in allowed]
            if unknown:
                raise fail(table, unknown[0], f"is not a known key (known here: {', '.join(sorted(allowed))})")
    study = data.get("study", {})
    parameter_set = study.get("parameter_set", "halder2013")
    if parameter_set not in FAMILIES:
        raise fail("study", "parameter_set", f"= {parameter_set!r} is not a platform family here ("
                   + "; ".join(f"{name!r}: {f.describe}" for name, f in FAMILIES.items()) + ")")
    family = FAMILIES[parameter_set]
    config = load(parameter_set)
    geometry = family.design_values(config)
    fixed = study.get("fixed", {})
    if not isinstance(fixed, dict):
        raise fail("study", "fixed", "must be a table of geometry values")
    for key, value in fixed.items():
        if key not in geometry:
            raise fail("study", "fixed", f"names {key!r}, not a design value of {parameter_set} "
                       f"({', '.join(sorted(geometry))})")
        number("study.fixed", fixed, key, positive=False)
    axes = {}
    raw_axes = data.get("axes", {})
    if not isinstance(raw_axes, dict) or len(raw_axes) != 2:
        raise fail("", "axes", f"must name two design values of {parameter_set}, each {{from, to, step}} "
                   f"({', '.join(sorted(geometry))})")
    for key, spec in raw_axes.items():
        if key not in geometry:
            raise fail("axes", key, f"is not a design value of {parameter_set} ({', '.join(sorted(geometry))})")
        if key in family.fixed_only:
            raise fail("axes", key, "is one value per study: set it in [study] fixed")
        if not isinstance(spec, dict) or set(spec) != {"from", "to", "step"}:
            raise fail("axes", key, "must be {from = ..., to = ..., step = ...}")
        low, high, step = (number("axes", spec, k, positive=k == "step") for k in ("from", "to", "step"))
        if not high >= low:
            raise fail("axes", key, f"runs from {low} to {high}: 'to' must not be below 'from'")
        count = int(round((high - low) / step)) + 1
        if count > 2000:
            raise fail("axes", key, f"has {count} values; at most 2000 per axis")
        axes[key] = np.round(low + step * np.arange(count), 10)
    motion = data.get("motion", {})
    spec, recorded = None, None
    if RECORDED & set(motion):
        sources = [k for k in ("scene", "table") if k in motion]
        if len(sources) != 1:
            raise fail("motion", "samples" if not sources else sources[1],
                       "needs one of 'scene' (a scene's reference motion) or 'table' (a recorded motion), not "
                       + ("neither" if not sources else "both"))
        others = sorted(set(motion) - RECORDED)
        if others:
            raise fail("motion", others[0], f"belongs to the basic motions; the motion here is the {sources[0]}'s")
        samples_in_time = motion.get("samples", 1001)
        if not isinstance(samples_in_time, int) or isinstance(samples_in_time, bool) or not 4 <= samples_in_time <= 100001:
            raise fail("motion", "samples", f"= {samples_in_time!r} must be a whole number of samples, 4 to 100001")
        try:
            recorded = recorded_motion(path, sources[0], motion[sources[0]], samples_in_time)
        except StudyError as error:
            raise fail("motion", sources[0], str(error)) from None
    else:
        ranges = {d: number("motion", motion, d, 0.0, positive=False) for d in DOFS if d not in ROTATIONS}
        ranges.update({d: math.radians(number("motion", motion, f"{d}_deg", 0.0, positive=False)) for d in ROTATIONS})
        if not any(ranges.values()):
            raise fail("", "motion", "gives no range: name at least one of surge, sway, heave, roll_deg, pitch_deg, "
                       "yaw_deg (or a scene or table)")
        spec = Motion(ranges, number("motion", motion, "velocity"), number("motion", motion, "acceleration"),
                      math.radians(number("motion", motion, "angular_velocity_deg")),
                      math.radians(number("motion", motion, "angular_acceleration_deg")))
    actuators = []
    raw = data.get("actuator", [])
    if not isinstance(raw, list) or not raw:
        raise fail("", "actuator", "must be one or more [[actuator]] tables")
    transmission = family.mechanics(config, geometry)
    force_torque, screw_ratio = transmission["transmission.force_torque"], transmission["transmission.screw_ratio"]
    for entry in raw:
        name = entry.get("name")
        if not isinstance(name, str) or not name:
            raise fail("actuator", "name", "must be a name")
        limits = {}
        for force, torque, factor, what in (("continuous_force", "continuous_torque", force_torque, "N m"),
                                            ("peak_force", "peak_torque", force_torque, "N m"),
                                            ("speed", "motor_speed", 1.0 / screw_ratio, "rad/s")):
            if force in entry and torque in entry:
                raise fail("actuator", torque, f"and '{force}' both given: one of them")
            if torque in entry:  # the motor's side, through the family's screw (K_FT, i_theta)
                if force_torque == 1.0 and screw_ratio == 1.0:
                    raise fail("actuator", torque, f"needs a screw: {parameter_set}'s legs are driven by force "
                               f"(give '{force}')")
                limits[force] = number("actuator", entry, torque) * factor
            elif force in entry or force == "continuous_force":
                limits[force] = number("actuator", entry, force)
        actuators.append(Actuator(name, number("actuator", entry, "stroke"),
                                  number("actuator", entry, "running_length_min"), limits["continuous_force"],
                                  limits.get("peak_force"), limits.get("speed")))
    payload_mass, payload_inertia = family.payload(config)
    inertia = study.get("payload_inertia", payload_inertia)
    if not (isinstance(inertia, list) and len(inertia) == 3 and all(isinstance(v, (int, float)) and v > 0
                                                                    for v in inertia)):
        raise fail("study", "payload_inertia", "must be three positive numbers [kg m^2]")
    margins = study.get("force_margins", [0.07, 0.20])
    if not (isinstance(margins, list) and len(margins) == 2 and all(isinstance(v, (int, float)) and 0 <= v < 1
                                                                   for v in margins)):
        raise fail("study", "force_margins", "must be two fractions [friction, other], each in [0, 1)")
    samples = study.get("samples", 121)
    if not isinstance(samples, int) or isinstance(samples, bool) or not 3 <= samples <= 10001:
        raise fail("study", "samples", "must be a whole number of poses per motion, 3 to 10001")
    def design_point(table: str) -> dict | None:
        """[workspace] or [confirm]: a design (a value for each axis) and one of the actuators."""
        given = data.get(table)
        if given is None:
            return None
        point = given.get("point")
        if not isinstance(point, dict) or set(point) != set(axes):
            raise fail(table, "point", f"must give the design as {{{', '.join(f'{k} = ...' for k in axes)}}}")
        for key in point:
            number(f"{table}.point", point, key)
        names = [a.name for a in actuators]
        if given.get("actuator") not in names:
            raise fail(table, "actuator", f"= {given.get('actuator')!r} is not one of the study's actuators "
                       f"({', '.join(names)})")
        return {"point": {k: float(v) for k, v in point.items()}, "actuator": given["actuator"]}

    space, confirmed = design_point("workspace"), design_point("confirm")
    if confirmed is not None:
        driven = data["confirm"].get("drive", "force")
        if driven not in DRIVEN:
            raise fail("confirm", "drive", f"= {driven!r} is not one of " + "; ".join(f"{k!r}: {v}" for k, v in DRIVEN.items()))
        confirmed["drive"] = driven
    if space is not None:
        given = data["workspace"]
        space.update(spacing=number("workspace", given, "spacing", 0.02),
                     angle_step=math.radians(number("workspace", given, "angle_step_deg", 1.0)))
    best = data.get("optimise")
    if best is not None:
        names = [a.name for a in actuators]
        if best.get("actuator") not in names:
            raise fail("optimise", "actuator", f"= {best.get('actuator')!r} is not one of the study's actuators "
                       f"({', '.join(names)})")
        for key, default in (("seed", 1), ("iterations", 60)):
            value = best.get(key, default)
            if not isinstance(value, int) or isinstance(value, bool) or value < (0 if key == "seed" else 1):
                raise fail("optimise", key, f"= {value!r} must be a whole number" + (" of at least 1" if key ==
                                                                                      "iterations" else ""))
        best = {"actuator": best["actuator"], "seed": best.get("seed", 1), "iterations": best.get("iterations", 60)}
    return Study(path, str(study.get("name", path.stem)), parameter_set, axes, spec, actuators,
                 math.radians(number("study", study, "joint_angle_limit_deg", 20.0)),
                 number("study", study, "payload_mass", float(payload_mass)),
                 tuple(float(v) for v in inertia), (float(margins[0]), float(margins[1])), samples,
                 fixed={k: float(v) for k, v in fixed.items()}, workspace=space, optimise=best,
                 confirm=confirmed, recorded=recorded,
                 top_joint_limit=math.radians(number("study", study, "top_joint_angle_limit_deg"))
                 if "top_joint_angle_limit_deg" in study else None,
                 bottom_joint_limit=math.radians(number("study", study, "bottom_joint_angle_limit_deg"))
                 if "bottom_joint_angle_limit_deg" in study else None)


def recorded_motion(study_path: Path, kind: str, source: Any, samples: int) -> Recorded:
    """[motion] scene = "<name or path>": the scene's reference motion less its platform's neutral
    pose; [motion] table = "<csv>": a recorded motion (columns time and any of x, y, z, roll, pitch,
    yaw: displacements from the neutral pose, m and rad), played by the trajectory FMU (cubic
    interpolation), the one reader of tables. Either sampled `samples` times evenly over its
    duration (at least 4); the rates and accelerations are the samples' second-order differences.
    Raises StudyError with the reason (the caller adds the file and line)."""
    from .core import neutral_pose
    from .run.runner import scene_values
    from .scene import SceneError, Signal, load_scene, shipped
    from .scene.signals import scene_trajectory, trajectory_parameters
    from .report.view3d import play
    if not isinstance(source, str) or not source:
        raise StudyError(f"= {source!r} must name a {'scene' if kind == 'scene' else 'CSV file'}")
    given = study_path.parent / source
    if kind == "scene":
        found = given if given.is_file() else shipped(source, "scenes")
        if found is None:
            raise StudyError(f"= {source!r}: no such scene (relative to the study's folder, or a shipped scene's name)")
        try:
            scene = load_scene(found)
            neutral = neutral_pose(scene_values(scene)[0])
            values, duration, name = scene_trajectory(scene), scene.duration, found.stem
        except (SceneError, ValueError) as error:
            raise StudyError(f"= {source!r}: {error}") from None
    else:
        if not given.is_file():
            raise StudyError(f"= {source!r}: no such file (relative to the study's folder)")
        lines = [line for line in given.read_text(errors="replace").splitlines() if line.strip()]
        try:
            duration = float(lines[-1].split(",")[0])
        except (IndexError, ValueError):
            raise StudyError(f"= {source!r}: its last line gives no time (a CSV with columns time and any of "
                             f"{', '.join(POSE)})") from None
        values = trajectory_parameters({axis: Signal(offset=0.0) for axis in POSE}, table=given, interpolation="cubic")
        neutral, name = np.zeros(6), given.stem
    if not duration > 0:
        raise StudyError(f"= {source!r}: lasts {duration:g} s; a motion needs a positive duration")
    step = duration / (samples - 1)
    try:
        times, poses, _ = play(values, duration, step)
    except Exception as error:  # the trajectory FMU's refusal (a bad table: its file and line)
        raise StudyError(f"= {source!r}: {error}") from None
    displacement = poses - neutral
    return Recorded(name, times, displacement, np.gradient(displacement, step, axis=0, edge_order=2),
                    second_difference(displacement, step))


def second_difference(x: np.ndarray, step: float) -> np.ndarray:
    """The second derivative of evenly sampled rows, to second order: central differences inside,
    the one-sided four-point formula (2, -5, 4, -1) at both ends."""
    out = np.empty_like(x)
    out[1:-1] = x[2:] - 2 * x[1:-1] + x[:-2]
    out[0] = 2 * x[0] - 5 * x[1] + 4 * x[2] - x[3]
    out[-1] = 2 * x[-1] - 5 * x[-2] + 4 * x[-3] - x[-4]
    return out / step ** 2


# -- on every core --------------------------------------------------------------------------------

def _rows(study: Study, rows: list[int], dynamic: bool) -> DesignMap:
    """The map of some rows of the study's grid (a task of a parallel map)."""
    (row_key, values), (column_key, columns) = list(study.axes.items())
    part = copy.copy(study)
    part.axes = {row_key: values[rows], column_key: columns}
    return design_map(part, dynamic)


def parallel_map(study: Study, dynamic: bool = True, workers: int | None = None,
                 scheduler: str | None = None) -> DesignMap:
    """design_map with its rows on Dask (a LocalCluster of `workers` processes, default one per
    core, or a running scheduler); workers = 0: in this process. Bit for bit the in-process map."""
    if workers == 0 and scheduler is None:
        return design_map(study, dynamic)
    from ..engine.sweep.dask_run import dask_client
    start = time.perf_counter()
    with dask_client(workers, scheduler) as client:
        n = max(len(client.scheduler_info()["workers"]), 1)
        rows = np.array_split(np.arange(len(next(iter(study.axes.values())))), 4 * n)
        parts = client.gather(client.map(_rows, [study] * len(rows), [list(r) for r in rows if len(r)],
                                         [dynamic] * len(rows), pure=False))
    merged = {name: np.concatenate([getattr(p, name) for p in parts]) for name in
              ("length_max", "length_min", "neutral_length", "top_angle", "bottom_angle", "smallest_singular",
               "condition", *(("force_paper", "force_full", "leg_speed") if dynamic else ()))}
    return DesignMap(study, parts[0].motions, seconds=time.perf_counter() - start, **merged)


# -- what the paper shows ---------------------------------------------------------------------------

def _plane(design: DesignMap):
    """A figure in the plane of the study's two axes (labelled), and the axes' names and values."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    (row_key, rows), (column_key, columns) = list(design.study.axes.items())
    fig, ax = plt.subplots(figsize=(8, 6))
    ax.set_xlabel(row_key.replace("_", " ") + (f" [{unit(row_key)}]" if unit(row_key) else ""))
    ax.set_ylabel(column_key.replace("_", " ") + (f" [{unit(column_key)}]" if unit(column_key) else ""))
    return plt, fig, ax, (row_key, rows), (column_key, columns)


LINES = {"max stroke": "-", "min stroke": "--", "joint angle": "-.", "force": "-", "force, full model": ":"}
COLOURS = {"surge": "tab:blue", "sway": "tab:orange", "heave": "tab:green", "roll": "tab:red", "pitch": "tab:purple",
           "yaw": "tab:brown"}


def plot_kinematic(design: DesignMap, actuator: Actuator, path: Path, marks: dict[str, tuple[float, float]]) -> Path:
    """Halder's Figs 2 and 3: per basic motion and constraint, the limiting curve (solid: max stroke,
    dashed: min stroke, dash-dot: joint angle) in the base radius - disc height plane, the zone
    where every constraint of every motion holds shaded, and the named points marked."""
    plt, fig, ax, (row_key, rows), (column_key, columns) = _plane(design)
    ok = design.admissible(actuator)
    if ok.any():
        ax.contourf(rows, columns, ok.T.astype(float), levels=[0.5, 1.5], colors=["0.85"])
    for constraint, admissible in design.kinematic_admissible(actuator).items():
        for m, motion in enumerate(design.motions):
            grid = admissible[:, :, m].T.astype(float)
            if 0 < grid.mean() < 1:
                ax.contour(rows, columns, grid, levels=[0.5], colors=[COLOURS.get(motion, "tab:blue")], linestyles=LINES[constraint])
    for label, (x, y) in marks.items():
        ax.plot(x, y, "k.", markersize=7)
        ax.annotate(label, (x, y), textcoords="offset points", xytext=(5, 3))
    handles = [plt.Line2D([], [], color=COLOURS.get(m, "tab:blue"), label=m) for m in design.motions] + \
        [plt.Line2D([], [], color="k", linestyle=LINES[c], label=c) for c in ("max stroke", "min stroke", "joint angle")]
    ax.legend(handles=handles, fontsize=8, ncol=3, loc="upper right")
    ax.set_title(f"{actuator.name}: running length {actuator.running_length_min:g}-{actuator.running_length_max:g} m, "
                 "joint angle < " + ("{:g}".format(*map(math.degrees, design.study.joint_limits))
                                     if len(set(design.study.joint_limits)) == 1 else
                                     "{:g} (top), {:g} (bottom)".format(*map(math.degrees, design.study.joint_limits)))
                 + " deg (admissible: shaded)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_dynamic(design: DesignMap, actuator: Actuator, path: Path, marks: dict[str, tuple[float, float]]) -> Path:
    """Halder's Fig 4: the peak force limit (the paper's payload-only model, solid; our full model,
    dotted), where the actuator gives them its peak force (full model, dashed) and speed (grey), and
    the stroke limits of the heave motion (or of the one recorded motion); the zone where all of
    them and every other kinematic constraint hold shaded."""
    plt, fig, ax, (row_key, rows), (column_key, columns) = _plane(design)
    ok = design.admissible(actuator, dynamic=True)
    if ok.any():
        ax.contourf(rows, columns, ok.T.astype(float), levels=[0.5, 1.5], colors=["0.85"])
    allowed = design.study.allowed_force(actuator)
    lines = [(design.force_paper <= allowed, "k", "-", f"peak force = {allowed:.0f} N (payload only)"),
             (design.force_full <= allowed, "k", ":", "the same, legs' inertia and friction included")]
    if actuator.peak_force is not None:
        lines.append((design.force_full <= actuator.peak_force, "k", "--",
                      f"peak force = {actuator.peak_force:.0f} N (the actuator's peak, full model)"))
    if actuator.speed is not None:
        lines.append((design.leg_speed <= actuator.speed, "0.5", "-", f"leg speed = {actuator.speed:g} m/s"))
    motion = "heave" if "heave" in design.motions else design.motions[0] if len(design.motions) == 1 else None
    if motion is not None:
        kinematic = design.kinematic_admissible(actuator)
        for constraint, style in (("min stroke", "--"), ("max stroke", "-.")):
            lines.append((kinematic[constraint][:, :, [design.motions.index(motion)]], COLOURS.get(motion, "tab:blue"),
                          style, f"{motion}: {constraint}"))
    handles = []
    for holds, colour, style, label in lines:
        grid = holds.all(axis=2).T.astype(float)
        handles.append(plt.Line2D([], [], color=colour, linestyle=style, label=label))
        if 0 < grid.mean() < 1:
            ax.contour(rows, columns, grid, levels=[0.5], colors=[colour], linestyles=style)
    for label, (x, y) in marks.items():
        ax.plot(x, y, "k.", markersize=7)
        ax.annotate(label, (x, y), textcoords="offset points", xytext=(5, 3))
    ax.legend(handles=handles, fontsize=8, loc="upper right")
    friction, other = design.study.force_margins
    ax.set_title(f"{actuator.name}: {actuator.continuous_force:g} N continuous less {friction:.0%} and {other:.0%} "
                 "margins (admissible: shaded)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# -- the paper's numbers beside ours ----------------------------------------------------------------

PAPER = {"a": 1.19, "b": 1.06, "c": 0.62, "chosen": (1.10, 1.40), "lengths": (1.286, 1.647, 1.886),
         "zone_450": (1.25, 0.95), "zone_600": (1.10, 1.40)}


def nearest(study: Study, point: tuple[float, float]) -> tuple[int, int]:
    (_, rows), (_, columns) = list(study.axes.items())
    return int(np.argmin(np.abs(rows - point[0]))), int(np.argmin(np.abs(columns - point[1])))


def paper_rows(design: DesignMap) -> list:
    """Section V's stated numbers beside ours (validation rows), and what the paper's
    simplification of the dynamics costs, for a study over base_radius and disc_height."""
    from .report.rows import Row
    study = design.study
    (_, rows), (_, columns) = list(study.axes.items())
    s = stubs(study)
    short, long_ = min(study.actuators, key=lambda a: a.stroke), max(study.actuators, key=lambda a: a.stroke)
    out = []
    if "sway" in design.motions and rows[0] <= 1.03 <= rows[-1]:
        for label, constraint in (("a", "max stroke"), ("b", "min stroke"), ("c", "joint angle")):
            found = limit_along(design, short, constraint, "sway", 1.03)
            out.append(Row(f"point {label}: sway at r_b = 1.03 m, {constraint} limit ({short.name})",
                           f"{PAPER[label]:.2f}", "none" if found is None else found, "m of z_p0",
                           "" if found is not None and abs(found - PAPER[label]) < 1e-9 else "one grid step (0.01 m)"))
    for actuator, key in ((short, "zone_450"), (long_, "zone_600")):
        ok = design.admissible(actuator)
        r, c = np.nonzero(ok)
        out.append(Row(f"kinematically admissible zone, {actuator.name}", f"around ({PAPER[key][0]:.2f}, {PAPER[key][1]:.2f})",
                       f"centroid ({rows[r].mean():.2f}, {columns[c].mean():.2f}), {ok.sum()} points" if ok.any() else "none",
                       "m (r_b, z_p0)", "a band along the heave stroke limits, as the paper's figure"))
    r, c = nearest(study, PAPER["chosen"])
    admissible = design.kinematic_admissible(long_)
    failing = [f"{name} in {', '.join(m for k, m in enumerate(design.motions) if not v[r, c, k])}"
               for name, v in admissible.items() if not v[r, c].all()]
    highest = limit_along(design, long_, "max stroke", "heave", PAPER["chosen"][0])
    out.append(Row(f"r_b = 1.10 m, z_p0 = 1.40 m with {long_.name}", "admissible",
                   "admissible" if not failing else "outside: " + "; ".join(failing), "",
                   "" if not failing else f"+0.3 m heave needs the running length below; the highest admissible z_p0 at "
                   f"r_b = 1.10 m is {highest} m"))
    needed = (design.length_min[r, c].min() + s, design.neutral_length[r, c] + s, design.length_max[r, c].max() + s)
    out.append(Row("running lengths there, min / neutral / max", " / ".join(f"{1e3 * v:.0f}" for v in PAPER["lengths"]),
                   " / ".join(f"{1e3 * v:.0f}" for v in needed), "mm",
                   "the paper quotes the actuator's limits, we what the six motions need; the neutral matches by "
                   "construction (params/halder2013.toml)"))
    if design.force_paper is not None:
        allowed = study.allowed_force(long_)
        out.append(Row("peak leg force there, payload only (Eq 16)", f"below {allowed:.0f}", float(design.force_paper[r, c].max()),
                       "N", f"{long_.continuous_force:g} N / (1 + {study.force_margins[0]:g}) / (1 + {study.force_margins[1]:g}); "
                       "the margins read as factors on the demand"))
        out.append(Row("the same with the legs' weight, inertia and friction", "", float(design.force_full[r, c].max()), "N",
                       "what the paper's simplification leaves out"))
        full_ok = design.admissible(long_) & (design.force_full.max(axis=2) <= allowed)
        out.append(Row("admissible points with the force limit", "", f"{design.admissible(long_, True).sum()} / "
                       f"{full_ok.sum()} of {design.admissible(long_).sum()}", "points",
                       "payload only / full model, of the kinematically admissible"))
    share = float(np.mean(design.bottom_angle > design.top_angle + 1e-9))
    out.append(Row("bottom joint angle above the top one", "never", f"{share:.1%} of points and motions", "", ""))
    out.append(Row("leg Jacobian at r_b = 1.10 m, z_p0 = 1.40 m over the motions", "",
                   f"smallest singular value {design.smallest_singular[r, c].min():.3f}, condition number "
                   f"{design.condition[r, c].max():.1f}", "", "far from a singular pose"))
    return out


def is_section5(study: Study) -> bool:
    """A study of Halder's layout in the paper's plane (r_b, z_p0): its stated numbers apply."""
    return study.parameter_set == "halder2013" and list(study.axes) == ["base_radius", "disc_height"]


def map_rows(design: DesignMap) -> list:
    """Any study's answer: per actuator the admissible designs (kinematic, then with its forces and
    speed) and their extent along each axis; the smallest stroke that carries every motion within
    the joint limit, where, and the running lengths it needs there."""
    from .report.rows import Row
    study = design.study
    (row_key, rows), (column_key, columns) = list(study.axes.items())
    out = []
    for actuator in study.actuators:
        kinematic, both = design.admissible(actuator), design.admissible(actuator, dynamic=True)
        failing = {name: float(np.mean(~holds.all(axis=2))) for name, holds in
                   {**design.kinematic_admissible(actuator), **design.dynamic_admissible(actuator)}.items()}
        r, c = np.nonzero(both)
        extent = f"{span(row_key, rows[r])}, {span(column_key, columns[c])}" if both.any() else "none"
        out.append(Row(f"admissible designs, {actuator.name}", "", f"{kinematic.sum()} / {both.sum()} of {design.points}",
                       "points", f"kinematic / with forces and speed; {extent}; each limit fails at: " + ", ".join(
                           f"{name} {share:.0%}" for name, share in failing.items())))
    joints = study.joints_within(design.top_angle, design.bottom_angle).all(axis=2)
    needed = np.where(joints, design.length_max.max(axis=2) - design.length_min.min(axis=2), np.inf)
    if np.isfinite(needed).any():
        r, c = np.unravel_index(np.argmin(needed), needed.shape)
        s = stubs(study)
        out.append(Row("the smallest stroke that carries every motion, over the grid (joint limit held)", "", float(needed[r, c]), "m",
                       f"at {value(row_key, rows[r])}, {value(column_key, columns[c])}: running length "
                       f"{design.length_min[r, c].min() + s:.3f} to {design.length_max[r, c].max() + s:.3f} m"
                       + ("; on the grid's edge: a wider grid may need less" if r in (0, len(rows) - 1)
                          or c in (0, len(columns) - 1) else "")))
    else:
        out.append(Row("the smallest stroke that carries every motion", "", "none", "",
                       "the joint limit fails at every design of the grid"))
    return out


def report_rows(design: DesignMap, workers: int | None = 0, scheduler: str | None = None) -> list:
    """The map's rows (beside the paper's numbers for Halder's Section V plane), then the
    [workspace] design's and the [optimise] optimum's, where the study names them (the
    optimiser's designs on Dask as workers/scheduler say)."""
    space, best = study_workspace(design.study), study_optimum(design.study, workers, scheduler)
    runs = study_confirmation(design.study, workers, scheduler)
    return (paper_rows(design) if is_section5(design.study) else []) + map_rows(design) + \
        (workspace_rows(design.study, space) if space else []) + \
        (optimum_rows(design.study, best) if best else []) + (confirmation_rows(design.study, runs) if runs else [])


def summary(design: DesignMap, rows: list | None = None) -> list[str]:
    """Markdown lines: the grid, the rows (report_rows unless given), the map's speed."""
    from .report.rows import table
    (row_key, grid_rows), (column_key, columns) = list(design.study.axes.items())
    return [f"Grid: {span(row_key, grid_rows)} x {span(column_key, columns)}, {design.points} points, " + (f"the motion of {design.study.recorded.name} "
                                             f"({len(design.study.recorded.times)} samples)." if design.study.recorded else
                                             f"{len(design.motions)} basic motions ({', '.join(design.motions)})."), "",
            table(rows if rows is not None else report_rows(design)), "",
            f"The map took {design.seconds:.1f} s ({design.points / design.seconds:.0f} grid points per second, each "
            + ("over the motion)." if design.study.recorded else "over every basic motion).")]


def write(design: DesignMap, out: Path, rows: list | None = None) -> list[Path]:
    """The figures (Halder's Figs 2 and 3 per actuator, Fig 4 for the longest stroke), the summary
    and the map as a table (one row per grid point and basic motion) into `out`."""
    import pyarrow as pa
    import pyarrow.csv
    import pyarrow.parquet as pq
    out.mkdir(parents=True, exist_ok=True)
    stem = design.study.path.stem
    (row_key, radii), (column_key, columns) = list(design.study.axes.items())
    written = []
    short = min(design.study.actuators, key=lambda a: a.stroke)
    marks, chosen = {}, {"chosen": PAPER["chosen"]} if is_section5(design.study) else {}
    if is_section5(design.study) and "sway" in design.motions and radii[0] <= 1.03 <= radii[-1]:
        for label, constraint in (("a", "max stroke"), ("b", "min stroke"), ("c", "joint angle")):
            found = limit_along(design, short, constraint, "sway", 1.03)
            if found is not None:
                marks[label] = (1.03, found)
    for k, actuator in enumerate(design.study.actuators):
        own = marks if actuator is short else chosen
        written.append(plot_kinematic(design, actuator, out / f"{stem}_kinematic_{k + 1}.png", own))
    long_ = max(design.study.actuators, key=lambda a: a.stroke)
    if design.force_paper is not None:
        written.append(plot_dynamic(design, long_, out / f"{stem}_dynamic.png", chosen))
    r, c, m = np.meshgrid(np.arange(len(radii)), np.arange(len(columns)), np.arange(len(design.motions)), indexing="ij")
    table = {row_key: radii[r].ravel(), column_key: columns[c].ravel(), "motion": np.array(design.motions)[m].ravel(),
             "length_min": design.length_min.ravel(), "length_max": design.length_max.ravel(),
             "top_angle": design.top_angle.ravel(), "bottom_angle": design.bottom_angle.ravel(),
             "smallest_singular": design.smallest_singular.ravel(), "condition": design.condition.ravel()}
    if design.force_paper is not None:
        table.update(force_paper=design.force_paper.ravel(), force_full=design.force_full.ravel(),
                     leg_speed=design.leg_speed.ravel())
    arrow = pa.table(table)
    pq.write_table(arrow, out / f"{stem}.parquet")
    pa.csv.write_csv(arrow, out / f"{stem}.csv")
    (out / f"{stem}.md").write_text("\n".join([f"# {design.study.name}", "", *summary(design, rows), ""]))
    return [*written, out / f"{stem}.parquet", out / f"{stem}.csv", out / f"{stem}.md"]


def validation(figures: Path) -> tuple[list, DesignMap]:
    """The validation report's Section V study: the shipped study's map, its rows and Figs 2-4
    (figures/halder_fig2.png, fig3, fig4)."""
    from ..engine.artifacts import data_dir
    study = load_study(data_dir("studies") / "halder_section5.toml")
    design = design_map(study)
    short, long_ = min(study.actuators, key=lambda a: a.stroke), max(study.actuators, key=lambda a: a.stroke)
    marks = {label: (1.03, found) for label, constraint in (("a", "max stroke"), ("b", "min stroke"), ("c", "joint angle"))
             if (found := limit_along(design, short, constraint, "sway", 1.03)) is not None}
    plot_kinematic(design, short, figures / "halder_fig2.png", marks)
    plot_kinematic(design, long_, figures / "halder_fig3.png", {"chosen": PAPER["chosen"]})
    plot_dynamic(design, long_, figures / "halder_fig4.png", {"chosen": PAPER["chosen"]})
    return report_rows(design), design


# -- workspace and singularity ----------------------------------------------------------------------

@dataclass
class Workspace:
    """A design's reachable workspace under an actuator's running lengths and the joint limit: the
    positions reachable at the neutral orientation (a grid of `spacing`), the orientations
    reachable at the neutral position (a grid of `angle_step`), the leg Jacobian's conditioning
    over the reachable positions, and along each DOF from the neutral the distance to the nearest
    singular pose (inf where none lies within `reach`)."""
    positions: np.ndarray        # reachable positions (n x 3) [m]
    spacing: float
    orientations: np.ndarray     # reachable (roll, pitch, yaw) (n x 3) [rad]
    angle_step: float
    smallest_singular: float     # over the reachable positions
    condition: float
    singular_distance: dict[str, float]  # per DOF [m or rad]

    @property
    def volume(self) -> float:
        """[m^3] the reachable positions' cells."""
        return len(self.positions) * self.spacing ** 3

    def reach(self) -> dict[str, tuple[float, float]]:
        """Per DOF the smallest and largest reachable displacement on its own axis (m, rad)."""
        out = {}
        for k, dof in enumerate(DOFS):
            points = self.positions if k < 3 else self.orientations
            others = np.delete(np.arange(3), k % 3)
            on_axis = points[np.all(np.abs(points[:, others]) < 1e-12, axis=1), k % 3]
            out[dof] = (float(on_axis.min()), float(on_axis.max())) if len(on_axis) else (0.0, 0.0)
        return out


def reachable(core: Core, poses: np.ndarray, actuator: Actuator, joint_limit: float | tuple[float, float],
              stub_length: float) -> np.ndarray:
    """Which poses keep every leg's running length within the actuator's and both joint angles
    within the limit (Eq 21 at one pose); joint_limit: both joints', or (top, bottom)."""
    top_limit, bottom_limit = joint_limit if isinstance(joint_limit, tuple) else (joint_limit, joint_limit)
    k = core.pose_kinematics(poses)
    running = k["length"] + stub_length
    return (np.all(running <= actuator.running_length_max, axis=1) & np.all(running >= actuator.running_length_min, axis=1)
            & np.all(k["upper_angle"] <= top_limit, axis=1) & np.all(k["lower_angle"] <= bottom_limit, axis=1))


def singular_distance(core: Core, reach: float = 1.0, angular_reach: float = math.pi, samples: int = 2001) -> dict:
    """Along each DOF alone from the neutral pose, the smallest displacement (either sign) at which
    the leg Jacobian turns singular: where its determinant changes sign between two samples,
    refined by bisection; inf if it does not within +-reach (m) or +-angular_reach (rad)."""
    neutral = core.neutral_pose
    out = {}

    def det(poses: np.ndarray) -> np.ndarray:
        return np.linalg.det(core.pose_kinematics(poses, jacobian=True)["jacobian"])

    for k, dof in enumerate(DOFS):
        limit = angular_reach if dof in ROTATIONS else reach
        best = math.inf
        for sign in (1.0, -1.0):
            steps = sign * np.linspace(0.0, limit, samples)
            poses = np.tile(neutral, (samples, 1))
            poses[:, k] += steps
            d = det(poses)
            change = np.nonzero(np.sign(d[1:]) != np.sign(d[:-1]))[0]
            if not len(change):
                continue
            low, high = steps[change[0]], steps[change[0] + 1]
            for _ in range(60):  # bisection on the sign of det J
                middle = 0.5 * (low + high)
                pose = neutral.copy()
                pose[k] += middle
                if np.sign(det(pose[None])[0]) == np.sign(d[change[0]]):
                    low = middle
                else:
                    high = middle
            best = min(best, abs(0.5 * (low + high)))
        out[dof] = best
    return out


def workspace(study: Study, point: dict[str, float], actuator: Actuator, spacing: float = 0.02,
              angle_step: float = math.radians(1.0), extent: float = 0.8, angular_extent: float = math.radians(45.0)) -> Workspace:
    """The workspace of the design at `point` (see Workspace): positions within +-extent of the
    neutral on each axis, orientations within +-angular_extent."""
    core = Core(actuators=False, motors=False, friction=False).use_start_values(platform_values(study, point))
    neutral = core.neutral_pose
    s = stubs(study)

    def cube(first: int, half: float, step: float) -> np.ndarray:
        """Poses about the neutral on a grid over three coordinates from `first` on."""
        axis = np.arange(-half, half + step / 2, step)
        grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
        poses = np.tile(neutral, (len(grid), 1))
        poses[:, first:first + 3] += grid
        return poses

    poses = cube(0, extent, spacing)
    ok = reachable(core, poses, actuator, study.joint_limits, s)
    positions = poses[ok, :3] - neutral[:3]
    turned = cube(3, angular_extent, angle_step)
    orientations = turned[reachable(core, turned, actuator, study.joint_limits, s), 3:] - neutral[3:]
    sample = poses[ok][:: max(1, ok.sum() // 5000)]
    singular = np.linalg.svd(core.pose_kinematics(sample, jacobian=True)["jacobian"], compute_uv=False) \
        if len(sample) else np.full((1, 6), np.nan)
    return Workspace(np.round(positions, 12), spacing, np.round(orientations, 12), angle_step,
                     float(singular[:, -1].min()), float((singular[:, 0] / singular[:, -1]).max()),
                     singular_distance(core))


def study_workspace(study: Study) -> Workspace | None:
    """The workspace of the study's [workspace] design, or None if it names none."""
    if study.workspace is None:
        return None
    actuator = next(a for a in study.actuators if a.name == study.workspace["actuator"])
    return workspace(study, study.workspace["point"], actuator, study.workspace["spacing"],
                     study.workspace["angle_step"])


def workspace_rows(study: Study, space: Workspace) -> list:
    """The [workspace] design's reach, volume, conditioning and singular distances as rows."""
    from .report.rows import Row
    where = ", ".join(value(k, v) for k, v in study.workspace["point"].items())
    reach = space.reach()
    lines = [Row(f"reachable positions at the neutral orientation ({where}, {study.workspace['actuator']})", "",
                 space.volume, "m^3", f"a {1e3 * space.spacing:g} mm grid; on the axes: " + ", ".join(
                     f"{d} {reach[d][0]:+.2f}/{reach[d][1]:+.2f} m" for d in ("surge", "sway", "heave"))),
             Row("reachable orientations at the neutral position, each alone", "",
                 ", ".join(f"{d} {math.degrees(reach[d][0]):+.0f}/{math.degrees(reach[d][1]):+.0f}" for d in ROTATIONS),
                 "deg", f"{len(space.orientations)} of the {math.degrees(space.angle_step):g} deg grid's orientations "
                 "reachable"),
             Row("leg Jacobian over the reachable positions", "",
                 f"smallest singular value {space.smallest_singular:.3f}, condition number {space.condition:.1f}", "", ""),
             Row("nearest singular pose along each DOF from the neutral", "(left open by the papers)",
                 ", ".join(f"{d} {math.degrees(v):.1f} deg" if d in ROTATIONS else f"{d} {v:.3f} m"
                           for d, v in space.singular_distance.items() if math.isfinite(v)) or "none",
                 "", "translations: none within 1 m" if not any(math.isfinite(space.singular_distance[d])
                                                                 for d in ("surge", "sway", "heave")) else "")]
    return lines


# -- beyond one grid: the design with the largest worst-case margin -------------------------------

def margins(study: Study, point: dict[str, float], actuator: Actuator) -> dict[str, float]:
    """A design's margins against each constraint over every basic motion, each as a fraction of
    what it is measured against (negative: violated): the stroke at both ends (of the stroke), the
    joint angle (of the limit) and the peak force of the paper's model (of the allowed force)."""
    part = copy.copy(study)
    part.axes = {key: np.array([value]) for key, value in point.items()}
    design = design_map(part, dynamic=True)
    s = stubs(study)
    return {"max stroke": float((actuator.running_length_max - s - design.length_max.max()) / actuator.stroke),
            "min stroke": float((design.length_min.min() + s - actuator.running_length_min) / actuator.stroke),
            "joint angle": float(1 - max(design.top_angle.max() / study.joint_limits[0],
                                         design.bottom_angle.max() / study.joint_limits[1])),
            "force": float(1 - design.force_paper.max() / study.allowed_force(actuator))}


def _negative_margin(x: np.ndarray, study: Study, keys: tuple[str, ...], actuator: Actuator) -> float:
    return -min(margins(study, dict(zip(keys, map(float, x))), actuator).values())


@dataclass
class Optimum:
    point: dict[str, float]
    margins: dict[str, float]
    evaluations: int
    seconds: float


def optimise(study: Study, actuator: Actuator, workers: int | None = 0, scheduler: str | None = None,
             seed: int = 1, max_iterations: int = 60) -> Optimum:
    """The design (within the study's axes' ranges) whose smallest margin over every constraint and
    basic motion is largest: the most robust admissible design, found by scipy's differential
    evolution (one objective: the worst margin; a Pareto front would need a second, which the
    papers' specification does not give). Its evaluations run on Dask when workers/scheduler say
    so (each a design of the map), in this process otherwise; the same seed gives the same design."""
    from contextlib import nullcontext
    from functools import partial
    from scipy.optimize import differential_evolution
    from ..engine.sweep.dask_run import dask_client
    keys = tuple(study.axes)
    bounds = [(float(v[0]), float(v[-1])) for v in study.axes.values()]
    start = time.perf_counter()
    objective = partial(_negative_margin, study=study, keys=keys, actuator=actuator)
    with (dask_client(workers, scheduler) if workers != 0 or scheduler else nullcontext()) as client:

        def mapper(function, points):  # what differential_evolution evaluates its population through
            return client.gather(client.map(function, list(points), pure=False)) if client else list(map(function, points))
        result = differential_evolution(objective, bounds, seed=seed, maxiter=max_iterations, tol=1e-6, polish=False,
                                        updating="deferred", workers=mapper)
    point = dict(zip(keys, map(float, result.x)))
    return Optimum(point, margins(study, point, actuator), int(result.nfev), time.perf_counter() - start)


def study_optimum(study: Study, workers: int | None = 0, scheduler: str | None = None) -> Optimum | None:
    """The most robust design for the study's [optimise] actuator, or None if it names none."""
    if study.optimise is None:
        return None
    actuator = next(a for a in study.actuators if a.name == study.optimise["actuator"])
    return optimise(study, actuator, workers, scheduler, study.optimise["seed"], study.optimise["iterations"])


def optimum_rows(study: Study, best: Optimum) -> list:
    from .report.rows import Row
    where = ", ".join(value(k, v, ".3f") for k, v in best.point.items())
    worst = min(best.margins, key=best.margins.get)
    return [Row(f"the most robust design for {study.optimise['actuator']} (largest worst-case margin)", "", where, "",
                f"differential evolution, {best.evaluations} designs; margins: " + ", ".join(
                    f"{k} {v:.1%}" for k, v in best.margins.items()) + f" (the least: {worst})")]


# -- a scene's motion as the specification ----------------------------------------------------------

@dataclass
class SceneFit:
    """What a scene's reference motion asks of its platform's legs, and which value of one
    geometry parameter carries it within the stroke and the joint limit."""
    parameter: str
    values: np.ndarray          # the parameter's values tried
    shortest: np.ndarray        # per value, the shortest leg over the motion [m]
    longest: np.ndarray         # the longest [m]
    joint_angle: np.ndarray     # the largest joint angle [rad]
    stroke: tuple[float, float]  # the platform's [m]
    joint_limit: float          # [rad]

    @property
    def needed_stroke(self) -> np.ndarray:
        return self.longest - self.shortest

    @property
    def carries(self) -> np.ndarray:
        return (self.shortest >= self.stroke[0]) & (self.longest <= self.stroke[1]) & (self.joint_angle <= self.joint_limit)


def scene_fit(scene, parameter: str, values: np.ndarray, samples: int = 2001) -> SceneFit:
    """The scene's reference motion (its trajectory FMU run alone: the one evaluation of its
    signals) on its own platform with `parameter` (a mechanics parameter, e.g.
    geometry.middle_leg_length) at each of `values`: every leg's range and the largest joint angle
    through the dynamics core, against the platform's stroke and joint limit. The motion is the
    reference poses; a parameter that moves the neutral moves the platform under them (the scene's
    offsets at "neutral" follow it)."""
    from .core import mechanics_value
    from .run.runner import scene_values
    from .report.view3d import reference_motion
    shortest, longest, angle = [], [], []
    base_values = scene_values(scene)[0]
    stroke = (float(mechanics_value(base_values, "limit.leg_length_min")),
              float(mechanics_value(base_values, "limit.leg_length_max")))
    joint_limit = float(mechanics_value(base_values, "limit.joint_angle"))
    core = Core(actuators=False, motors=False, friction=False)
    for value in values:
        changed = scene.changed({f'mechanics.parameters."{parameter}"': float(value)})
        _, poses, _ = reference_motion(changed, samples)
        core.use_start_values(scene_values(changed)[0])
        k = core.pose_kinematics(poses)
        shortest.append(k["length"].min())
        longest.append(k["length"].max())
        angle.append(max(k["upper_angle"].max(), k["lower_angle"].max()))
    return SceneFit(parameter, np.asarray(values, float), np.array(shortest), np.array(longest), np.array(angle),
                    stroke, joint_limit)


# -- a design confirmed by co-simulation ------------------------------------------------------------

HOLD = 0.5  # [s] at the start pose before a basic motion, and after it
START_UP = 0.2  # [s] of a motion that starts moving at once, left out of its forces and currents


def motion_profile(study: Study, motion: str) -> tuple[np.ndarray, ...]:
    """A motion of the study as the co-simulation plays it: times from 0, displacements from the
    neutral (n x 6), rates and accelerations; a basic motion's shortest-time move finely sampled
    (400 per phase), or the recorded motion."""
    if study.recorded is not None:
        r = study.recorded
        return r.times - r.times[0], r.displacement, r.rates, r.accelerations
    k, half, m = DOFS.index(motion), study.motion.ranges[motion], study.motion
    rotation = motion in ROTATIONS
    t, s, v, a = shortest_time(2 * half, m.angular_velocity if rotation else m.velocity,
                               m.angular_acceleration if rotation else m.acceleration, 400)
    keep = np.r_[True, np.diff(t) > 0]  # the phases' shared instants once
    out = [np.zeros((keep.sum(), 6)) for _ in range(3)]
    for array, column in zip(out, (s - half, v, a)):
        array[:, k] = column[keep]
    return (t[keep], *out)


DRIVEN = {"force": "ideal force sources (linear-motor FMUs, electrical model off)",
          "pmsm": "our PMSM drive FMU (current, speed and position loops)",
          "linear": "our linear-motor drive FMU (its current loop and electrical model)"}


def drive_parameters(study: Study, drive: str) -> tuple[dict, dict, str]:
    """For a confirmation through our drive FMU of kind `drive`: its parameters and what it changes
    on the legs (the platform's drive set where the project has one, e.g. meng2010_linear; the
    FMU's own defaults otherwise: Meng's PMSM, Sumnu's linear motor), and the drive's name."""
    from .scene.parameter_sets import drive_set, drive_set_name
    name = drive_set_name(study.parameter_set, drive)
    if name is None:
        return {}, {}, {"pmsm": "pmsm_drive (Meng's PMSM, Table 2)", "linear": "linear_motor (Sumnu's motor)"}[drive]
    drive_values, mechanics_values = drive_set(name)
    return drive_values, mechanics_values, f"the drive set {name}"


def confirm_motion(study: Study, point: dict[str, float], actuator: Actuator, dof: str, step: float = 1e-3,
                   folder: Path | None = None, drive: str = "force") -> dict[str, Any]:
    """One motion of a design, closed loop through the co-simulation: the mechanics FMU with the
    study's platform (legs, their weight, inertia and friction), six drives (DRIVEN: ideal force
    sources, or our PMSM or linear-motor drive FMU with the platform's drive set), their loops
    designed for each leg's plant (tuning "auto"), the trajectory FMU playing the motion from a
    table after HOLD s at its start. Returns the largest tracking error (m, rad) after the first
    HOLD; over the motion the peak and rms leg force [N] (a PMSM's torque times K_FT) against the
    actuator's continuous force, and the full inverse dynamics' peak along the reference [N]; with
    our drives the peak and rms current [A] against the drive's current limit and the current the
    actuator's continuous force takes. A drive that cannot hold the start pose returns its
    reason as "problem"."""
    import tempfile
    from ..engine import FixedStep
    from .scene import Signal
    from .scene.signals import trajectory_parameters
    from .ports import platform_algorithm
    from .run.system import columns, platform_structure, run
    from .run.tuning import SizingError, check_limit, check_sizing, design, drive_defaults, leg_plants
    t, displacement, rates, accelerations = motion_profile(study, dof)
    values = platform_values(study, point, effects=True)
    if drive == "force":
        kind, drive_values, what = "linear", {"effects.electrical": False, "motor.continuous_force": actuator.continuous_force,
                                              "limit.force": 1e6, "limit.current": 1e6}, DRIVEN["force"]
    else:
        kind = drive
        drive_values, on_legs, what = drive_parameters(study, drive)
        values.update(on_legs)
    core = Core().use_start_values(values)
    force_torque = float(core.p.force_torque) if kind == "pmsm" else 1.0
    neutral = core.neutral_pose
    start = neutral + displacement[0]
    values.update({f"initial.pose.{axis}": float(start[n]) for n, axis in enumerate(POSE)})
    duration = HOLD + t[-1] + HOLD
    scratch = tempfile.TemporaryDirectory(prefix="cosim-confirm-") if folder is None else None
    folder = Path(folder or scratch.name)  # the table lives until the run has read it
    try:
        folder.mkdir(parents=True, exist_ok=True)
        table = folder / f"{dof}.csv"
        times = np.r_[0.0, HOLD + t, duration]
        played = np.vstack([displacement[:1], displacement, displacement[-1:]])
        np.savetxt(table, np.column_stack([times, played]), delimiter=",", header=",".join(["time", *POSE]),
                   comments="")
        trajectory = trajectory_parameters({axis: Signal(offset=float(neutral[n])) for n, axis in enumerate(POSE)},
                                           table=table, interpolation="cubic")
        plants = leg_plants(values)
        try:
            for leg, plant in enumerate(plants, start=1):
                check_limit("linear", plant, actuator.continuous_force, f"{actuator.name}'s continuous force", leg)
            if drive != "force":
                check_sizing(kind, plants, drive_values)
        except SizingError as error:
            return {"motion": dof, "drive": what, "problem": str(error)}
        legs = [design(kind, [plant], drive_values)[0] for plant in plants]
        effort, current = ("torque", "current.q") if kind == "pmsm" else ("force", "current")
        # our drives through the interface Jacobian (their damping integrated implicitly by the
        # mechanics: stable at the macro step on any geometry), their efforts as the legs felt them
        jacobian = drive != "force"
        structure = platform_structure(kind, values, drive_values, trajectory, leg_values=legs,
                                       interface_jacobian=jacobian)
        # our drives' start-up shock and the motion's start (a jump of the reference's rate where a
        # recorded motion starts moving) at a sixteenth of the step, as the shipped scenes take them
        control = FixedStep(step) if drive == "force" else \
            FixedStep(step, 0.1, step / 16, ((HOLD - step, HOLD + 0.02),))
        outcome = run(structure, platform_algorithm(kind), control, duration, columns(kind, drive_outputs=(effort, current),
                                                                            applied=jacobian))
    finally:
        if scratch is not None:
            scratch.cleanup()
    result = outcome.result
    # over the motion; where it starts moving at once (a recorded motion's rate at its start), from
    # START_UP later: no actuator follows a jump of speed, and its shock is the drive's, not the design's
    begins = HOLD + (START_UP if np.abs(rates[0]).max() > 0 else 0.0)
    late = result["time"] >= begins
    tracking = max(float(np.abs(result[f"pose.{axis}"] - result[f"pose_ref.{axis}"])[late].max()) for axis in POSE)
    forces = force_torque * np.column_stack([result[f"{effort}{'_applied' if jacobian else ''}[{i}]"]
                                             for i in range(1, 7)])
    poses = neutral + displacement
    core.p.force_torque = 1.0
    predicted = float(np.abs(core.inverse_dynamics_many(poses, rates, accelerations)).max())
    moving = late & (result["time"] <= HOLD + t[-1])
    out = {"motion": dof, "drive": what, "tracking": tracking, "peak_force": float(np.abs(forces[moving]).max()),
           "rms_force": float(np.sqrt(np.mean(forces[moving] ** 2))), "predicted_peak": predicted,
           "continuous_force": actuator.continuous_force, "steps": len(result) - 1, "from": begins - HOLD}
    if drive != "force":
        given = {**drive_defaults(kind), **drive_values}
        currents = np.column_stack([result[f"{current}[{i}]"] for i in range(1, 7)])[moving]
        per_ampere = force_torque * given["motor.torque_constant"] if kind == "pmsm" else given["motor.force_constant"]
        out.update(peak_current=float(np.abs(currents).max()), rms_current=float(np.sqrt(np.mean(currents ** 2))),
                   current_limit=float(given["limit.current"]), continuous_current=actuator.continuous_force / per_ampere)
    return out


def confirm(study: Study, point: dict[str, float], actuator: Actuator, workers: int | None = 0,
            scheduler: str | None = None, motions: tuple[str, ...] | None = None,
            drive: str = "force") -> list[dict[str, Any]]:
    """Every basic motion of a design through the co-simulation (confirm_motion), on Dask when
    workers/scheduler say so (one motion per task), in this process otherwise."""
    chosen = [m for m in _displacements(study, False) if motions is None or m in motions]
    if workers == 0 and scheduler is None:
        return [confirm_motion(study, point, actuator, dof, drive=drive) for dof in chosen]
    from ..engine.sweep.dask_run import dask_client
    with dask_client(workers, scheduler) as client:
        return client.gather([client.submit(confirm_motion, study, point, actuator, dof, drive=drive, pure=False)
                              for dof in chosen])


def study_confirmation(study: Study, workers: int | None = 0, scheduler: str | None = None) -> list | None:
    if study.confirm is None:
        return None
    actuator = next(a for a in study.actuators if a.name == study.confirm["actuator"])
    return confirm(study, study.confirm["point"], actuator, workers, scheduler, drive=study.confirm["drive"])


def confirmation_rows(study: Study, runs: list[dict[str, Any]]) -> list:
    from .report.rows import Row
    where = ", ".join(value(k, v) for k, v in study.confirm["point"].items())
    out = []
    for r in runs:
        quantity = f"co-simulated {r['motion']} ({where}, {study.confirm['actuator']}; {r['drive']})"
        if "problem" in r:
            out.append(Row(quantity, "", "cannot hold the start pose", "", r["problem"]))
            continue
        unit = "rad" if r["motion"] in ROTATIONS else "m" if r["motion"] in DOFS else "m, rad"
        note = (f"the full inverse dynamics' peak {r['predicted_peak']:.0f} N "
                f"({100 * (r['peak_force'] / r['predicted_peak'] - 1):+.1f} %); tracking within "
                f"{r['tracking']:.1e} {unit}; continuous {r['continuous_force']:g} N")
        if r.get("from"):
            note += f"; from {r['from']:g} s into the motion (it starts moving at once)"
        if "peak_current" in r:
            note += (f"; current peak {r['peak_current']:.1f} A (limit {r['current_limit']:g} A), rms "
                     f"{r['rms_current']:.1f} A (the continuous force takes {r['continuous_current']:.1f} A)")
        out.append(Row(quantity, "", f"peak {r['peak_force']:.0f} N, rms {r['rms_force']:.0f} N", "N", note))
    return out
