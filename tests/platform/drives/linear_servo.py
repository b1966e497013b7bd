"""A linear position servo written in Python and exported with pythonfmu (tests/platform/test_user_drives.py):
a PD on the leg length with the reference's rate (the optional input velocity_ref), the force
limited; its state can be got and set (pythonfmu's --handle-state), so step doubling may roll it
back. It keeps the linear drive ports of ../shared/INTERFACES.md."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class linear_servo(Fmi2Slave):
    author = "stewart-cosim tests"
    description = "PD position servo on the leg length (linear drive ports)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.position_ref = self.position = self.velocity = self.velocity_ref = self.force = 0.0
        self.kp, self.kd = 3.0e6, 1.2e5              # [N/m], [N s/m]
        self.force_max, self.force_continuous = 2.0e4, 5.0e3  # [N]
        for name in ("position_ref", "position", "velocity", "velocity_ref"):
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        self.register_variable(Real("force", causality=Fmi2Causality.output))
        for name in ("kp", "kd", "force_max", "force_continuous"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))

    def do_step(self, current_time, step_size):
        force = self.kp * (self.position_ref - self.position) + self.kd * (self.velocity_ref - self.velocity)
        self.force = max(-self.force_max, min(self.force_max, force))
        return True
