"""`make bench`, scale: 1000 bottles on one belt with every default (free transport), and a hall of
ten bottling lines side by side (tests/hall.py: one generated scenario, about 1000 bottles on the
lines from 80 s on), each against bare pybullet stepping the same bodies, all awake, on from where
the hub left them. The hall: its 100–110 s (routing in the hub), after a run from 0 s that is
timed too. One line (the bottling plant itself) is the bottling-plant section's."""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .bench import line_scene
from .bench_report import warm_cost
from .hall import write_hall

LINES = 10
WINDOW = (100.0, 110.0)


def one_belt(n: int = 1000) -> None:
    warm, ticks = 75, 450
    scenario = line_scene(n, seconds=(warm + ticks) / 150, transport="free")
    hub, bare = warm_cost(scenario, warm, ticks, False), warm_cost(scenario, warm, ticks, True)
    print(f"\n## {n} bottles on one belt, every default (free transport)\n")
    print("| bottles | hub µs/tick | bare pybullet µs/tick | hub / bare | hub real-time factor | bare real-time factor |")
    print("|---:|---:|---:|---:|---:|---:|")
    print(f"| {n} | {1e6 * hub:.0f} | {1e6 * bare:.0f} | {hub / bare:.2f} | {1 / (150 * hub):.1f}× "
          f"| {1 / (150 * bare):.1f}× |")


def hall() -> None:
    began = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        scenario = load_scenario(write_hall(Path(tmp) / "hall.yaml", LINES, WINDOW[1]))
    rate = scenario.run.physics_rate
    start, end = (round(t * rate) for t in WINDOW)
    with Run(scenario) as run:   # the scenario checked and the hall built
        run.start()
        built = time.perf_counter() - began
        began = time.perf_counter()
        run.run(until_tick=start)
        filling = time.perf_counter() - began
        world = run.plant.world
        on_line = int((world.positions[:, 2] > -50.0).sum())
        began = time.perf_counter()
        run.run(until_tick=end)
        hub = time.perf_counter() - began
        run.master.close("the window is measured")
        world.transport.release(world.transport.rows)
        world.wake_all()
        began = time.perf_counter()
        world.step_engine_only(end - start)
        bare = time.perf_counter() - began
    sim = WINDOW[1] - WINDOW[0]
    print(f"\n## A hall of {LINES} bottling lines (tests/hall.py), {WINDOW[0]:g}–{WINDOW[1]:g} s\n")
    print("| bottles on the lines | hub s | bare pybullet s | hub / bare | hub real-time factor "
          "| bare real-time factor | 0–100 s real-time factor | checked and built, s |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    print(f"| {on_line} | {hub:.1f} | {bare:.1f} | {hub / bare:.2f} | {sim / hub:.2f}× | {sim / bare:.2f}× "
          f"| {WINDOW[0] / filling:.2f}× | {built:.1f} |")


def scale() -> None:
    one_belt()
    hall()


if __name__ == "__main__":
    scale()
