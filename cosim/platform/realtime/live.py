"""A scene in real time (cosim.engine.realtime): what its stream carries, and how a live input
drives the platform in place of the scene's trajectory.

The stream carries the pose and its reference, the legs' lengths and their rates, and each drive's
effort, speed and current (what the scene records of them). A live input replaces the trajectory
FMU's pose reference (or the cueing FMU's): the reference moves towards each pose received within
the scene's [live] limits and is held within the platform's motion envelope (envelope.py) by the
dynamics core's own kinematics in C, braking in time; the watchdog's neutral pose is the
platform's. Before a run in real time the scene's own reference is checked against the envelope.
"""

from __future__ import annotations

import ctypes
from dataclasses import replace

from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.realtime import LiveInput, RealTime
from ...engine.run import Plan
from ..core import Core
from ..ports import DRIVES, LEGS, POSE, per_leg
from ..run.compile import CompiledScene, drive_fmus, scene_cueing, scene_record
from ..run.system import pose_source
from ..scene import Scene
from .envelope import GUARD_KINDS, Envelope, check_reference

LEG_OUTPUTS = ("length", "velocity")  # per leg, the mechanics' outputs a stream carries


def stream_names(scene: Scene, recorded: list[str]) -> list[str]:
    """What a scene's stream carries, in this order: pose_ref.<dof>, pose.<dof>, leg[i].length,
    leg[i].velocity, then per drive output recorded (effort, speed or velocity, current) its six
    legs."""
    drive = [name for output in DRIVES[scene.drive].outputs for name in per_leg(output) if name in recorded]
    return [*(f"pose_ref.{a}" for a in POSE), *(f"pose.{a}" for a in POSE),
            *(f"leg[{i}].{o}" for o in LEG_OUTPUTS for i in LEGS), *drive]


def real_time_plan(compiled: CompiledScene, factor: float | None = 1.0, stream: str | None = None,
                   listen: str | None = None, key: bytes | None = None) -> tuple[Plan, str | None]:
    """The compiled scene's plan paced at `factor` (None: unpaced), streamed to `stream` and driven through
    `listen` (addresses udp://HOST:PORT; its datagrams tagged with `key` if given): the legs'
    lengths and rates recorded as well when it streams. Paced or listening, the scene's own
    reference is checked against the platform's envelope: returned beside the plan, what the run
    says before it starts of one that leaves it (None if it stays inside)."""
    scene, mechanics_values, plan = compiled.scene, compiled.mechanics, compiled.plan
    record, names = list(plan.record), list(plan.names)
    if stream:
        for output in LEG_OUTPUTS:
            for i in LEGS:
                if f"leg[{i}].{output}" not in names:
                    record.append(("mechanics", f"leg[{i}].{output}"))
                    names.append(f"leg[{i}].{output}")
    remark = check_scene_reference(scene, mechanics_values) if factor is not None or listen else None
    options = RealTime(factor, stream, stream_names(scene, names) if stream else None, listen,
                       live_input(scene, mechanics_values, key) if listen else None)
    return replace(plan, record=record, names=names, real_time=options), remark


def check_scene_reference(scene: Scene, mechanics_values: dict) -> str | None:
    """The scene's own reference (its trajectory or its cueing, run alone at the scene's step)
    against the platform's envelope (envelope.check_reference)."""
    from ..run.alone import play, play_cueing
    from ..scene.signals import scene_trajectory
    if scene.vehicle is not None:
        times, poses = play_cueing(scene_cueing(scene, mechanics_values), scene.duration, scene.step)[:2]
    else:
        times, poses, _ = play(scene_trajectory(scene), scene.duration, scene.step)
    return check_reference(f"scene {scene.name}", Core(values=mechanics_values), Envelope.of(mechanics_values), times, poses)


def live_input(scene: Scene, mechanics_values: dict, key: bytes | None = None) -> LiveInput:
    """The trajectory's pose reference replaced by a live input within the scene's [live] limits
    (its exact rate, pose_ref_rate.*, by the live rate), held within the platform's envelope by
    its guard; the platform's neutral pose for the watchdog."""
    def value(key: str) -> float:
        return float(scene.document.value("live", key))
    core = Core(values=mechanics_values)
    envelope = Envelope.of(mechanics_values)
    acceleration_max = [value("acceleration_max")] * 3 + [value("angular_acceleration_max")] * 3
    context = ctypes.pointer(envelope.c_struct(core, acceleration_max))
    return LiveInput(pose_source(scene.vehicle is not None), [f"pose_ref.{a}" for a in POSE],
                     rate_outputs=[f"pose_ref_rate.{a}" for a in POSE],
                     rate_max=[value("velocity_max")] * 3 + [value("angular_velocity_max")] * 3,
                     acceleration_max=acceleration_max, neutral=core.neutral_pose.tolist(),
                     late_after=value("late_after"), watchdog=value("watchdog"),
                     admissible=ctypes.cast(core.dll.platform_envelope_contains, ctypes.c_void_p),
                     admissible_context=context, refusal="outside the envelope",
                     guard=ctypes.cast(core.dll.platform_envelope_guard, ctypes.c_void_p), guard_context=context,
                     guard_kinds=GUARD_KINDS, key=key)


def stream_fields(scene: Scene) -> list[tuple[str, str, str]]:
    """The values a scene's stream carries (`cosim stream-layout`): name, unit and what it is, from
    the FMUs' own descriptions."""
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
