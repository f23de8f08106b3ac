"""Per-step cost of the net FMUs through fmpy against the Python interpreter (a report, not a test).

Run from the repository root after `make fmus`: .venv/bin/python -m tests.fmus.bench_petri [steps]"""

import sys
import tempfile
import time

import fmpy
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from fmus.petri import Interpreter

from .fmu_support import REPO
from .petri_support import PLANT_NETS, load

H = 0.01


def per_step(function, steps):
    start = time.perf_counter()
    for _ in range(steps):
        function()
    return (time.perf_counter() - start) / steps * 1e6


def fmu_costs(name, version, steps):
    """(doStep alone, set every put + doStep + get every output) in µs, through fmpy's low-level slave."""
    net, path = load(name), REPO / "build" / "fmus" / f"{name}-fmi{version}.fmu"
    description = fmpy.read_model_description(str(path))
    unzipped = tempfile.mkdtemp(prefix=f"bench-{name}-")
    fmpy.extract(str(path), unzipped)
    slave = (FMU2Slave if version == 2 else FMU3Slave)(
        guid=description.guid, unzipDirectory=unzipped,
        modelIdentifier=description.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    if version == 2:
        slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    vr = {v.name: v.valueReference for v in description.modelVariables}
    puts = [vr[f"{p.name}_put"] for p in net.places]
    tokens = [vr[f"{p.name}_tokens"] for p in net.places]
    flags = [vr[f"{p.name}_{what}"] for p in net.places for what in ("marked", "got")]
    get_int = slave.getInteger if version == 2 else slave.getInt32
    values = [False] * len(puts)
    clock = {"t": 0.0}

    def do_step():
        slave.doStep(clock["t"], H)
        clock["t"] += H

    def exchange():
        slave.setBoolean(puts, values)
        do_step()
        get_int(tokens)
        slave.getBoolean(flags)

    try:
        return per_step(do_step, steps), per_step(exchange, steps)
    finally:
        slave.terminate()
        slave.freeInstance()


def interpreter_costs(name, steps):
    interpreter, clock = Interpreter(load(name)), {"t": 0.0}

    def step():
        interpreter.step(clock["t"], H)
        clock["t"] += H

    def exchange():
        step()
        interpreter.outputs()

    return per_step(step, steps), per_step(exchange, steps)


def rows(steps: int):
    """(net, engine, µs a step, µs a step with I/O) for every plant net: FMI 2, FMI 3, the interpreter."""
    for name in PLANT_NETS:
        for version in (2, 3):
            yield (name, f"fmi{version}", *fmu_costs(name, version, steps))
        yield (name, "python", *interpreter_costs(name, steps))


def markdown(steps: int = 20000) -> None:
    """The same figures as a markdown table (for `make bench`'s report)."""
    print(f"\n## Petri-net state logic: µs per step, mean of {steps} steps of {H} s\n")
    print("'with I/O' sets every input and reads every output; python: the same net in the interpreter, the floor.\n")
    print("| net | engine | step µs | with I/O µs |")
    print("|---|---|---:|---:|")
    for name, engine, alone, with_io in rows(steps):
        print(f"| {name} | {engine} | {alone:.1f} | {with_io:.1f} |")


def main(argv):
    steps = int(argv[0]) if argv else 20000
    print(f"µs per step, mean of {steps} steps of {H} s; 'with I/O' sets every put and reads every output")
    print(f"{'net':<14} {'engine':<8} {'step':>8} {'with I/O':>9}")
    for name, engine, alone, with_io in rows(steps):
        print(f"{name:<14} {engine:<8} {alone:8.1f} {with_io:9.1f}")


if __name__ == "__main__":
    main(sys.argv[1:])
