"""`make bench`, the bottling plant: cost per tick with 100 bottles on the line at 150 Hz, with
bottles in free transport (the default, hub/physics/transport.py) and moved by the
engine all the way (`transport: engine`), the routing logic in the hub and
over Zenoh, and with bottles at rest left asleep (hub/physics/rest.py) and without; what
letting them ride free, and leaving them asleep, changes in the deliveries; and the whole plant
(`make run`'s 150 orders) both ways.

From 100 s to 110 s of scenarios/bottling_plant.yaml about 100 bottles are on the line (95–101
from 80 s to 125 s; most of them stand in the magazine's queue, which stops while a bottle waits
at the separator): the hub steps that window with everything (fields, triggers, 8 logic FMUs,
the plant-management logic, the flows), timing pybullet's stepSimulation inside it; then bare
pybullet steps the same bodies, all awake, as many ticks from where the hub left them. Medians
of REPEATS (2: the report must fit in 20 min), measured alternately, and the slowest–fastest real-time factor.
"""
from __future__ import annotations

import statistics
import time

import numpy as np

from hub.physics.world import pybullet
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario
from modules.sink import Bin

from .helpers import ROOT

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
WINDOW = (100.0, 110.0)
REPEATS = 2
COMPARED = 150.0    # s of the plant run with and without rest for the deliveries
FREE = {"defaults.source.transport": "free"}   # every bottle of the plant may ride free (transport.py)
ENGINE = {"defaults.source.transport": "engine"}   # the engine moves every bottle


def on_line(world) -> int:
    return int((world.positions[:, 2] > -50.0).sum())   # parked and delivered bodies wait 100 m down


class EngineClock:
    """Time spent in pybullet.stepSimulation while installed: the engine's own part of a run."""

    def __init__(self):
        self.seconds = 0.0
        self._step = None

    def __enter__(self):
        self._step = step = pybullet.stepSimulation

        def timed(*args, **kwargs):
            began = time.perf_counter()
            step(*args, **kwargs)
            self.seconds += time.perf_counter() - began
        pybullet.stepSimulation = timed
        return self

    def __exit__(self, *exc):
        pybullet.stepSimulation = self._step


def window(in_process: bool, sleep_after: float | None, more: dict | None = None) -> tuple[float, float, float, str, float]:
    """(hub s, of it the engine s, bare pybullet s, bottles on the line at the window's
    start–end, mean asleep). Bare: pybullet alone steps the same bodies as many ticks from
    where the hub left them, every one awake (as in a world without rest). `more`: further
    overrides (free transport)."""
    overrides = {"objects.control.runs": "hub" if in_process else "bus", **(more or {})}
    if sleep_after is not None:
        overrides["run.sleep_after"] = sleep_after
    scenario = load_scenario(PLANT, overrides)
    rate = scenario.run.physics_rate
    start, end = (round(t * rate) for t in WINDOW)
    # Run adds the plant tally its sources and sinks contribute (as `planthub run` does): in the hub's time.
    with Run(scenario) as run:
        run.start()   # joining the bus and launching the participants are not timed
        run.run(until_tick=start)
        world = run.plant.world
        first = on_line(world)
        resting = []
        with EngineClock() as engine:
            began = time.perf_counter()
            for tick in range(start, end, 30):      # a look every 0.2 s
                run.run(until_tick=tick + 30)
                resting.append(int(world.rest.resting.sum()))
            hub = time.perf_counter() - began
        count = f"{first}–{on_line(world)}"
        run.master.close("the window is measured")   # participants stopped before the floor, as before
        world.transport.release(world.transport.rows)   # every bottle back in the engine, awake
        world.wake_all()
        began = time.perf_counter()
        world.step_engine_only(end - start)
        bare = time.perf_counter() - began
    return hub, engine.seconds, bare, count, statistics.mean(resting)


def deliveries(sleep_after: float | None, more: dict | None = None) -> tuple[dict[str, tuple[str, float]], float]:
    """{bottle: (sink, time)} over the first COMPARED seconds, and the wall time."""
    overrides = {"objects.control.runs": "hub", "run.duration": COMPARED, **(more or {})}
    if sleep_after is not None:
        overrides["run.sleep_after"] = sleep_after
    scenario = load_scenario(PLANT, overrides)
    rate = scenario.run.physics_rate
    # Run adds the plant tally its sources and sinks contribute (as `planthub run` does): in the wall time.
    with Run(scenario) as run:
        began = time.perf_counter()
        run.run()
        wall = time.perf_counter() - began
        sinks = [c for c in run.plant.components if isinstance(c, Bin)]
        taken = {d.bottle: (sink.obj, d.tick / rate) for sink in sinks for d in sink.deliveries}
    return taken, wall


