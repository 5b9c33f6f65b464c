"""A PythonFMU slave with internal state for the checkpoint tests (#29 item 6): a skyhook force
on the body speed low-passed at 5 Hz (F_d = -c_sky * x, dx/dt = (v_b - x) / tau), forward
Euler inside doStep. The filter state x is a local variable, so PythonFMU's get/set FMU state
(all variables) holds the whole state."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class FilteredSkyhook(Fmi2Slave):
    author = "suscosim tests"
    description = "skyhook on a low-passed body speed (state for get/set FMU state)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.v_b = 0.0
        self.v_w = 0.0
        self.F_d = 0.0
        self.x = 0.0
        self.c_sky = 2000.0
        self.tau = 1.0 / (2.0 * 3.141592653589793 * 5.0)
        self.register_variable(Real("v_b", causality=Fmi2Causality.input))
        self.register_variable(Real("v_w", causality=Fmi2Causality.input))
        self.register_variable(Real("F_d", causality=Fmi2Causality.output))
        self.register_variable(Real("x", causality=Fmi2Causality.local))
        self.register_variable(Real("c_sky", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))

    def do_step(self, current_time, step_size):
        self.x += step_size * (self.v_b - self.x) / self.tau
        self.F_d = -self.c_sky * self.x
        return True
