"""A design study as the program holds it: the platform family it sweeps, its two design axes, the
motion (basic motions, or a recorded time series), the actuators, the limits and margins, and
the designs it looks at more closely (workspace, optimum, co-simulated confirmation).

A family is a platform layout with its design values (Halder's 6-SBU, Meng's, Sumnu's), the
mechanics FMU's start values at a design (the one mapping, cosim.platform.scene.parameter_sets)
and the payload; `platform_values` gives the mechanics values of a design point.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ...scene.parameter_sets import halder_mechanics, read_parameter_set, meng_mechanics, sumnu_mechanics

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
ROTATIONS = ("roll", "pitch", "yaw")


@dataclass(frozen=True)
class Motor:
    """An actuator given by its motor, turning the leg's screw: its torques, speed and the rotor's
    (and screw's) inertia about its axis; the screw's lead makes them leg force and speed."""
    continuous_torque: float            # [N m]
    peak_torque: float | None = None    # [N m]
    speed: float | None = None          # [rad/s]
    rotor_inertia: float | None = None  # [kg m^2] (None: the parameter set's)
    efficiency: float = 1.0             # K_FT / i_theta: the screw's (and belt's) share of the power


@dataclass(frozen=True)
class Actuator:
    name: str
    stroke: float              # [m]
    running_length_min: float  # L_min [m]: the leg system, stubs included, at the shortest stroke
    continuous_force: float    # [N], 100 % duty cycle (a study may give the motor's torque: times K_FT)
    peak_force: float | None = None  # [N], what it gives for a moment (checked against the full model)
    speed: float | None = None       # [m/s], the largest extension rate (or the motor's speed / i_theta)
    motor: Motor | None = None       # given by its motor: the forces and speed above at `lead`
    lead: float | None = None        # [m] the screw's travel per motor turn the forces were turned at
    drive: str = "force"             # the drive a co-simulated confirmation runs it with (schema.DRIVEN)

    @property
    def running_length_max(self) -> float:
        return self.running_length_min + self.stroke

    def with_lead(self, lead: float) -> "Actuator":
        """A motor's actuator through a screw of another lead [m per turn]: leg force = torque x
        efficiency x 2 pi / lead, leg speed = motor speed x lead / (2 pi)."""
        m = self.motor
        ratio = 2 * math.pi / lead  # i_theta [rad/m]
        return replace(self, continuous_force=m.continuous_torque * m.efficiency * ratio,
                       peak_force=None if m.peak_torque is None else m.peak_torque * m.efficiency * ratio,
                       speed=None if m.speed is None else m.speed / ratio, lead=lead)

    def mechanics(self) -> dict[str, float]:
        """What the actuator sets on the mechanics FMU's legs: a motor's screw ratio, K_FT and rotor
        inertia (nothing for one given by its force)."""
        if self.motor is None or self.lead is None:
            return {}
        ratio = 2 * math.pi / self.lead
        out = {"transmission.screw_ratio": ratio, "transmission.force_torque": self.motor.efficiency * ratio}
        if self.motor.rotor_inertia is not None:
            out["motor_system.rotor_inertia"] = self.motor.rotor_inertia
        return out


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
class Recorded:
    """A motion given as a time series (a scene's reference or a recorded table): displacements
    from the design's neutral pose (n x 6, m and rad), their rates and accelerations."""
    name: str
    times: np.ndarray
    displacement: np.ndarray
    rates: np.ndarray
    accelerations: np.ndarray


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
    may_be_zero: tuple[str, ...] = ()  # design values that are not sizes (a stub, an offset): 0 is a design


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
                         lambda c: (c["payload"]["mass"], c["payload"]["inertia_diag"]), ("top_stub", "bottom_stub"),
                         ("top_stub", "bottom_stub", "payload_com_above_disc")),
    "meng2010": Family("Meng's layout (Table 1): joint pairs on two circles, the neutral height from the middle leg "
                       "length", lambda c: _scalars(c["geometry"]), lambda c, g: meng_mechanics(_with_geometry(c, g)),
                       lambda g: 0.0, lambda c: (c["platform"]["mass"], c["platform"]["inertia_diag"])),
    "sumnu2015": Family("Sumnu's motion-simulator layout (Section 4.2): joints point by point, scaled in the plane",
                        _sumnu_values, _sumnu_mechanics, lambda g: 0.0,
                        lambda c: (c["mass_sets"]["heavy"]["platform_mass"],
                                   c["mass_sets"]["heavy"]["platform_inertia_diag"])),
}