def whole_plant(more: dict) -> tuple[float, int, int]:
    """`make run`'s plant (150 orders, routing over Zenoh as the scenario has it): (wall s, simulated
    ticks, delivered)."""
    scenario = load_scenario(PLANT, more)
    with Run(scenario) as run:
        run.start()
        began = time.perf_counter()
        result = run.run()
        wall = time.perf_counter() - began
        delivered = sum(len(c.deliveries) for c in run.plant.components if isinstance(c, Bin))
    return wall, result.ticks, delivered


def bottling_plant() -> None:
    print(f"\n## The bottling plant at 150 Hz with 100 bottles on the line ({WINDOW[0]:g}–{WINDOW[1]:g} s)\n")
    print("| transport | bottles at rest | routing logic | bottles on the line | of them asleep (mean) | hub µs/tick "
          "| of it the engine | bare pybullet, all awake | hub / bare | hub real-time factor (slowest–fastest) "
          "| bare real-time factor |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    ticks = round((WINDOW[1] - WINDOW[0]) * 150)
    cases = (("free (default)", None, True, "asleep (default)", "in the hub", FREE),
             ("free (default)", None, False, "asleep (default)", "over Zenoh", FREE),
             ("engine", None, True, "asleep (default)", "in the hub", ENGINE),
             ("engine", None, False, "asleep (default)", "over Zenoh", ENGINE),
             ("engine", 0.0, True, "awake (`sleep_after: 0`)", "in the hub", ENGINE))
    samples = [[] for _ in cases]
    for _ in range(REPEATS):
        for case, taken in zip(cases, samples):
            taken.append(window(case[2], case[1], case[5]))
    sim = WINDOW[1] - WINDOW[0]
    for case, taken in zip(cases, samples):
        hub, engine, bare = (statistics.median(s[k] for s in taken) for k in range(3))
        count, resting = taken[0][3], statistics.median(s[4] for s in taken)
        spread = f"{sim / max(s[0] for s in taken):.1f}–{sim / min(s[0] for s in taken):.1f}"
        print(f"| {case[0]} | {case[3]} | {case[4]} | {count} | {resting:.0f} | {1e6 * hub / ticks:.0f} "
              f"| {1e6 * engine / ticks:.0f} | {1e6 * bare / ticks:.0f} | {hub / bare:.2f} | {sim / hub:.1f}× ({spread}) "
              f"| {sim / bare:.1f}× |")

    free, wall_free = deliveries(None, FREE)
    engine, wall_engine = deliveries(None, ENGINE)
    compare("free transport", "transport", ("free (default)", free, wall_free), ("engine", engine, wall_engine))
    awake, wall_awake = deliveries(0.0, ENGINE)
    compare("rest", "bottles at rest (transport: engine)", ("asleep", engine, wall_engine), ("awake", awake, wall_awake))

    print("\n### The whole plant (`make run`: 150 orders, routing over Zenoh)\n")
    print("| transport | simulated s | bottles into the sinks (rejects too) | wall s | real-time factor |")
    print("|---|---:|---:|---:|---:|")
    for label, more in (("free (default)", FREE), ("engine", ENGINE)):
        wall, sim_ticks, delivered = whole_plant(more)
        print(f"| {label} | {sim_ticks / 150:.1f} | {delivered} | {wall:.1f} | {sim_ticks / 150 / wall:.1f}× |")


def compare(saving: str, column: str, on, off) -> None:
    """The deliveries of the first COMPARED s with a saving on and off: (label, {bottle: (sink, time)}, wall s) each."""
    (on_label, on_taken, _), (off_label, off_taken, _) = on, off
    print(f"\n### What {saving} changes: the first {COMPARED:g} s, routing in the hub\n")
    both = sorted(set(on_taken) & set(off_taken))
    shift = np.array([on_taken[b][1] - off_taken[b][1] for b in both])
    same_sink = sum(on_taken[b][0] == off_taken[b][0] for b in both)
    print(f"| {column} | delivered | wall s | real-time factor |")
    print("|---|---:|---:|---:|")
    for label, taken, wall in (on, off):
        print(f"| {label} | {len(taken)} | {wall:.1f} | {COMPARED / wall:.1f}× |")
    print(f"\nDelivered in both: {len(both)}, to the same sink: {same_sink}; delivery time {on_label} − {off_label}: "
          f"median {np.median(shift):+.3f} s, mean |Δ| {np.abs(shift).mean():.3f} s, "
          f"largest {shift[np.argmax(np.abs(shift))]:+.3f} s; within one communication step (20 ms): "
          f"{int((np.abs(shift) <= 0.02 + 1e-9).sum())}.")


if __name__ == "__main__":
    bottling_plant()
