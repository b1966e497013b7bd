"""The margins the motion envelope needs on a platform, measured (docs/guide/realtime.md).

The guard holds the reference within the stroke less limit.stroke_margin and the joints within
limit.joint_angle less limit.joint_margin; the platform lags its reference, most when the reference
brakes at the envelope's edge at the limits the guard admits, and the margins must cover that lag.
Here the scene's platform and drives are driven by a guarded reference that steps far outside the
envelope at once on every axis (no load, no other motion), so that the reference goes to the edge
with every axis at its top [live] rate and acceleration at once and brakes there: into each leg's
top and bottom, the axes signed as that leg's length grows (shrinks) with each. Per direction:
how far the platform's legs went past the reference's usable stroke and its joints past the
reference's usable tilt, which the margins must exceed, and whether the platform stayed within
the stroke and the joints' limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core import Core
from ..ports import POSE
from ..scene import Scene
from ..run.envelope import Envelope

STEP_AT = 0.1          # [s] the reference steps out here (the start-up behind it)
STEP_HEIGHT = (0.6,) * 3 + (0.6,) * 3  # [m, rad] far past any shipped platform's envelope


@dataclass(frozen=True)
class EdgeProbe:
    """One drive into the envelope's edge: which, and what the platform did there."""
    direction: str              # "leg 3 lengthening"
    signs: tuple[int, ...]      # per axis x .. yaw, the sign of its step
    reached: bool               # the reference came to the envelope's edge (stroke or joints)
    stroke_excess: float        # [m] the platform's legs past the reference's usable stroke, at most (< 0: short of it)
    joint_excess: float         # [rad] the platform's joints past the reference's usable tilt, at most
    legs: tuple[float, float]   # [m] the platform's shortest and longest leg
    tilt: float                 # [rad] the platform's largest joint tilt


def directions(core: Core) -> list[tuple[str, tuple[int, ...]]]:
    """Each leg lengthening and shortening fastest with every axis at once: the signs of the leg's
    length's derivative by each axis at the neutral pose (by central differences)."""
    neutral, out = core.neutral_pose, []
    slopes = np.zeros((6, 6))
    for axis in range(6):
        delta = np.zeros(6)
        delta[axis] = 1e-6
        slopes[:, axis] = (core.leg_lengths(neutral + delta) - core.leg_lengths(neutral - delta)) / 2e-6
    for leg in range(6):
        signs = tuple(int(s) for s in np.where(slopes[leg] >= 0.0, 1, -1))
        for way, taken in (("lengthening", signs), ("shortening", tuple(-s for s in signs))):
            if all(taken != seen for _, seen in out):  # (a symmetric platform's legs share some)
                out.append((f"leg {leg + 1} {way}", taken))
    return out


def margin_needed(excess: float, unit: float, factor: float = 1.5) -> float:
    """The margin an excess measured at the edge asks for: `factor` times it, rounded up to whole
    `unit`s (at least one)."""
    return max(1, math.ceil(factor * excess / unit - 1e-9)) * unit


def probe_scene(scene: Scene, signs: tuple[int, ...], duration: float) -> Scene:
    """`scene`'s platform and drives, no load, its reference at the neutral pose stepping at
    STEP_AT by STEP_HEIGHT on every axis with these signs."""
    from ..run.compile import scene_values
    neutral = Core(values=scene_values(scene)[0]).neutral_pose
    changes: dict[str, object] = {"scene.duration": duration, "load.pulses": []}
    for axis, name in enumerate(POSE):
        changes[f"trajectory.{name}.offset"] = float(neutral[axis])
        changes[f"trajectory.{name}.sines"] = []
        changes[f"trajectory.{name}.ramps"] = []
        changes[f"trajectory.{name}.steps"] = [{"time": STEP_AT, "height": signs[axis] * STEP_HEIGHT[axis]}]
    return scene.changed(changes)


def probe(scene: Scene, direction: str, signs: tuple[int, ...], duration: float = 2.5) -> EdgeProbe:
    """The platform driven into the envelope's edge in one direction (a guarded run, not paced)."""
    from ..run.compile import scene_values
    from ..run.runner import run_scene
    from ..run.guard import guarded_plan
    stepped = probe_scene(scene, signs, duration)
    values = scene_values(stepped)[0]
    envelope, core = Envelope.of(values), Core(values=values)
    result, _ = run_scene(stepped, adapt=guarded_plan)
    low, high = envelope.usable

    def legs_and_tilt(prefix: str) -> tuple[np.ndarray, np.ndarray]:
        kinematics = core.pose_kinematics(np.column_stack([result[f"{prefix}.{a}"] for a in POSE]))
        return kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])

    reference_legs, reference_tilt = legs_and_tilt("pose_ref")
    legs, tilt = legs_and_tilt("pose")
    at_edge = max(reference_legs.max() - high, low - reference_legs.min(), reference_tilt.max() - envelope.usable_joint_angle)
    return EdgeProbe(direction, signs, bool(at_edge > -1e-4),
                     float(max(legs.max() - high, low - legs.min())), float(tilt.max() - envelope.usable_joint_angle),
                     (float(legs.min()), float(legs.max())), float(tilt.max()))


def measure(scene: Scene, duration: float = 2.5) -> list[EdgeProbe]:
    """Every direction of `directions` on the scene's platform and drives."""
    from ..run.compile import scene_values
    core = Core(values=scene_values(scene)[0])
    return [probe(scene, direction, signs, duration) for direction, signs in directions(core)]
