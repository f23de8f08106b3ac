"""`make bench`, the bottling plant: cost per tick with 100 bottles on the line at 150 Hz, beside
bare pybullet stepping of the same scene, with the routing logic in the hub and over Zenoh.

From 100 s to 110 s of scenarios/bottling_plant.yaml about 100 bottles are on the line (95–101
from 80 s to 125 s; most of them stand in the magazine's queue): the hub steps that window with everything (fields,
triggers, 8 logic FMUs, the plant-management logic, the flows), then bare pybullet steps the
same bodies as many ticks from where the hub left them. Medians of 3, measured alternately.
"""
from __future__ import annotations

import statistics
import time

from hub.master import Master
from hub.plant import Plant
from hub.recorder import Recorder
from hub.scenario import load_scenario

from .helpers import ROOT

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
WINDOW = (100.0, 110.0)
REPEATS = 3


def on_line(world) -> int:
    return int((world.positions[:, 2] > -50.0).sum())   # parked and delivered bodies wait 100 m down


def window(in_process: bool) -> tuple[float, float, str]:
    """(hub s, bare pybullet s, bottles on the line at the window's start–end)."""
    scenario = load_scenario(PLANT, {"objects.control.in_process": in_process})
    rate = scenario.run.physics_rate
    start, end = (round(t * rate) for t in WINDOW)
    with Plant(scenario) as plant:
        with Master(plant, Recorder([], rate)) as master:
            master.start()
            master.run(until_tick=start)
            world = plant.world
            first = on_line(world)
            began = time.perf_counter()
            master.run(until_tick=end)
            hub = time.perf_counter() - began
            count = f"{first}–{on_line(world)}"
        began = time.perf_counter()
        world.step_engine_only(end - start)
        bare = time.perf_counter() - began
    return hub, bare, count


def bottling_plant() -> None:
    print(f"\n## The bottling plant at 150 Hz with 100 bottles on the line ({WINDOW[0]:g}–{WINDOW[1]:g} s)\n")
    print("| routing logic | bottles on the line | hub µs/tick | bare pybullet µs/tick | hub / bare "
          "| hub real-time factor | bare real-time factor |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    ticks = round((WINDOW[1] - WINDOW[0]) * 150)
    samples = {True: [], False: []}
    for _ in range(REPEATS):
        for in_process in (True, False):
            samples[in_process].append(window(in_process))
    for in_process, label in ((True, "in the hub"), (False, "participant over Zenoh")):
        hub = statistics.median(s[0] for s in samples[in_process])
        bare = statistics.median(s[1] for s in samples[in_process])
        count = samples[in_process][0][2]
        sim = WINDOW[1] - WINDOW[0]
        print(f"| {label} | {count} | {1e6 * hub / ticks:.0f} | {1e6 * bare / ticks:.0f} | {hub / bare:.2f} "
              f"| {sim / hub:.1f}× | {sim / bare:.1f}× |")


if __name__ == "__main__":
    bottling_plant()
