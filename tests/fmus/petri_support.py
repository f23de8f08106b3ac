"""Shared by the Petri-net tests: nets by name, and one runner interface over the interpreter and the FMUs."""

from functools import cache

from fmpy.fmi1 import FMICallException

from fmus.petri import Interpreter, load_net, net_name

from .fmu_support import FMUS_DIR, TEST_NETS_DIR

PLANT_NETS_DIR = FMUS_DIR / "nets"


def net_files(folder):
    return sorted(path for path in folder.iterdir() if net_name(path))


PLANT_NETS = tuple(net_name(path) for path in net_files(PLANT_NETS_DIR))
TEST_NETS = tuple(net_name(path) for path in net_files(TEST_NETS_DIR))


@cache
def load(name):
    """The Net called name, from fmus/nets or tests/fmus/nets."""
    for path in net_files(PLANT_NETS_DIR) + net_files(TEST_NETS_DIR):
        if net_name(path) == name:
            return load_net(path)
    raise KeyError(name)


class PythonRunner:
    """A net on the reference interpreter, stepped like an FMU: t accumulates h as a double, as an importer's does."""

    engine = "python"

    def __init__(self, net, start_values):
        self.interpreter = Interpreter(net, start_values)
        self.time = 0.0

    def step(self, h, put=()):
        self.interpreter.step(self.time, h, put)
        self.time += h
        return self.outputs()

    def outputs(self):
        return self.interpreter.outputs()


class FMURunner:
    """A net's FMU through fmpy, with the interpreter's interface; all puts are set in every step."""

    def __init__(self, instance, net, start_values):
        self.instance = instance
        self.engine = f"fmi{instance.version}"
        instance.initialize(**start_values)
        vr = {name: variable.valueReference for name, variable in instance.variables.items()}
        self.places = [place.name for place in net.places]
        self.put_vrs = [vr[f"{place}_put"] for place in self.places]
        self.token_names = [f"{place}_tokens" for place in self.places]
        self.token_vrs = [vr[name] for name in self.token_names]
        self.bool_names = [f"{place}_{what}" for place in self.places for what in ("marked", "got")]
        self.bool_vrs = [vr[name] for name in self.bool_names]
        slave = instance.slave
        self._get_int = slave.getInteger if instance.version == 2 else slave.getInt32

    @property
    def time(self):
        return self.instance.time

    def step(self, h, put=()):
        unknown = set(put) - set(self.places)
        if unknown:
            raise KeyError(unknown)
        self.instance.slave.setBoolean(self.put_vrs, [place in put for place in self.places])
        try:
            self.instance.step(h)
        except FMICallException:
            raise RuntimeError("; ".join(self.instance.errors)) from None
        return self.outputs()

    def outputs(self):
        values = dict(zip(self.token_names, self._get_int(self.token_vrs)))
        values.update(zip(self.bool_names, (bool(b) for b in self.instance.slave.getBoolean(self.bool_vrs))))
        return {name: values[name] for place in self.places
                for name in (f"{place}_tokens", f"{place}_marked", f"{place}_got")}


def run_script(runner, steps, h, puts=None):
    """Step runner `steps` times; puts maps a 1-based step number to the places put in it.

    Returns [(t at the end of the step, outputs)] for every step."""
    trace = []
    for number in range(1, steps + 1):
        outputs = runner.step(h, (puts or {}).get(number, ()))
        trace.append((round(runner.time, 9), outputs))
    return trace


def times_when(trace, output):
    """The step end times at which output is true."""
    return [t for t, outputs in trace if outputs[output]]
