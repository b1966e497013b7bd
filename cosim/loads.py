"""Small mechanical loads for driving one drive FMU on a test bench, without the platform."""

from __future__ import annotations

from dataclasses import dataclass


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
