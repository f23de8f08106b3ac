"""`make bench`, checkpoints: the bottling plant at its busiest, saved and put back, beside one communication step's time.

At T (the line full: the report gives how many bottles are in play) a checkpoint is captured
again and again (the median is the save); a freshly built run is handed it and started, against
the same fresh run started without one (the difference, median, is the restore: reading the
file, checking it and putting every part back). The floor is one communication step of the same
plant at the same point (the median over the next second), and real time's step (20 ms at 50 Hz).
The routing logic runs in the hub, so no participant process starts beside a run.
Run alone: `python -m tests.bench_checkpoint`.
"""
from __future__ import annotations

import statistics
import time

from hub.run import checkpoint
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "bottling_plant.yaml"
AT = 45.0          # s: the line is full (make run: the busiest window is 40–60 s)
REPEATS = 7
SETS = {"objects.control.runs": "hub"}


def _started(data: bytes | None) -> float:
    """Seconds to start a freshly built run, handed `data` or not (its build is not counted)."""
    run = Run(load_scenario(SCENARIO, SETS), resume=None if data is None else (data, "bench"))
    with run:
        began = time.perf_counter()
        run.start()
        return time.perf_counter() - began


def checkpoints() -> None:
    scenario = load_scenario(SCENARIO, SETS)
    rate, substeps = scenario.run.physics_rate, scenario.run.substeps
    tick = round(AT * rate) // substeps * substeps
    with Run(scenario) as run:
        run.run(tick)
        world = run.plant.world
        in_play = len(world.bodies.ids) - len(world.bodies.parked)
        saves = []
        for _ in range(REPEATS):
            began = time.perf_counter()
            data = checkpoint.capture(run)
            saves.append(time.perf_counter() - began)
        steps = []
        for n in range(1, rate // substeps + 1):
            began = time.perf_counter()
            run.run(tick + n * substeps)
            steps.append(time.perf_counter() - began)
    restores = [_started(data) - _started(None) for _ in range(REPEATS)]
    step = statistics.median(steps)
    real = substeps / rate
    print(f"\n## Checkpoints: the bottling plant at {AT:g} s, {in_play} bottles in play\n")
    print("| figure | value |")
    print("|---|---:|")
    for name, value in (("checkpoint size (kB)", f"{len(data) / 1e3:.0f}"),
                        ("save, median (ms)", f"{1e3 * statistics.median(saves):.1f}"),
                        ("restore into a freshly built run, median (ms)", f"{1e3 * statistics.median(restores):.1f}"),
                        ("one communication step of the same plant, median (ms)", f"{1e3 * step:.1f}"),
                        ("save / one step", f"{statistics.median(saves) / step:.2f}"),
                        ("a step in real time (ms)", f"{1e3 * real:.0f}")):
        print(f"| {name} | {value} |")


if __name__ == "__main__":
    checkpoints()