MARGIN_MODES = {  # how the force margins [friction, other] leave the force the demand may reach
    "subtract": "the continuous force less each margin's share of it: F (1 - friction - other), the paper's "
                "words (\"keeping 7% margin for friction and another 20% for other factors\")",
    "product": "the continuous force less one margin, then the other: F (1 - friction)(1 - other)",
    "divide": "the continuous force over the margins as factors on the demand: F / ((1 + friction)(1 + other))"}


def allowed(force: float, margins: tuple[float, float], mode: str) -> float:
    """The force the demand may reach [N] of an actuator's continuous force under the margins,
    read as `mode` (MARGIN_MODES)."""
    friction, other = margins
    return {"subtract": force * (1 - friction - other), "product": force * (1 - friction) * (1 - other),
            "divide": force / ((1 + friction) * (1 + other))}[mode]


OBJECTIVES = {  # [pareto] objectives: what each measures, and which way is better
    "stroke": "the stroke the motions need, the longest less the shortest actuated length over them [m], smaller",
    "force_margin": "1 - the full model's peak leg force / the force the margins leave the actuator, larger",
    "workspace": "the volume of positions reachable at the neutral orientation [m^3], larger",
    "conditioning": "the leg Jacobian's largest condition number over the motions, smaller",
    "actuator_force": "the actuator's continuous leg force [N], what its size costs, smaller"}
MAXIMISED = ("force_margin", "workspace")  # the objectives where larger is better


@dataclass(frozen=True)
class Thresholds:
    """[thresholds]: where the words the summary prints change (CONDITION_REASON, NEAR_REASON)."""
    condition_number: float = 20.0          # above it, ill conditioned
    singular_distance_factor: float = 2.0   # a singular pose nearer than this many motion ranges is near


CONDITION_REASON = ("the leg Jacobian's condition number bounds how much a relative error of the legs' lengths or "
                    "forces grows in the platform's pose or wrench: at 20 a 0.5 % leg error stays below 10 %")
NEAR_REASON = ("a singular pose twice the motion's range away along a DOF leaves the motion's own range again as "
               "margin for overshoot, a wider motion or a stop")


@dataclass(frozen=True)
class WorkspaceSpec:
    """[workspace]: the design whose reach is mapped, with which actuator, on which grids."""
    point: dict[str, float]
    actuator: str
    spacing: float     # [m] the positions' grid
    angle_step: float  # [rad] the orientations' grid


@dataclass(frozen=True)
class OptimiseSpec:
    """[optimise]: the actuator the most robust design is sought for, and the search's seed and
    iterations."""
    actuator: str
    seed: int
    iterations: int


@dataclass(frozen=True)
class ParetoSpec:
    """[pareto]: the objectives traded (pareto.OBJECTIVES), the catalogue the actuator is chosen
    from, the screw leads a motor's actuator may take, NSGA-II's population, generations and seed,
    the workspace objective's grid, and whether the knee and the extremes are co-simulated."""
    objectives: tuple[str, ...]
    actuators: tuple[str, ...]
    lead: tuple[float, float] | None  # [m per turn] from, to
    population: int
    generations: int
    seed: int
    workspace_spacing: float          # [m]
    confirm: bool


