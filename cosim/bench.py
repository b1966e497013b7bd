"""A drive FMU on a test bench: one instance turning a rigid inertia, coupled at a fixed step.

The drive steps first from the load's state at t (Gauss-Seidel); the load then advances with the
mean of the drive's torque at t and t + h (trapezoidal coupling, second order in h).
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np

from .fmu_instance import FmuInstance
from .loads import RigidInertia

References = Callable[[float], Mapping[str, float]]


ROTARY = ("angle", "speed", "torque")   # pmsm_drive
LINEAR = ("position", "velocity", "force")  # linear_motor


def run_on_inertia(drive: FmuInstance, load: RigidInertia, stop_time: float, step: float,
                   references: References, record: Sequence[str] = (),
                   ports: tuple[str, str, str] = ROTARY) -> np.ndarray:
    """Runs from drive.time to stop_time; returns a structured array with `time`, the recorded
    drive outputs and the load's `load.angle` and `load.speed` (position and velocity for a linear
    drive), one row per communication point. `ports` names the drive's position and velocity
    inputs and its effort output."""
    position, velocity, effort = ports
    reference_names = list(references(drive.time).keys())
    inputs = drive.real_group([position, velocity, *reference_names])
    outputs = drive.real_group([effort, *[name for name in record if name != effort]])
    n_steps = int(round((stop_time - drive.time) / step))
    columns = ["time", *outputs.names, "load.angle", "load.speed"]
    result = np.zeros(n_steps + 1, dtype=[(name, float) for name in columns])

    def write_row(row: int) -> None:
        result[row] = (drive.time, *outputs.values, load.angle, load.speed)

    inputs.values[:2] = load.angle, load.speed
    inputs.values[2:] = list(references(drive.time).values())
    inputs.write()
    outputs.read()
    write_row(0)
    for row in range(1, n_steps + 1):
        torque_before = outputs.values[0]
        drive.do_step(step)
        outputs.read()
        load.step(0.5 * (torque_before + outputs.values[0]), step)
        inputs.values[:2] = load.angle, load.speed
        inputs.values[2:] = list(references(drive.time).values())
        inputs.write()
        outputs.read()  # outputs that feed through from the new inputs
        write_row(row)
    return result
