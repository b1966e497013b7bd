"""Drives designed for the plant they drive.

What a drive designer needs, per leg at the start pose, comes from the mechanics' own dynamics
core (fmu/mechanics/platform.c: platform_leg_plants, through cosim.platform.core; the
mechanics FMU outputs the same as leg[i].plant.inertia and leg[i].plant.static_force, so other FMI
tools can design drives from it):
- the leg's inertia with the other legs held, M_ii of the joint-space mass matrix: twice the
  kinetic energy when leg i alone extends at 1 m/s (motor systems included when they are on);
- the static load: the leg force that holds the start pose against gravity;
- the stroke.
From it each drive's loops follow the rules its documentation states:
- pmsm_drive: current loop by the modulus optimum (independent of the plant: kept); speed loop
  symmetric-optimum style at w_c = 500 rad/s on the motor-side inertia J_eq = M_ii / (K_FT i_theta):
  Kp_w = w_c J_eq / K_m, Ki_w = Kp_w w_c / 6; position loop from the speed loop's bandwidth:
  Kp_p = 0.12 w_c, Ki_p = 5 Kp_p; and the drive starts holding its leg (initial.current_q).
- linear_motor: position PID critically damped at w = 2 pi 10 Hz on m = M_ii: Kp = m w^2,
  Kd = 2 m w, Ki = Kp w / 10; the current loop is kept.
Sizing is checked first: a drive that cannot hold its leg's static load (linear motor: its
continuous force; PMSM: K_m times its current limit) is a `SizingError` naming the leg, the load
and the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ...engine.checks import variables
from ...engine.artifacts import fmu_path
from ..core import Core, mechanics_value
from ..ports import DRIVES, POSE

SPEED_CROSSOVER = 500.0           # w_c [rad/s] of the PMSM speed loop
POSITION_BANDWIDTH = 2 * math.pi * 10.0  # w [rad/s] of the linear motor's position PID


class SizingError(ValueError):
    """A drive that cannot hold its leg at the start pose: leg, load and limit named."""


@dataclass(frozen=True)
class LegPlant:
    mass: float          # M_ii [kg]: the leg's inertia with the other legs held (leg side)
    static_force: float  # [N]: the leg force that holds the start pose (positive: pushing)
    length: float        # [m] at the start pose
    stroke: tuple[float, float]  # [m]
    screw_ratio: float   # i_theta [rad/m]: motor angle per leg length
    force_torque: float  # K_FT [N/(N m)]: leg force per motor torque


def leg_plants(values: Mapping[str, object]) -> list[LegPlant]:
    """Each leg's plant at the start pose, for mechanics start values (over the FMU's defaults):
    the dynamics core's platform_leg_plants on the platform the FMU builds from them, the same
    function that gives the mechanics FMU's leg[i].plant.* outputs."""
    core = Core().use_start_values(dict(values))
    pose = np.array([float(mechanics_value(values, f"initial.pose.{a}")) for a in POSE])
    inertia, force = core.leg_plants(pose)
    lengths = core.leg_lengths(pose)
    stroke = (float(mechanics_value(values, "limit.leg_length_min")),
              float(mechanics_value(values, "limit.leg_length_max")))
    return [LegPlant(float(inertia[i]), float(force[i]), float(lengths[i]), stroke, core.p.screw_ratio,
                     core.p.force_torque) for i in range(6)]


def drive_defaults(drive: str) -> dict[str, float]:
    return {name: float(v.start) for name, v in variables(fmu_path(DRIVES[drive].fmu)).items()
            if v.start is not None and v.type in ("Real", "Integer")}


def design(drive: str, plants: list[LegPlant], drive_values: Mapping[str, object]) -> list[dict[str, float]]:
    """Per leg, the drive parameters its rules give for its plant (explicit drive_values win)."""
    given = {**drive_defaults(drive), **{k: float(v) for k, v in drive_values.items() if isinstance(v, (int, float))}}
    designed = []
    for plant in plants:
        if drive == "pmsm":
            inertia = plant.mass / (plant.force_torque * plant.screw_ratio)  # J_eq, motor side [kg m^2]
            kp_w = SPEED_CROSSOVER * inertia / given["motor.torque_constant"]
            kp_p = 0.12 * SPEED_CROSSOVER
            values = {"control.speed_kp": kp_w, "control.speed_ki": kp_w * SPEED_CROSSOVER / 6,
                      "control.position_kp": kp_p, "control.position_ki": 5 * kp_p,
                      "initial.current_q": hold_currents([plant], given)[0]}
        else:
            w, m = POSITION_BANDWIDTH, plant.mass
            values = {"control.position_kp": m * w * w, "control.position_kd": 2 * m * w,
                      "control.position_ki": m * w ** 3 / 10}
        designed.append({**values, **{k: v for k, v in drive_values.items()}})
    return designed


def hold_currents(plants: list[LegPlant], drive_values: Mapping[str, object]) -> list[float]:
    """Per leg, the PMSM's q current that holds the start pose: i_q = F / (K_FT K_m)."""
    given = {**drive_defaults("pmsm"), **{k: float(v) for k, v in drive_values.items() if isinstance(v, (int, float))}}
    return [plant.static_force / plant.force_torque / given["motor.torque_constant"] for plant in plants]


def check_sizing(drive: str, plants: list[LegPlant], drive_values: Mapping[str, object], leg: int = 1) -> None:
    """Raises SizingError for the first leg (numbered from `leg`) our drive cannot hold: the PMSM
    up to K_m times its current limit, the linear motor up to its continuous force."""
    given = {**drive_defaults(drive), **{k: float(v) for k, v in drive_values.items() if isinstance(v, (int, float))}}
    for i, plant in enumerate(plants, start=leg):
        if drive == "pmsm":
            check_limit(drive, plant, given["motor.torque_constant"] * given["limit.current"],
                        "pmsm_drive's K_m x limit.current", i)
        else:
            check_limit(drive, plant, given["motor.continuous_force"], "linear_motor's motor.continuous_force", i)


def check_limit(drive: str, plant: LegPlant, limit: float, what: str, leg: int) -> None:
    """Raises SizingError if leg `leg`'s static load needs more than `limit` (N m of a rotary
    drive: the leg force over K_FT; N of a linear one), named `what`."""
    if drive == "pmsm":
        torque = abs(plant.static_force) / plant.force_torque
        if torque > limit:
            raise SizingError(f"leg {leg} needs {torque:.3g} N m to hold the start pose, above {what} = {limit:.3g} N m")
    elif abs(plant.static_force) > limit:
        raise SizingError(f"leg {leg} needs {abs(plant.static_force):.4g} N to hold the start pose, above {what} = "
                          f"{limit:.4g} N")


def summary(drive: str, designed: list[dict[str, float]]) -> str:
    """The gains chosen, one line (ranges over the legs)."""
    keys = ["control.speed_kp", "control.speed_ki", "control.position_kp", "control.position_ki"] if drive == "pmsm" \
        else ["control.position_kp", "control.position_ki", "control.position_kd"]
    parts = []
    for key in keys:
        values = [float(d[key]) for d in designed]
        low, high = min(values), max(values)
        parts.append(f"{key.split('.')[1]} {low:.4g}" + (f"-{high:.4g}" if high > low * (1 + 1e-9) else ""))
    return "drive loops designed for the plant: " + ", ".join(parts)
