"""The project's parameter sets (params/*.toml) as FMU start values.

The mechanics FMU's defaults are the Meng platform (params/meng2010.toml), so that set maps to the
same values the FMU already has; the Sumnu platform (params/sumnu2015.toml) loads as explicit
joint coordinates (geometry.layout = 2) with one of the thesis' mass sets. A platform's set gives
every value the mechanics reads, so switching an effect on never brings in another paper's values.

A drive set (params/<platform>_<drive kind>.toml, e.g. sumnu2015_pmsm) is a drive sized for a
platform its papers do not drive that way: its [drive] table holds the drive FMU's parameters, its
[mechanics] table what the drive changes on the legs (motor system, screw), both by FMU variable
names. A scene that swaps the drive uses the matching set unless it names another.
"""

from __future__ import annotations

import copy
import math
import tomllib

from ...engine.artifacts import ROOT, data_dir
from ..ports import LEGS, POSE

PARAMS = ROOT / "params"


_READ: dict[str, tuple[int, dict]] = {}  # per parameter set, its file's modification time and contents


def read_parameter_set(name: str) -> dict:
    """A parameter set's contents (params/<name>.toml; a copy the caller may change), the file
    opened once per process while it stays unchanged."""
    path = data_dir("params") / f"{name}.toml"
    if not path.exists():
        known = ", ".join(p.stem for p in sorted(PARAMS.glob("*.toml")))
        raise FileNotFoundError(f"no parameter set '{name}' in {PARAMS} (known: {known})")
    modified = path.stat().st_mtime_ns
    if name not in _READ or _READ[name][0] != modified:
        with open(path, "rb") as f:
            _READ[name] = (modified, tomllib.load(f))
    return copy.deepcopy(_READ[name][1])


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


def envelope_margins(platform: str, drive: str) -> dict[str, float]:
    """The margins a guarded reference keeps off the stroke and the joints' limit on `platform`
    driven by `drive` (params/envelope.toml, measured; {} where it lists none: the mechanics FMU's
    defaults)."""
    margins = read_parameter_set("envelope").get(platform, {}).get(drive, {})
    return {**({"limit.stroke_margin": margins["stroke_margin"]} if "stroke_margin" in margins else {}),
            **({"limit.joint_margin": math.radians(margins["joint_margin_deg"])}
               if "joint_margin_deg" in margins else {})}


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
        # Linear motors act along the legs: no motor systems, no screw (i_theta = K_FT = 1, so the
        # mechanics' motor angle and torque ports read as leg length and force), no motor friction.
        "effects.motor_inertia": False,
        "effects.friction": False,
        "motor_system.mass": 0.0, "motor_system.inertia": 0.0, "motor_system.com": 0.0,
        "motor_system.rotor_inertia": 0.0, "transmission.screw_ratio": 1.0, "transmission.force_torque": 1.0,
        "motor.viscous_friction": 0.0,
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


def halder_joints(c: dict) -> tuple[list[list[float]], list[list[float]], list[float]]:
    """Halder's Eqs 1-4: the lower (spherical) joints B_i in the base frame, the upper (universal)
    joints T_i in the payload frame (origin at the payload's centre of mass p), and the neutral pose.
    Each joint lies on the line from the stub's end on the base circle, b_i, to its end on the disc,
    t_i, a stub length from it (the stubs and the leg are collinear at the neutral, Eq 3)."""
    g = c["geometry"]
    theta_s = math.radians(g["half_pair_angle_deg"])
    theta_b = {1: theta_s - math.pi / 3, 2: math.pi / 3 - theta_s}
    theta_t = {1: -theta_s, 2: theta_s}
    for i in range(3, 7):  # odd legs from leg 1, even legs from leg 2 (see params/halder2013.toml)
        first = 1 if i % 2 else 2
        theta_b[i] = theta_b[first] + (i - first) * math.pi / 3
        theta_t[i] = theta_t[first] + (i - first) * math.pi / 3
    z_disc, z_com = g["disc_height"], g["disc_height"] + g["payload_com_above_disc"]
    lower, upper = [], []
    for i in LEGS:
        b = [g["base_radius"] * math.cos(theta_b[i]), g["base_radius"] * math.sin(theta_b[i]), 0.0]
        t = [g["top_radius"] * math.cos(theta_t[i]), g["top_radius"] * math.sin(theta_t[i]), z_disc]
        length = math.dist(b, t)
        lower.append([bk + (tk - bk) * g["bottom_stub"] / length for bk, tk in zip(b, t)])
        top = [tk - (tk - bk) * g["top_stub"] / length for bk, tk in zip(b, t)]
        upper.append([top[0], top[1], top[2] - z_com])
    return lower, upper, [0.0, 0.0, z_com, 0.0, 0.0, 0.0]


