"""The guard on the reference the platform is given (docs/guide/realtime.md, "The motion
envelope"): whatever its source, the scene's trajectory, a live sender or the watchdog's return,
the step kernel holds it within the platform's envelope (envelope.py, the dynamics core's
kinematics in C), braking in time within the scene's [live] limits, and brings one that is outside
back in on the way to the neutral pose. The scene's own reference passes through untouched while
the guard would take its motion. A run in real time (cosim.platform.realtime) guards and may
replace the reference with a live input. A motion-cueing scene's own reference is held by the
cueing FMU itself (fmu/cueing/guard.c, the same stepping and envelope: compile.guarded_cueing), so
that every tool its system goes to holds it too; the kernel guards only a live input there.
"""

from __future__ import annotations

import ctypes
from dataclasses import replace

from ...engine.realtime import LiveInput, RealTime
from ...engine.run import Plan
from ..core import Core
from ..ports import POSE
from ..scene import Scene
from .compile import CompiledScene
from .envelope import GUARD_KINDS, Envelope
from .system import pose_source


def reference_guard(scene: Scene, mechanics_values: dict, key: bytes | None = None) -> LiveInput:
    """The trajectory's pose reference, guarded, and (a trajectory's or a cueing's) replaced by a live
    input where one is given, within the scene's [live] limits (its exact rate, pose_ref_rate.*, by
    the reference's rate), held within the platform's envelope by its guard and brought back in by
    its recovery; the platform's neutral pose for the watchdog; `key`: a live input's shared key. A
    cueing's own output is not guarded here: the cueing FMU holds it itself."""
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
                     guard_kinds=GUARD_KINDS, recover=ctypes.cast(core.dll.platform_envelope_recovery, ctypes.c_void_p),
                     guarded=scene.vehicle is None, key=key)


def guarded_plan(compiled: CompiledScene) -> tuple[Plan, None]:
    """The compiled scene's plan with its trajectory's reference held within the platform's envelope
    by the step kernel (not paced, streamed or listening)."""
    guard = reference_guard(compiled.scene, compiled.mechanics)
    return replace(compiled.plan, real_time=RealTime(None, live=guard)), None
