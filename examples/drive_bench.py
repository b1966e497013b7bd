"""A drive FMU on a test bench: one instance turning a rigid inertia, coupled at a fixed step
(used by examples/drive_demo.py and by the drive tests; not part of the cosim package).

The drive steps first from the load's state at t (Gauss-Seidel); the load then advances with the
mean of the drive's torque at t and t + h (trapezoidal coupling, second order in h).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from cosim.engine.fmi import FmuInstance


@dataclass
class RigidInertia:
    """A rigid shaft: J dw/dt = T - B w - T_load, advanced over a step with the torque given
    (explicit Euler in the speed, trapezoidal in the angle)."""

    inertia: float            # J [kg m^2]
    viscous_friction: float = 0.0  # B [N m s/rad]
    load_torque: float = 0.0  # T_load [N m]
    angle: float = 0.0        # [rad]
    speed: float = 0.0        # [rad/s]

    def step(self, torque: float, h: float) -> None:
        accel = (torque - self.load_torque - self.viscous_friction * self.speed) / self.inertia
        new_speed = self.speed + h * accel
        self.angle += 0.5 * h * (self.speed + new_speed)
        self.speed = new_speed


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
