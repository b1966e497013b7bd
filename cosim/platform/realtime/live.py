"""A scene in real time (cosim.engine.realtime): what its stream carries, and how a live input
drives the platform in place of the scene's trajectory.

The stream carries the pose and its reference, the legs' lengths and their rates, and each drive's
effort, speed and current (what the scene records of them). The reference the platform is given
passes through one guard (envelope.py, the dynamics core's kinematics in C), whatever its source:
in every run paced or listening, and in every motion-cueing scene, the scene's own trajectory or
cueing output is taken as it is while the guard would take its motion and is otherwise followed
within the envelope; a live input replaces it, moving towards each pose received within the
scene's [live] limits, held within the envelope, braking in time; a reference outside goes back in
along the way to the platform's neutral pose, which is also the watchdog's.
"""

from __future__ import annotations

from dataclasses import replace

from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.realtime import RealTime
from ...engine.run import Plan
from ..core import Core
from ..ports import DRIVES, LEGS, POSE, per_leg
from ..run.compile import CompiledScene, drive_fmus, scene_cueing, scene_record
from ..scene import Scene
from ..run.envelope import Envelope, check_reference
from ..run.guard import reference_guard

LEG_OUTPUTS = ("length", "velocity")  # per leg, the mechanics' outputs a stream carries


def stream_names(scene: Scene, recorded: list[str]) -> list[str]:
    """What a scene's stream carries, in this order: pose_ref.<dof>, pose.<dof>, leg[i].length,
    leg[i].velocity, then per drive output recorded (effort, speed or velocity, current) its six
    legs."""
    drive = [name for output in DRIVES[scene.drive].outputs for name in per_leg(output) if name in recorded]
    return [*(f"pose_ref.{a}" for a in POSE), *(f"pose.{a}" for a in POSE),
            *(f"leg[{i}].{o}" for o in LEG_OUTPUTS for i in LEGS), *drive]


def real_time_plan(compiled: CompiledScene, factor: float | None = 1.0, stream: str | None = None,
                   listen: str | None = None, key: bytes | None = None,
                   guarded: bool = False) -> tuple[Plan, str | None]:
    """The compiled scene's plan paced at `factor` (None: unpaced), streamed to `stream` and driven through
    `listen` (addresses udp://HOST:PORT; its datagrams tagged with `key` if given): the legs'
    lengths and rates recorded as well when it streams. Paced, listening, cueing or asked
    (`guarded`), the reference is held within the envelope; what the run says before it starts of a scene's own reference that
    leaves the envelope is returned beside the plan (None if it stays inside)."""
    scene, mechanics_values, plan = compiled.scene, compiled.mechanics, compiled.plan
    record, names = list(plan.record), list(plan.names)
    if stream:
        for output in LEG_OUTPUTS:
            for i in LEGS:
                if f"leg[{i}].{output}" not in names:
                    record.append(("mechanics", f"leg[{i}].{output}"))
                    names.append(f"leg[{i}].{output}")
    guarded = guarded or factor is not None or bool(listen)  # (a cueing's output: its FMU's own guard holds it)
    remark = check_scene_reference(scene, mechanics_values) if factor is not None or listen else None
    options = RealTime(factor, stream, stream_names(scene, names) if stream else None, listen,
                       reference_guard(scene, mechanics_values, key) if guarded else None)
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
