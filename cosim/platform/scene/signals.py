"""The scene's reference pose and external wrench as parameters of the trajectory FMU
(fmu/trajectory/), which the platform system steps with the other FMUs; and the trajectory FMU
played alone (`play`), the one evaluation of a scene's signals outside a run."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Mapping

import numpy as np

from ...engine import Algorithm, Component, Experiment, FixedStep, SystemStructure, fmu_path
from ...engine.outcome import execute
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


def reference_motion(scene: Scene, samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The scene's reference pose and base-frame load force at `samples` evenly spaced times over
    its duration, from its trajectory FMU run alone (the one evaluation of the scene's signals,
    tables included): times, poses (n x 6), forces (n x 3)."""
    return play(scene_trajectory(scene), scene.duration, scene.duration / (samples - 1))


def play(trajectory_values: dict, duration: float, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The trajectory FMU with these start values run alone for `duration` at `step`: times,
    reference poses (n x 6), base-frame load forces (n x 3). Raises what the FMU refuses (a bad
    table: its file and line) as the engine's error."""
    alone = SystemStructure("reference", [Component("trajectory", fmu_path("trajectory"), trajectory_values)], [],
                            experiment=Experiment(0.0, duration, step))
    names = [*(f"pose_ref.{a}" for a in POSE), *(f"load.force.{a}" for a in "xyz")]
    outcome = execute(alone, Algorithm("jacobi", 0), FixedStep(step), duration, [("trajectory", n) for n in names])
    if outcome.failure is not None:
        raise outcome.failure
    result = outcome.result
    return result["time"], np.column_stack([result[f"trajectory.{n}"] for n in names[:6]]), \
        np.column_stack([result[f"trajectory.{n}"] for n in names[6:]])


CUEING_OUTPUTS = (*(f"pose_ref.{a}" for a in POSE), "tilt.roll", "tilt.pitch",
                  *(f"vehicle.{q}.{a}" for q in ("specific_force", "angular_rate") for a in "xyz"))


def play_cueing(cueing_values: dict, duration: float, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                             np.ndarray]:
    """The cueing FMU with these start values run alone for `duration` at `step` (a vehicle's
    motion through the classical washout, the platform's response left out): times, the pose
    reference (n x 6), the tilt (n x 2: roll, pitch) and the vehicle's motion it took (n x 6).
    Raises what the FMU refuses (a bad vehicle table: its file and line) as the engine's error."""
    alone = SystemStructure("cueing", [Component("cueing", fmu_path("cueing"), cueing_values)], [],
                            experiment=Experiment(0.0, duration, step))
    outcome = execute(alone, Algorithm("jacobi", 0), FixedStep(step), duration, [("cueing", n) for n in CUEING_OUTPUTS])
    if outcome.failure is not None:
        raise outcome.failure
    result = outcome.result
    columns = [np.column_stack([result[f"cueing.{n}"] for n in names])
               for names in (CUEING_OUTPUTS[:6], CUEING_OUTPUTS[6:8], CUEING_OUTPUTS[8:])]
    return (result["time"], *columns)
