"""A rotary position servo written in Python and exported with pythonfmu (tests/platform/test_user_drives.py):
a PID on the motor angle, its derivative from the reference's difference quotient and the measured
speed, the torque limited. It keeps the rotary drive ports of ../shared/INTERFACES.md and nothing else."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class rotary_servo(Fmi2Slave):
    author = "stewart-cosim tests"
    description = "PID position servo on the motor angle (rotary drive ports)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.angle_ref = self.angle = self.speed = self.torque = 0.0
        self.kp, self.ki, self.kd = 80.0, 0.0, 2.6               # [N m/rad], [N m/(rad s)], [N m s/rad]
        self.torque_max, self.torque_continuous = 60.0, 20.0     # [N m]
        self.integral = self.previous_ref = 0.0
        self.started = False
        for name in ("angle_ref", "angle", "speed"):
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        self.register_variable(Real("torque", causality=Fmi2Causality.output))
        for name in ("kp", "ki", "kd", "torque_max", "torque_continuous"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("integral", causality=Fmi2Causality.local))
        self.register_variable(Real("previous_ref", causality=Fmi2Causality.local))

    def do_step(self, current_time, step_size):
        error = self.angle_ref - self.angle
        speed_ref = (self.angle_ref - self.previous_ref) / step_size if self.started else 0.0
        self.previous_ref, self.started = self.angle_ref, True
        self.integral += error * step_size
        torque = self.kp * error + self.ki * self.integral + self.kd * (speed_ref - self.speed)
        self.torque = max(-self.torque_max, min(self.torque_max, torque))
        return True
