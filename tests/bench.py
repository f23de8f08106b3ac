"""`make bench`'s cost sections for the hub's parts (tests/bench_report.py puts them in the report):
bottle models, FMU stepping, event latency, the recorder's flush; and the timing helpers they share.

Benchmarks report; they assert nothing. Each figure is the median of several repeats, and each
hub figure stands beside its floor (bare pybullet stepping of the same bodies, a plain Python
call for an FMU step) from the same run, because this 2-core machine is noisy: read the ratios.
"""
from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from hub.run.assembly import Run
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario

from .helpers import ROOT

BELT = ROOT / "scenarios" / "belt_bottle_sensor.yaml"
REPEATS = 5


def timed(fn) -> float:
    samples = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def hub_run(scenario, out: Path | None):
    def go():
        # With `out`, Run also writes summary.json at close, which the old Master-with-Recorder did not.
        with Run(scenario, out=out) as run:
            run.run()
        return run.recorder
    return go


def floor_run(scenario):
    """The floor: pybullet alone steps the plant's bodies (not a run: a bare Plant)."""
    def go():
        with Plant(scenario) as plant:
            plant.world.step_engine_only(scenario.run.end_tick)
    return go


def line_scene(n: int, seconds: float = 10.0, barriers: int = 1, transport: str = "engine"):
    """`n` bottles 8 cm apart on one long belt at 0.5 m/s (150 Hz), `barriers` light barriers
    10 cm apart past them (each watched by the recording, so its trigger is evaluated); each
    bottle's `transport` (hub/physics/transport.py)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "line.yaml"
        spacing = 0.08
        bottles = "\n".join(
            f"  b{i}: {{module: bottle, position: [{0.04 + i * spacing:.3f}, 0, 0], transport: {transport}}}"
            for i in range(n))
        gates = "".join(f"  gate{g}: {{module: light_barrier, position: [{n * spacing + 1 + 0.1 * g:.2f}, 0, 0.05]}}\n"
                        for g in range(barriers))
        record = "".join(f"  - gate{g}.trigger.occupied\n" for g in range(barriers))
        path.write_text(
            f"planthub: 1\nrun: {{duration: {seconds}, physics_rate: 150}}\nobjects:\n"
            f"  belt: {{module: conveyor, position: [0, 0, 0], length: {n * spacing + 6 + 0.1 * barriers:.2f}, "
            f"speed: 0.5}}\n" + gates + bottles + "\n" + (f"record:\n{record}" if record else ""))
        return load_scenario(path)


class PythonBeltDrive:
    """The belt_drive FMU's logic written in plain Python: the floor for FMU stepping."""

    def __init__(self, ramp: float):
        self.ramp, self.speed, self.run, self.setpoint = ramp, 0.0, False, 0.0

    def set_inputs(self, values):
        self.run, self.setpoint = values

    def step(self, t, h):
        target = self.setpoint if self.run else 0.0
        gap, most = target - self.speed, self.ramp * h
        if gap != 0.0:
            self.speed = target if abs(gap) <= most * (1 + 1e-9) else self.speed + (most if gap > 0 else -most)

    def outputs(self):
        return [self.speed, self.speed != 0.0]


def fmu_stepping() -> None:
    from hub.logic.fmi import FmuSlave, inspect_fmu

    print("\n## Logic stepping: N belt_drive instances per communication step (set inputs, doStep, get outputs)\n")
    print("| instances | FMI 2.0 FMU µs/step | FMI 3.0 FMU µs/step | plain Python µs/step | FMI 2.0 / Python |")
    print("|---:|---:|---:|---:|---:|")
    steps = 2000
    for n in (10, 50):
        costs = {}
        for kind in ("fmi2", "fmi3", "python"):
            if kind == "python":
                make = lambda i: PythonBeltDrive(0.5)
            else:
                interface = inspect_fmu(ROOT / "build" / "fmus" / f"belt_drive-{kind}.fmu")
                make = lambda i, f=interface: FmuSlave(f, f"d{i}", ["run", "speed_setpoint"],
                                                       ["speed", "running"], {"ramp": 0.5})
            instances = [make(i) for i in range(n)]
            clock = iter(range(10**9))

            def loop():
                for _ in range(steps):
                    k = next(clock)
                    t = k * 0.01
                    for inst in instances:
                        inst.set_inputs([k % 400 < 200, 0.5])
                        inst.step(t, 0.01)
                        inst.outputs()
            costs[kind] = timed(loop) / steps
            for inst in instances:
                getattr(inst, "close", lambda: None)()
        print(f"| {n} | {1e6 * costs['fmi2']:.0f} | {1e6 * costs['fmi3']:.0f} | {1e6 * costs['python']:.0f} "
              f"| {costs['fmi2'] / costs['python']:.1f} |")


def event_latency() -> None:
    import csv

    print("\n## Sensor-to-actuator latency: light barrier → belt_drive FMU → belt (belt_ramp_fmu.yaml)\n")
    print("| communication step | fixed grid | event-driven | removed |")
    print("|---:|---:|---:|---:|")
    scenario_file = ROOT / "scenarios" / "belt_ramp_fmu.yaml"
    for step in (0.02, 0.1, 0.2):
        latency = {}
        for driven in (False, True):
            scenario = load_scenario(scenario_file, {"run.communication_step": step, "run.event_driven": driven})
            with tempfile.TemporaryDirectory() as tmp:
                hub_run(scenario, Path(tmp))()
                with open(Path(tmp) / "events.csv") as f:
                    enter = next(float(e["time"]) for e in csv.DictReader(f) if e["slot"].endswith("on_enter"))
                with open(Path(tmp) / "recording.csv") as f:
                    react = next(float(r["time"]) for r in csv.DictReader(f)
                                 if float(r["time"]) > enter and float(r["drive.logic.speed"]) < 0.5)
            latency[driven] = react - enter
        print(f"| {1000 * step:.0f} ms | {1000 * latency[False]:.0f} ms | {1000 * latency[True]:.0f} ms "
              f"| {100 * (1 - latency[True] / latency[False]):.0f} % |")


