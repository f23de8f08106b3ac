"""`make bench`, queues: how far a queue pressed against a stopper gives, how it tilts, what it costs."""
from __future__ import annotations

import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from hub.core.errors import SimulationError
from hub.physics import PhysicsWorld
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT
from .plant_watch import run_watched
from .test_belt_bottle_sensor import analytical_enter_time

RATE = 150
SECONDS = 6          # the queue has formed after ~3 s; the last second is judged, the last two timed
REPEATS = 5
FACE = 0.9975        # the stopper's upstream face, m (a 5 mm gate at x = 1.0)
PITCH = 0.0605       # bottles start 0.5 mm apart


def queue_scene(bottles: int, friction: float | None) -> Path:
    """`bottles` bottles on a running belt (0.5 m/s, k = 16/s, 7 cm lane) against a closed stopper."""
    length = max(1.2, FACE + 0.03)
    start = FACE - 0.0301 - PITCH * (bottles - 1)
    offset = max(0.0, 0.04 - start)          # a long queue: move everything downstream
    items = "\n".join(f"  q{n}: {{module: bottle, position: [{offset + FACE - 0.0301 - PITCH * n:.4f}, 0, 0]}}"
                      for n in range(bottles))
    mu = f", friction: {friction}" if friction else ""
    path = Path(tempfile.mkdtemp()) / f"queue{bottles}.yaml"
    path.write_text(f"planthub: 1\nrun: {{duration: {SECONDS}, physics_rate: {RATE}}}\nobjects:\n"
                    f"  belt: {{module: conveyor, position: [0, 0, 0], length: {length + offset:.4f}, speed: 0.5, "
                    f"width: 0.07{mu}}}\n"
                    f"  stop: {{module: stopper, position: [{1.0 + offset:.4f}, 0, 0], width: 0.07}}\n" + items + "\n")
    return path


def judge(path: Path, bottles: int) -> dict:
    """Over the last second: the first bottle's depth into the stopper, the mean overlap of
    neighbours, the deepest sinking into the floor; over the run: the largest tilt."""
    scenario = load_scenario(path)
    face = FACE + float(dict((o.name, o.params) for o in scenario.objects)["stop"]["position"][0]) - 1.0
    last = scenario.run.end_tick - RATE
    seen = {"depth": [], "overlap": [], "sink": [], "tilt": 0.0}

    class Watch:   # an observer: it also sees the first point (tick 0), which the old progress callback did not
        def observe(self, tick, signals, events):
            seen["tilt"] = max(seen["tilt"], max(math.degrees(w.tilt(n)) for n in range(bottles)))
            if tick > last:
                p = w.positions[:bottles]
                seen["depth"].append(p[0, 0] + 0.03 - face)
                gaps = np.hypot(*(p[1:, :2] - p[:-1, :2]).T)
                seen["overlap"].append(float(np.maximum(0.06 - gaps, 0.0).mean()) if bottles > 1 else 0.0)
                seen["sink"].append(float(-(p[:, 2] - w.half_heights[:bottles]).min()))

        def close(self, reason):
            pass

    with Run(scenario, observers=[Watch()]) as run:
        w = run.plant.world
        try:
            run.run()
        except SimulationError:   # the physics watch: a bottle fell through the floor, the queue fell apart
            return {"depth": math.inf, "overlap": math.inf, "sink": math.inf, "tilt": max(seen["tilt"], 90.0)}
    return {"depth": 1000 * max(seen["depth"]), "overlap": 1000 * max(seen["overlap"]),
            "sink": 1000 * max(seen["sink"]), "tilt": seen["tilt"]}


def cost(path: Path) -> tuple[float, float]:
    """Median µs per tick of the formed queue: the hub's step loop, and bare pybullet stepping of
    the same bodies from the same state (the floor; without the belt's push the queue relaxes,
    so the floor's solver stops earlier). CPU time of this process: on a shared machine the
    wall clock also counts other work."""
    scenario = load_scenario(path)
    formed, ticks = scenario.run.end_tick - 2 * RATE, 2 * RATE
    hub, bare = [], []
    for _ in range(REPEATS):
        for sample, engine_only in ((hub, False), (bare, True)):
            with Run(scenario) as run:
                run.run(until_tick=formed)
                start = time.process_time()
                if engine_only:   # the floor: pybullet alone steps the run's bodies on from where it stands
                    run.plant.world.step_engine_only(ticks)
                else:
                    run.run(until_tick=formed + ticks)
                sample.append((time.process_time() - start) / ticks * 1e6)
    return statistics.median(hub), statistics.median(bare)


