"""The platform's ports as ../shared/INTERFACES.md names them: the pose and wrench signals, the
components (trajectory, mechanics, one drive per leg) and, per drive kind, which mechanics outputs
feed a drive and which drive output feeds the mechanics; and the platform's coupling, the order in
which Gauss-Seidel steps the components. The scene reader checks names against it without
importing the runtime.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..engine.settings import Algorithm

POSE = ("x", "y", "z", "roll", "pitch", "yaw")
WRENCH = ("load.force.x", "load.force.y", "load.force.z", "load.torque.x", "load.torque.y", "load.torque.z")
BODY_WRENCH = tuple(name.replace("load.", "load.body.") for name in WRENCH)  # the platform frame's
LEGS = range(1, 7)


def per_leg(name: str) -> list[str]:
    """A per-leg column's names, as a platform run records them: name[1] .. name[6]."""
    return [f"{name}[{i}]" for i in LEGS]


@dataclass(frozen=True)
class DriveWiring:
    """Which mechanics outputs feed a drive and which drive output feeds the mechanics, per leg."""
    fmu: str
    reference: tuple[str, str]  # (mechanics output, drive input)
    position: tuple[str, str]
    velocity: tuple[str, str]
    effort: tuple[str, str]     # (drive output, mechanics input)
    outputs: tuple[str, ...]    # recorded per drive by default: effort, speed or velocity, current
    # The interface Jacobian: (drive output d effort / d flow, mechanics input for it, mechanics
    # input for the flow the drive was given over the step)
    slope: tuple[str, str, str]
    # The reference's rate, for a drive whose controller differentiates its reference: (mechanics
    # output, drive input), and the drive parameters that switch that input on
    reference_rate: tuple[str, str] | None = None
    wired_parameters: tuple[tuple[str, object], ...] = ()


DRIVES = {
    "pmsm": DriveWiring("pmsm_drive", ("leg[{i}].angle_ref", "angle_ref"), ("leg[{i}].angle", "angle"),
                        ("leg[{i}].speed", "speed"), ("torque", "leg[{i}].torque"), ("torque", "speed", "current.q"),
                        ("torque_speed_slope", "leg[{i}].torque_speed_slope", "leg[{i}].speed_seen")),
    "linear": DriveWiring("linear_motor", ("leg[{i}].length_ref", "position_ref"), ("leg[{i}].length", "position"),
                          ("leg[{i}].velocity", "velocity"), ("force", "leg[{i}].force"),
                          ("force", "velocity", "current"),
                          ("force_velocity_slope", "leg[{i}].force_velocity_slope", "leg[{i}].velocity_seen"),
                          ("leg[{i}].velocity_ref", "velocity_ref"), (("control.velocity_ref_input", True),)),
}


def drive_names(drive: str) -> list[str]:
    """The drives' component names, one per leg: pmsm1 .. pmsm6, linear1 .. linear6."""
    return [f"{drive}{i}" for i in LEGS]


def platform_algorithm(drive: str, kind: str = "gauss-seidel", order: int = 1) -> Algorithm:
    """The platform's coupling: Gauss-Seidel steps the trajectory, the drives, then the mechanics
    (each drive from the mechanics' last samples, the mechanics with the drives' new efforts)."""
    return Algorithm(kind, order, ("trajectory", *drive_names(drive), "mechanics") if kind == "gauss-seidel" else None)
