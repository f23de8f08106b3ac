"""A Petri net run by planthub's reference interpreter, exported by PythonFMU: a third-party FMU
with the same variables as the net's C FMU (fmus/petri). Built with the net file and the
`petri` package as project files; the net is the one file in resources ending in .pnml or
.net.yaml."""
import os

from petri.interpreter import Interpreter
from petri.load import load_net, net_name
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real


class petri_net_py(Fmi2Slave):
    author = "planthub tests"
    description = "Petri net in Python (planthub's reference interpreter)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        path = next(os.path.join(self.resources, f) for f in sorted(os.listdir(self.resources)) if net_name(f))
        self.net = load_net(path)
        self.interpreter = None
        for place in self.net.places:
            name = place.name
            setattr(self, f"{name}_put", False)
            setattr(self, f"{name}_initial", place.marking)
            setattr(self, f"{name}_tokens", place.marking)
            setattr(self, f"{name}_marked", place.marking > 0)
            setattr(self, f"{name}_got", False)
            self.register_variable(Boolean(f"{name}_put", causality=Fmi2Causality.input,
                                           variability=Fmi2Variability.discrete))
            self.register_variable(Integer(f"{name}_initial", causality=Fmi2Causality.parameter,
                                           variability=Fmi2Variability.fixed))
            for suffix, kind in (("tokens", Integer), ("marked", Boolean), ("got", Boolean)):
                self.register_variable(kind(f"{name}_{suffix}", causality=Fmi2Causality.output,
                                            variability=Fmi2Variability.discrete))
        for transition in self.net.delayed:
            setattr(self, f"{transition.name}_delay", transition.delay)
            self.register_variable(Real(f"{transition.name}_delay", causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.fixed))

    def exit_initialization_mode(self):
        start = {f"{p.name}_initial": getattr(self, f"{p.name}_initial") for p in self.net.places}
        start.update({f"{t.name}_delay": getattr(self, f"{t.name}_delay") for t in self.net.delayed})
        self.interpreter = Interpreter(self.net, start)
        self._publish()

    def do_step(self, current_time, step_size):
        put = [p.name for p in self.net.places if getattr(self, f"{p.name}_put")]
        self.interpreter.step(current_time, step_size, put)
        self._publish()
        return True

    def _publish(self):
        for place, tokens in self.interpreter.tokens.items():
            setattr(self, f"{place}_tokens", tokens)
            setattr(self, f"{place}_marked", tokens > 0)
            setattr(self, f"{place}_got", self.interpreter.got[place])