def settings(ring: float | None = None, iterations: int | None = None):
    """Set the world's contact ring and solver iterations for the worlds built next; returns the old ones."""
    old = PhysicsWorld.RING, PhysicsWorld.SOLVER_ITERATIONS
    PhysicsWorld.RING = old[0] if ring is None else ring
    PhysicsWorld.SOLVER_ITERATIONS = old[1] if iterations is None else iterations
    return old


def contact_models() -> None:
    print(f"\n## A queue pressed against a closed stopper ({RATE} Hz, belt 0.5 m/s, k = 16/s, 7 cm lane)\n")
    print(f"Last second of {SECONDS} s: depth of the first bottle into the gate, mean overlap of neighbours, deepest")
    print("sinking into the floor; largest tilt over the run. `cylinder`: the plain cylinder; `ring`: the")
    print("bottle's contact ring at its centre of mass (hub/physics/world.py).\n")
    print("| contact | belt friction μ | bottles | depth mm | overlap mm | sink mm | tilt ° |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    saved = settings()
    try:
        for label, ring in (("cylinder", 0.0), ("ring", saved[0])):
            settings(ring=ring)
            for friction in (None, 0.2):
                for bottles in (1, 6, 12, 40):
                    r = judge(queue_scene(bottles, friction), bottles)
                    if r["sink"] > 50 or r["tilt"] > 45:
                        print(f"| {label} | {friction or '—'} | {bottles} | falls apart | | | {r['tilt']:.0f} |")
                        continue
                    print(f"| {label} | {friction or '—'} | {bottles} | {r['depth']:.2f} | {r['overlap']:.2f} "
                          f"| {r['sink']:.2f} | {r['tilt']:.1f} |")
    finally:
        settings(*saved)


def separator_passes() -> bool:
    """scenarios/separator.yaml: one bottle per cycle, in order, none tipped or through a gate."""
    import csv

    with tempfile.TemporaryDirectory() as tmp:
        _, _, watch = run_watched(ROOT / "scenarios" / "separator.yaml", Path(tmp))
        with open(Path(tmp) / "events.csv") as f:
            passed = [e["detail"] for e in csv.DictReader(f) if e["slot"] == "out.trigger.on_enter"]
    try:
        watch.assert_sound()
    except AssertionError:
        return False
    return passed == [f"b{n}" for n in range(1, len(passed) + 1)] and len(passed) == 8


def solver_iterations() -> None:
    from .bench import BELT, hub_run

    print(f"\n## Solver iterations: accuracy against cost ({RATE} Hz, ring contact, belt friction μ = 0.2)\n")
    print("Enter-time error of a free bottle (belt_bottle_sensor); mean overlap of neighbours and largest tilt")
    print("in queues of 12 and 40; the separator scenario (8 bottles) sound and one bottle per cycle; µs per")
    print("tick (CPU) of the formed 40-bottle queue, hub beside bare pybullet stepping of the same bodies.\n")
    print("| iterations | enter-time error | 12: overlap mm | 12: tilt ° | 40: overlap mm | 40: tilt ° "
          "| separator | 40: hub µs/tick | 40: bare µs/tick |")
    print("|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    saved = settings()
    try:
        for iterations in (5, 10, 20, 30, 50):
            settings(iterations=iterations)
            scenario = load_scenario(BELT, {"run.physics_rate": RATE})
            expected = analytical_enter_time(scenario)
            measured = hub_run(scenario, None)().stats["barrier.trigger.on_enter"].first_tick / RATE
            q12 = judge(queue_scene(12, 0.2), 12)
            path = queue_scene(40, 0.2)
            q40 = judge(path, 40)
            hub, bare = cost(path)
            print(f"| {iterations} | {100 * (measured - expected) / expected:+.3f} % | {q12['overlap']:.2f} "
                  f"| {q12['tilt']:.1f} | {q40['overlap']:.2f} | {q40['tilt']:.1f} "
                  f"| {'passes' if separator_passes() else 'fails'} | {hub:.0f} | {bare:.0f} |")
    finally:
        settings(*saved)


def queues() -> None:
    contact_models()
    solver_iterations()


if __name__ == "__main__":
    queues()
