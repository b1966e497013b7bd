"""The scene's reference pose and external wrench as parameters of the trajectory FMU
(fmu/trajectory/), which the platform system steps with the other FMUs (played alone:
cosim.platform.run.alone), and the smooth part of a reference in closed form."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from .model import Pulse, Scene, Signal
from .schema import CAPACITY, FRAMES, WRENCH_COMPONENTS
from ..ports import POSE


def trajectory_parameters(trajectory: Mapping[str, Signal], pulses: Iterable[Pulse] = (),
                          table: str | Path | None = None, interpolation: str = "cubic") -> dict[str, float | str]:
    """Start values of the trajectory FMU for these signals. Every coordinate's offset is set (0
    where the scene names none). Raises ValueError when a signal has more parts than the FMU holds."""
    values: dict[str, float | str] = {}
    for dof in POSE:
        signal = trajectory.get(dof, Signal())
        values[f"{dof}.offset"] = signal.offset
        for kind in ("sines", "steps", "ramps"):
            if len(getattr(signal, kind)) > CAPACITY[kind]:
                raise ValueError(f"trajectory.{dof}: {len(getattr(signal, kind))} {kind}; the trajectory FMU holds "
                                 f"{CAPACITY[kind]}")
        for k, sine in enumerate(signal.sines, start=1):
            values.update({f"{dof}.sine[{k}].amplitude": sine.amplitude, f"{dof}.sine[{k}].frequency": sine.frequency,
                           f"{dof}.sine[{k}].phase": sine.phase})
        for k, step in enumerate(signal.steps, start=1):
            values.update({f"{dof}.step[{k}].time": step.time, f"{dof}.step[{k}].height": step.height})
        for k, ramp in enumerate(signal.ramps, start=1):
            values.update({f"{dof}.ramp[{k}].start": ramp.start, f"{dof}.ramp[{k}].end": ramp.end,
                           f"{dof}.ramp[{k}].slope": ramp.slope})
    count = dict.fromkeys(WRENCH_COMPONENTS, 0)
    for pulse in pulses:
        count[pulse.component] += 1
        k = count[pulse.component]
        if k > CAPACITY["pulses"]:
            raise ValueError(f"load: more than {CAPACITY['pulses']} pulses on {pulse.component}")
        prefix = f"load.{pulse.component}.pulse[{k}]"
        values.update({f"{prefix}.value": pulse.value, f"{prefix}.start": pulse.start, f"{prefix}.end": pulse.end})
        if pulse.frame != "base":
            values[f"{prefix}.frame"] = FRAMES[pulse.frame]
    if table:
        values["table.file"] = Path(table).resolve()  # a file: an SSP export carries it along
        values["table.interpolation"] = {"linear": 1, "cubic": 2}[interpolation]
    return values


def scene_trajectory(scene: Scene) -> dict[str, float | str]:
    """The trajectory FMU's start values for a scene."""
    return trajectory_parameters(scene.trajectory, scene.pulses, scene.table, scene.interpolation)


def sine_motion(trajectory: Mapping[str, Signal], t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose, rate and acceleration (each n x 6) at times t of the trajectory's offsets and sines
    (steps, ramps and tables left out): what an inverse model needs along a smooth reference."""
    pose, rate, acc = (np.zeros((len(t), 6)) for _ in range(3))
    for k, dof in enumerate(POSE):
        signal = trajectory.get(dof, Signal())
        pose[:, k] = signal.offset
        for s in signal.sines:
            w = 2 * np.pi * s.frequency
            pose[:, k] += s.amplitude * np.sin(w * t + s.phase)
            rate[:, k] += s.amplitude * w * np.cos(w * t + s.phase)
            acc[:, k] -= s.amplitude * w * w * np.sin(w * t + s.phase)
    return pose, rate, acc