def halder_mechanics(c: dict) -> dict[str, float]:
    """Halder's 6-SBU platform: explicit joints, the payload, legs as upper part (slides with the top
    joint), lower part and motor (swing about the bottom joint), leg spin and joint friction."""
    lower, upper, neutral = halder_joints(c)
    legs, friction, payload = c["legs"], c["friction"], c["payload"]
    values: dict[str, float] = {"geometry.layout": 2}
    for i, (b, a) in enumerate(zip(lower, upper), start=1):
        for axis, bv, av in zip("xyz", b, a):
            values[f"geometry.base_joint[{i}].{axis}"] = bv
            values[f"geometry.platform_joint[{i}].{axis}"] = av
    for axis, value in zip(POSE, neutral):
        values[f"geometry.neutral.{axis}"] = value
        values[f"initial.pose.{axis}"] = value
        values[f"pose_ref.{axis}"] = value
    l_u, l_l, l_m = legs["upper_part_length"], legs["lower_part_length"], legs["motor_length"]
    stubs = c["geometry"]["top_stub"] + c["geometry"]["bottom_stub"]
    values.update({
        "platform.mass": payload["mass"],
        "actuator.moving_mass": legs["upper_part_mass"], "actuator.moving_com": l_u / 2,
        "actuator.moving_inertia": legs["upper_part_mass"] * l_u ** 2 / 12,
        "actuator.rotating_mass": legs["lower_part_mass"], "actuator.rotating_com": l_m + l_l / 2,
        "actuator.rotating_inertia": legs["lower_part_mass"] * l_l ** 2 / 12,
        "motor_system.mass": legs["motor_mass"], "motor_system.com": l_m / 2,
        "motor_system.inertia": legs["motor_mass"] * l_m ** 2 / 12,
        "motor_system.rotor_inertia": legs["rotor_inertia"],
        "actuator.spin_inertia": legs["spin_inertia"],
        "transmission.screw_ratio": 2 * math.pi / legs["screw_lead"],
        "transmission.force_torque": 2 * math.pi / legs["screw_lead"],
        "motor.viscous_friction": friction["ball_screw"],
        "joint.friction_lower": friction["spherical"], "joint.friction_upper": friction["universal"],
        "limit.leg_length_min": c["geometry"]["running_length_min"] - stubs,
        "limit.leg_length_max": c["geometry"]["running_length_max"] - stubs,
    })
    for axis, value in zip(("xx", "yy", "zz"), payload["inertia_diag"]):
        values[f"platform.inertia_{axis}"] = value
    for axis, value in zip("xyz", c["environment"]["gravity"]):
        values[f"environment.gravity_{axis}"] = value
    return values


def drive_set_name(platform: str, drive: str) -> str | None:
    """The project's drive set for `drive` on `platform`, if it has one (None for a platform's own
    drive, whose FMU defaults are its paper's)."""
    name = f"{platform}_{drive}"
    return name if (PARAMS / f"{name}.toml").exists() else None


def drive_set(name: str) -> tuple[dict, dict]:
    """A drive set's (drive FMU values, mechanics FMU values)."""
    values = read_parameter_set(name)
    unknown = set(values) - {"drive", "mechanics"}
    if unknown:
        raise ValueError(f"params/{name}.toml: a drive set holds [drive] and [mechanics] only, not {sorted(unknown)}")
    return dict(values.get("drive", {})), dict(values.get("mechanics", {}))


def scene_mechanics(parameter_set: str, mass_set: str = "heavy", drive_mechanics: dict | None = None,
                    parameters: dict | None = None) -> dict[str, object]:
    """The mechanics FMU's values of a scene: the platform's set, the drive set's [mechanics]
    (`drive_mechanics`: what the drive changes on the legs), then the scene's own, which win. The platform starts at its
    neutral pose wherever none of them gives the start pose: the FMU's default start pose is the
    default layout's neutral, which a changed geometry moves."""
    from ..core import neutral_pose
    values = {**mechanics_start_values(parameter_set, mass_set), **(drive_mechanics or {}),
              **(parameters or {})}
    missing = [dof for dof in POSE if f"initial.pose.{dof}" not in values]
    if missing:
        neutral = neutral_pose(values)
        values.update({f"initial.pose.{dof}": float(neutral[POSE.index(dof)]) for dof in missing})
    return values


def mechanics_start_values(name: str, mass_set: str = "heavy") -> dict[str, float]:
    """Start values of the mechanics FMU for parameter set `name` (meng2010, sumnu2015, halder2013)."""
    c = read_parameter_set(name)
    if name == "meng2010":
        return meng_mechanics(c)
    if name == "sumnu2015":
        return sumnu_mechanics(c, mass_set)
    if name == "halder2013":
        return halder_mechanics(c)
    raise ValueError(f"parameter set '{name}' has no mapping to the mechanics FMU")
