"""The scene's reference pose and external wrench as functions of time."""

from __future__ import annotations

from typing import Callable

import numpy as np

from .scene import WRENCH_COMPONENTS, Scene
from .system import POSE


def pose_reference(scene: Scene) -> Callable[[float], np.ndarray]:
    """pose_ref(t) = offset + sum of sines + steps + ramps, per DOF (x, y, z, roll, pitch, yaw)."""
    offset = np.zeros(6)
    sines, steps, ramps = [], [], []
    for k, dof in enumerate(POSE):
        signal = scene.trajectory.get(dof)
        if signal is None:
            continue
        offset[k] = signal.offset
        sines += [(k, s.amplitude, 2 * np.pi * s.frequency, s.phase) for s in signal.sines]
        steps += [(k, s.time, s.height) for s in signal.steps]
        ramps += [(k, r.start, r.end, r.slope) for r in signal.ramps]
    sine = np.array(sines).reshape(-1, 4)
    sine_dof = sine[:, 0].astype(int)

    def reference(t: float) -> np.ndarray:
        pose = offset.copy()
        if len(sine):
            np.add.at(pose, sine_dof, sine[:, 1] * np.sin(sine[:, 2] * t + sine[:, 3]))
        for k, time, height in steps:
            if t >= time:
                pose[k] += height
        for k, start, end, slope in ramps:
            pose[k] += slope * (min(t, end) - start) if t > start else 0.0
        return pose

    return reference


def wrench(scene: Scene) -> Callable[[float], np.ndarray] | None:
    """The load pulses as [F (3), M (3)] on the platform, or None without pulses."""
    if not scene.pulses:
        return None
    pulses = [(WRENCH_COMPONENTS.index(p.component), p.value, p.start, p.end) for p in scene.pulses]

    def load(t: float) -> np.ndarray:
        w = np.zeros(6)
        for k, value, start, end in pulses:
            if start <= t <= end:
                w[k] += value
        return w

    return load