def bottle_models() -> None:
    from hub.reports.cost import lod_costs

    bottles, ticks = 20, 450
    print(f"\n## Bottle levels of detail: cost per physics tick, {bottles} bottles (150 Hz, {ticks} ticks)\n")
    print("Physics world only (engine, belt field, state reads), beside the simple model from the same run.\n")
    print("| model | shape | on a belt µs/tick | × simple | off every belt µs/tick | × simple |")
    print("|---|---|---:|---:|---:|---:|")
    costs = {(c.model, c.shape, c.on_belt): c.microseconds for c in lod_costs(bottles, ticks, REPEATS)}
    for shape in ("cylinder", "hull"):
        for model in ("simple", "base_point", "base_body"):
            on, off = costs[(model, shape, True)], costs[(model, shape, False)]
            print(f"| {model} | {shape} | {on:.0f} | {on / costs[('simple', shape, True)]:.2f} "
                  f"| {off:.0f} | {off / costs[('simple', shape, False)]:.2f} |")


def flush_cost() -> None:
    """The recorder's bounded flush (hub/run/recorder.py FLUSH_PERIOD): the same recorded run with
    the files flushed every 0.5 s of wall time and never flushed until closed, alternated."""
    from hub.run import recorder as recording

    print("\n## The recorder's flush: files readable after a kill, and what it costs\n")
    print("| flush | µs per communication point (median) | ratio |")
    print("|---|---:|---:|")
    scenario = load_scenario(BELT, {"record": ["bottle.body.position", "bottle.body.velocity",
                                               "barrier.trigger.occupied", "belt.drive.velocity"]})
    points = scenario.run.end_tick // scenario.run.substeps + 1
    samples = {"every 0.5 s": [], "never (closed only)": []}
    default = recording.FLUSH_PERIOD
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(max(REPEATS, 5)):
                for name, period in (("every 0.5 s", default), ("never (closed only)", float("inf"))):
                    recording.FLUSH_PERIOD = period
                    started = time.perf_counter()
                    hub_run(scenario, Path(tmp))()
                    samples[name].append(1e6 * (time.perf_counter() - started) / points)
    finally:
        recording.FLUSH_PERIOD = default
    floor = statistics.median(samples["never (closed only)"])
    for name, values in samples.items():
        print(f"| {name} | {statistics.median(values):.1f} | {statistics.median(values) / floor:.3f} |")


def model_exchange() -> None:
    """A model-exchange FMU integrated by the hub: speed against error per solver setting, beside a
    co-simulation FMU's step (the floor: the FMU integrates itself) — the bouncing ball of
    tests/test_model_exchange.py for 3 s at a 10 ms communication step, against its exact height."""
    from hub.logic.fmi import FmuSlave, inspect_fmu
    from hub.logic.fmi_me import Integration, open_fmu

    from .foreign_fmus import build
    from .test_model_exchange import ball_height

    with tempfile.TemporaryDirectory() as folder:
        ball = inspect_fmu(build("ball2", 2, Path(folder)))
        drive = inspect_fmu(ROOT / "build" / "fmus" / "belt_drive-fmi2.fmu")
        h, steps = 0.01, 300
        print("\n## Model exchange: the bouncing ball (FMI 2, 11 impacts in 3 s), 10 ms communication step\n")
        print("| solver | µs per communication step | ÷ a co-simulation FMU's step | largest height error, m |")
        print("|---|---:|---:|---:|")

        def stepped(slave, check=None) -> float:
            """s per communication step of `slave` over the 3 s, its making and closing not counted."""
            start = time.perf_counter()
            for k in range(steps):
                slave.set_inputs([k % 100 < 50, 0.5] if check is None else [])
                slave.step(k * h, h)
                out = slave.outputs()
                if check is not None:
                    check((k + 1) * h, out[0])
            spent = time.perf_counter() - start
            slave.close()
            return spent / steps

        floor = lambda: FmuSlave(drive, "d", ["run", "speed_setpoint"], ["speed", "running"], {"ramp": 0.5})
        base = statistics.median(stepped(floor()) for _ in range(REPEATS))
        settings = [("cvode, tolerance 1e-4", Integration(tolerance=1e-4)),
                    ("cvode, tolerance 1e-6 (default)", Integration()),
                    ("cvode, tolerance 1e-8", Integration(tolerance=1e-8)),
                    ("euler, max_step 1 ms", Integration(solver="euler", max_step=1e-3)),
                    ("euler, max_step 0.1 ms", Integration(solver="euler", max_step=1e-4))]
        for label, integration in settings:
            heights = []
            record = lambda t, height: heights.append((t, height))
            cost = statistics.median(stepped(open_fmu(ball, "b", [], ["h"], {}, integration=integration), record)
                                     for _ in range(REPEATS))
            error = max(abs(height - ball_height(t)) for t, height in heights)
            print(f"| {label} | {1e6 * cost:.0f} | {cost / base:.1f} | {error:.1e} |")
        print(f"\nThe floor, belt_drive (FMI 2 co-simulation) set, stepped and read: {1e6 * base:.0f} µs a step.")
