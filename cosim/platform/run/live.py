"""A scene in real time (cosim.engine.realtime): what its stream carries, and how a live input
drives the platform in place of the scene's trajectory.

The stream carries the pose and its reference, the legs' lengths and their rates, and each drive's
effort, speed and current (what the scene records of them). A live input replaces the trajectory
FMU's pose reference: the reference moves towards each pose received within the scene's [live]
limits, a pose that puts a leg outside its stroke (limit.leg_length_min/max) is refused in C by the
dynamics core's own leg kinematics (platform_pose_within_stroke, Eq 2), and the watchdog's neutral
pose is the platform's.
"""

from __future__ import annotations

import ctypes
from dataclasses import replace

from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.realtime import LiveInput, RealTime
from ...engine.run import Plan
from ..core import Core, PlatformStroke
from ..ports import DRIVES, LEGS, POSE, per_leg
from ..scene import Scene

LEG_OUTPUTS = ("length", "velocity")  # per leg, the mechanics' outputs a stream carries


def stream_names(scene: Scene, recorded: list[str]) -> list[str]:
    """What a scene's stream carries, in this order: pose_ref.<dof>, pose.<dof>, leg[i].length,
    leg[i].velocity, then per drive output recorded (effort, speed or velocity, current) its six
    legs."""
    drive = [name for output in DRIVES[scene.drive].outputs for name in per_leg(output) if name in recorded]
    return [*(f"pose_ref.{a}" for a in POSE), *(f"pose.{a}" for a in POSE),
            *(f"leg[{i}].{o}" for o in LEG_OUTPUTS for i in LEGS), *drive]


def real_time_plan(scene: Scene, plan: Plan, mechanics_values: dict, factor: float | None = 1.0,
                   stream: str | None = None, listen: str | None = None) -> Plan:
    """The scene's plan paced at `factor` (None: unpaced), streamed to `stream` and driven through
    `listen` (addresses udp://HOST:PORT): the legs' lengths and rates recorded as well when it
    streams."""
    record, names = list(plan.record), list(plan.names)
    if stream:
        for output in LEG_OUTPUTS:
            for i in LEGS:
                if f"leg[{i}].{output}" not in names:
                    record.append(("mechanics", f"leg[{i}].{output}"))
                    names.append(f"leg[{i}].{output}")
    options = RealTime(factor, stream, stream_names(scene, names) if stream else None, listen,
                       live_input(scene, mechanics_values) if listen else None)
    return replace(plan, record=record, names=names, real_time=options)


def live_input(scene: Scene, mechanics_values: dict) -> LiveInput:
    """The trajectory's pose reference replaced by a live input within the scene's [live] limits
    (its exact rate, pose_ref_rate.*, by the live rate); poses checked against the legs' stroke;
    the platform's neutral pose for the watchdog."""
    def value(key: str) -> float:
        return float(scene.document.value("live", key))
    core = Core(values=mechanics_values)
    starts = variables(fmu_path("mechanics"))
    limits = [float(mechanics_values.get(f"limit.leg_length_{end}", starts[f"limit.leg_length_{end}"].start))
              for end in ("min", "max")]
    stroke = PlatformStroke(core.p, *limits)
    check = ctypes.cast(core.dll.platform_pose_within_stroke, ctypes.c_void_p)
    from .system import pose_source
    return LiveInput(pose_source(scene.vehicle is not None), [f"pose_ref.{a}" for a in POSE],
                     rate_outputs=[f"pose_ref_rate.{a}" for a in POSE],
                     rate_max=[value("velocity_max")] * 3 + [value("angular_velocity_max")] * 3,
                     acceleration_max=[value("acceleration_max")] * 3 + [value("angular_acceleration_max")] * 3,
                     neutral=core.neutral_pose.tolist(), late_after=value("late_after"), watchdog=value("watchdog"),
                     admissible=check, admissible_context=ctypes.pointer(stroke),
                     refusal=f"outside the stroke ({limits[0]:g}-{limits[1]:g} m)")


def stream_fields(scene: Scene) -> list[tuple[str, str, str]]:
    """The values a scene's stream carries (`cosim stream-layout`): name, unit and what it is, from
    the FMUs' own descriptions."""
    from .compile import drive_fmus, scene_record
    record, names = scene_record(scene)
    names = [*names, *(f"leg[{i}].{o}" for o in LEG_OUTPUTS for i in LEGS)]
    trajectory, mechanics = variables(fmu_path("trajectory")), variables(fmu_path("mechanics"))
    drive = variables(drive_fmus(scene)[0])
    out = []
    for name in stream_names(scene, names):
        if name.startswith("pose_ref."):
            found = trajectory[name]
        elif name.startswith(("pose.", "leg[")):
            found = mechanics[name]
        else:
            found = drive[name.split("[")[0]]
        unit = found.unit or getattr(found.declaredType, "unit", None) or ""
        out.append((name, unit, found.description or ""))
    return out