@dataclass(frozen=True)
class ConfirmSpec:
    """[confirm]: the design run through the co-simulation, its actuator and its drives."""
    point: dict[str, float]
    actuator: str
    drive: str  # "force" (ideal force sources), "pmsm" or "linear" (our drive FMUs)


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
    force_margins_mode: str = "subtract"   # MARGIN_MODES
    samples: int = 121               # poses per basic motion along its path
    phase_samples: int = 11          # poses per phase (accelerate, cruise, decelerate) of a timed motion
    fixed: dict[str, float] = field(default_factory=dict)  # geometry values over the parameter set's
    workspace: WorkspaceSpec | None = None
    optimise: OptimiseSpec | None = None
    confirm: ConfirmSpec | None = None
    recorded: Recorded | None = None  # [motion] scene or table: one motion, the time series
    top_joint_limit: float | None = None     # [rad] the top (universal) joint's own limit
    bottom_joint_limit: float | None = None  # [rad] the bottom (spherical) joint's own limit
    thresholds: Thresholds = Thresholds()
    chosen: dict[str, float] | None = None   # [study] chosen: the design the assumptions are judged at
    payload_from: str = "the parameter set"  # where the payload's mass and inertia come from
    pareto: ParetoSpec | None = None
    mechanics: dict[str, float] = field(default_factory=dict)  # mechanics values over the family's (an actuator's)

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

    def actuator(self, name: str) -> Actuator:
        return next(a for a in self.actuators if a.name == name)

    def allowed_force(self, actuator: Actuator, mode: str | None = None) -> float:
        """The force the demand may reach [N]: the continuous force under the study's margins, read
        as its force_margins_mode (or `mode`)."""
        return allowed(actuator.continuous_force, self.force_margins, mode or self.force_margins_mode)

    def step(self, key: str) -> float | None:
        """The spacing of an axis's grid (None for an axis of one value)."""
        values = self.axes[key]
        return float(np.round(np.min(np.diff(values)), 10)) if len(values) > 1 else None

    def decimals(self, key: str) -> int:
        """The decimals an axis's values print with: those its spacing and its first value need."""
        return max(decimals(self.step(key) or 0.0), decimals(float(self.axes[key][0])))

    def with_axes(self, axes: dict[str, np.ndarray]) -> "Study":
        """The study over other values of its axes (a part of its grid, one design)."""
        part = copy.copy(self)
        part.axes = axes
        return part

    def with_actuator(self, actuator: Actuator) -> "Study":
        """The study with the legs an actuator sets (a motor's screw and rotor) on its platform."""
        part = copy.copy(self)
        part.mechanics = {**self.mechanics, **actuator.mechanics()}
        return part


def unit(key: str) -> str:
    """A design value's unit as the parameter sets name them: *_deg in degrees, *_scale a factor,
    the rest lengths."""
    return "deg" if key.endswith("_deg") else "" if key.endswith("_scale") else "m"


def decimals(number: float, most: int = 6) -> int:
    """The fewest decimals that write `number` exactly (to 1e-9 of it), at most `most`: 2 for a
    0.01 m grid, 4 for a 0.0005 m one."""
    return next((d for d in range(most) if abs(round(number, d) - number) <= 1e-9 * max(1.0, abs(number))), most)


def value(key: str, number: float, digits: str = "g") -> str:
    """`key = number unit`, e.g. 'base_radius = 1.1 m'; digits: a format (".2f") or "g"."""
    return f"{key} = {number:{digits}}" + (f" {unit(key)}" if unit(key) else "")


def span(key: str, values: np.ndarray, places: int | None = None) -> str:
    """`key low-high unit`, e.g. 'base_radius 0.80-1.50 m' (to `places` decimals, or as short as
    the values allow)."""
    low, high = float(np.min(values)), float(np.max(values))
    d = places if places is not None else max(decimals(low), decimals(high))
    return f"{key} {low:.{d}f}-{high:.{d}f}" + (f" {unit(key)}" if unit(key) else "")


def point_text(study: Study, point: dict[str, float], grid: bool = False) -> str:
    """A design as 'base_radius = 1.1 m, disc_height = 1.4 m': a named design as it is written, a
    point of the grid (`grid`) at its axes' precision ('base_radius = 1.10 m')."""
    return ", ".join(value(k, v, f".{study.decimals(k) if grid else decimals(v)}f") for k, v in point.items())


_SETS: dict[str, dict] = {}


def parameter_set(name: str) -> dict:
    """The parameter set, shared unchanged (a map reads it at every grid point)."""
    if name not in _SETS:
        _SETS[name] = read_parameter_set(name)
    return _SETS[name]


def platform_values(study: Study, point: dict[str, float], effects: bool = False) -> dict[str, Any]:
    """The mechanics start values of the study's platform at a design point (geometry keys of the
    parameter set's [geometry] table); the payload is the study's. effects: the legs' inertia and
    friction as the parameter set gives them (the full model), or off (the paper's inverse model)."""
    config = parameter_set(study.parameter_set)
    family = study.family
    values = family.mechanics(config, {**family.design_values(config), **study.fixed, **point})
    values["platform.mass"] = study.payload_mass
    for axis, inertia in zip(("xx", "yy", "zz"), study.payload_inertia):
        values[f"platform.inertia_{axis}"] = inertia
    values.update({"effects.actuator_inertia": effects, "effects.motor_inertia": effects, "effects.friction": effects})
    values.update(study.mechanics)
    return values


def stubs(study: Study) -> float:
    """What the actuator's running length adds to the joint-to-joint (actuated) length [m]."""
    config = parameter_set(study.parameter_set)
    return study.family.stubs({**study.family.design_values(config), **study.fixed})
