"""The project's parameter sets (params/*.toml) as FMU start values.

The mechanics FMU's defaults are the Meng platform (params/meng2010.toml), so that set maps to the
same values the FMU already has; the Sumnu platform (params/sumnu2015.toml) loads as explicit
joint coordinates (geometry.layout = 2) with one of the thesis' mass sets.
"""

from __future__ import annotations

import math
import tomllib

from .fmus import ROOT

PARAMS = ROOT / "params"
POSE = ("x", "y", "z", "roll", "pitch", "yaw")


def load(name: str) -> dict:
    path = PARAMS / f"{name}.toml"
    if not path.exists():
        known = ", ".join(p.stem for p in sorted(PARAMS.glob("*.toml")))
        raise FileNotFoundError(f"no parameter set '{name}' in {PARAMS} (known: {known})")
    with open(path, "rb") as f:
        return tomllib.load(f)


def meng_mechanics(c: dict) -> dict[str, float]:
    g, act, ms = c["geometry"], c["actuator"], c["motor_system"]
    values = {
        "geometry.layout": 1,
        "geometry.upper_joint_radius": g["upper_joint_radius"], "geometry.lower_joint_radius": g["lower_joint_radius"],
        "geometry.upper_joint_spacing": g["upper_joint_spacing"],
        "geometry.lower_joint_spacing": g["lower_joint_spacing"],
        "geometry.middle_leg_length": g["middle_leg_length"],
        "limit.leg_length_min": g["leg_length_min"], "limit.leg_length_max": g["leg_length_max"],
        "platform.mass": c["platform"]["mass"],
        "actuator.moving_mass": act["moving_part_mass"], "actuator.moving_inertia": act["moving_part_inertia"],
        "actuator.moving_com": act["moving_part_com_from_upper_joint"],
        "actuator.rotating_mass": act["rotating_part_mass"], "actuator.rotating_inertia": act["rotating_part_inertia"],
        "actuator.rotating_com": act["rotating_part_com_from_lower_joint"],
        "motor_system.mass": ms["mass"], "motor_system.inertia": ms["transverse_inertia"],
        "motor_system.com": ms["com_from_lower_joint"], "motor_system.rotor_inertia": ms["rotor_screw_inertia"],
        "transmission.screw_ratio": c["transmission"]["screw_ratio"],
        "transmission.force_torque": c["transmission"]["force_torque_coefficient"],
        "motor.viscous_friction": c["motor"]["viscous_friction"],
    }
    for axis, value in zip(("xx", "yy", "zz"), c["platform"]["inertia_diag"]):
        values[f"platform.inertia_{axis}"] = value
    for axis, value in zip("xyz", c["environment"]["gravity"]):
        values[f"environment.gravity_{axis}"] = value
    for k, centre in enumerate(g["lower_pair_centres_deg"]):
        values[f"geometry.lower_pair_centre_{k + 1}"] = math.radians(centre)
    for k, centre in enumerate(g["upper_pair_centres_deg"]):
        values[f"geometry.upper_pair_centre_{k + 1}"] = math.radians(centre)
    return values


def sumnu_mechanics(c: dict, mass_set: str = "heavy") -> dict[str, float]:
    """The Sumnu platform driven by direct (linear-motor) forces: no screw, no motor systems on the
    legs (the forcer and stator masses belong to the legs' parts; see the linear-motor FMU), no
    motor friction. The thesis gives no stroke: the limits are set at half the shortest and one
    and a half times the longest home leg, so only gross excursions are reported."""
    g, legs, masses = c["geometry"], c["legs"], c["mass_sets"][mass_set]
    values: dict[str, float] = {"geometry.layout": 2}
    for i, (b, q) in enumerate(zip(g["base_joints"], g["platform_joints"]), start=1):
        for axis, bv, qv in zip("xyz", b, q):
            values[f"geometry.base_joint[{i}].{axis}"] = bv
            values[f"geometry.platform_joint[{i}].{axis}"] = qv
    for axis, value in zip(POSE, g["home_pose"]):
        values[f"geometry.neutral.{axis}"] = value
        values[f"initial.pose.{axis}"] = value
        values[f"pose_ref.{axis}"] = value
    values.update({
        "platform.mass": masses["platform_mass"],
        "actuator.moving_mass": masses["moving_part_mass"],
        "actuator.moving_inertia": masses["moving_part_inertia_diag"][0],
        "actuator.moving_com": legs["moving_part_com_from_platform_joint"],
        "actuator.rotating_mass": masses["rotating_part_mass"],
        "actuator.rotating_inertia": masses["rotating_part_inertia_diag"][0],
        "actuator.rotating_com": legs["rotating_part_com_from_base_joint"],
        "effects.motor_inertia": False,
        "effects.friction": False,
    })
    for axis, value in zip(("xx", "yy", "zz"), masses["platform_inertia_diag"]):
        values[f"platform.inertia_{axis}"] = value
    home = home_leg_lengths(g)
    values["limit.leg_length_min"] = 0.5 * min(home)
    values["limit.leg_length_max"] = 1.5 * max(home)
    return values


def home_leg_lengths(geometry: dict) -> list[float]:
    x, y, z, roll, pitch, yaw = geometry["home_pose"]
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    R = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
         [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
         [-sp, cp * sr, cp * cr]]
    lengths = []
    for b, q in zip(geometry["base_joints"], geometry["platform_joints"]):
        top = [(x, y, z)[k] + sum(R[k][j] * q[j] for j in range(3)) for k in range(3)]
        lengths.append(math.dist(top, b))
    return lengths


def mechanics_start_values(name: str, mass_set: str = "heavy") -> dict[str, float]:
    """Start values of the mechanics FMU for parameter set `name` (meng2010 or sumnu2015)."""
    c = load(name)
    if name == "meng2010":
        return meng_mechanics(c)
    if name == "sumnu2015":
        return sumnu_mechanics(c, mass_set)
    raise ValueError(f"parameter set '{name}' has no mapping to the mechanics FMU")
