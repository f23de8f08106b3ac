"""The belt_drive FMU's logic as a PythonFMU class: a third-party FMU (FMI 2.0, exported by PythonFMU)."""
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class belt_drive_py(Fmi2Slave):
    author = "planthub"
    description = "belt drive in Python"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.run = False
        self.speed_setpoint = 0.0
        self.ramp = 0.0
        self.speed = 0.0
        self.running = False
        self.register_variable(Boolean("run", causality=Fmi2Causality.input, variability=Fmi2Variability.discrete))
        self.register_variable(Real("speed_setpoint", causality=Fmi2Causality.input))
        self.register_variable(Real("ramp", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("speed", causality=Fmi2Causality.output))
        self.register_variable(Boolean("running", causality=Fmi2Causality.output, variability=Fmi2Variability.discrete))

    def do_step(self, current_time, step_size):
        target = self.speed_setpoint if self.run else 0.0
        gap = target - self.speed
        most = self.ramp * step_size
        # Same arithmetic, in the same order, as fmus/models/belt_drive/model.c: equal doubles.
        if gap != 0.0:
            if self.ramp == 0.0 or abs(gap) <= most * (1.0 + 1e-9):
                self.speed = target
            else:
                self.speed += most if gap > 0 else -most
        self.running = self.speed != 0.0
        return True
