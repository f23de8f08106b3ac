"""`make bench`, plant elements: what a parked bottle, an idle or moving arm, a gate switch and the physics watch cost per tick; queues (tests/bench_queue.py)."""
from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from hub.physics import PhysicsWorld
from hub.physics.robot import JointMotion
from hub.run.assembly import Run
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario

REPEATS = 5
TICKS = 1500


def median_us_per_tick(make, run) -> float:
    """Median over REPEATS of the time `run(thing)` takes per tick, `make()` built outside the timing."""
    samples = []
    for _ in range(REPEATS):
        thing = make()
        try:
            start = time.perf_counter()
            run(thing)
            samples.append((time.perf_counter() - start) / TICKS * 1e6)
        finally:
            thing.close()
    return statistics.median(samples)


def store_scene(parked: int) -> Path:
    """Five bottles on a belt, and a store holding `parked` more that it never releases."""
    bottles = "\n".join(f"  b{i}: {{module: bottle, position: [{0.04 + 0.1 * i:.2f}, 0, 0]}}" for i in range(5))
    store = f"  store: {{module: source, position: [0.04, 0.5, 0], count: {parked}}}\n" if parked else ""
    path = Path(tempfile.mkdtemp()) / f"store{parked}.yaml"
    path.write_text("planthub: 1\nrun: {duration: 10, physics_rate: 150}\nobjects:\n"
                    "  belt: {module: conveyor, position: [0, 0, 0], length: 8.0, speed: 0.5}\n"
                    + bottles + "\n" + store)
    return path


def parked_bottles() -> None:
    print("\n## Parked bottles: a store's bottles waiting off stage (150 Hz, 5 bottles on a belt)\n")
    print("| bottles in store | hub µs/tick | engine only µs/tick | hub: extra µs/tick per stored bottle |")
    print("|---:|---:|---:|---:|")
    base = None
    for parked in (0, 100, 1000):
        scenario = load_scenario(store_scene(parked))

        def hub(run):
            run.run(until_tick=TICKS)

        def engine(plant):
            plant.world.step_engine_only(TICKS)

        # A store is a source: Run adds the plant tally it contributes (as `planthub run` does), timed with the hub.
        us = median_us_per_tick(lambda: Run(scenario), hub)
        floor = median_us_per_tick(lambda: Plant(scenario), engine)   # the floor: a bare plant, not a run
        base = us if base is None else base
        extra = f"{(us - base) / parked:.3f}" if parked else "—"
        print(f"| {parked} | {us:.0f} | {floor:.0f} | {extra} |")


def arm_world(arm: bool):
    world = PhysicsWorld(150)
    world.add_static_box((0.5, 0, -0.01), (1.0, 0.3, 0.01))
    world.add_cylinder((0.3, 0, 0), 0.03, 0.1, 0.05, "b")
    if arm:
        world.add_arm((0, 0.5, 0), 0.0, 0.1)
    world.start()
    return world


def robot_arm() -> None:
    print("\n## Robot arm (kinematic KUKA iiwa, 150 Hz, one bottle in the world)\n")
    print("| world | µs/tick |")
    print("|---|---:|")

    def moving():
        world = arm_world(True)
        arm = world.arms[0]
        arm.play(JointMotion(arm.q, arm.q + 0.5, world.tick, TICKS, world.rate))
        return world

    for label, make in (("no arm", lambda: arm_world(False)), ("arm idle", lambda: arm_world(True)),
                        ("arm moving (joints set and tool read every tick)", moving)):
        print(f"| {label} | {median_us_per_tick(make, lambda w: w.step(TICKS)):.1f} |")


def gate_switch() -> None:
    world = PhysicsWorld(150)
    part = world.add_switchable_boxes([(0, 0, 0.04)], [(0.01, 0.05, 0.04)], [0.0], solid=False)
    calls = 20000
    start = time.perf_counter()
    for i in range(calls):
        world.set_solid(part, i % 2 == 0)
    us = (time.perf_counter() - start) / calls * 1e6
    world.close()
    print(f"\nSwitching a gate's collision (filter group and mask, one call whatever the number of bottles): "
          f"{us:.2f} µs per switch.")


def watch_cost() -> None:
    """The physics watch (hub/physics/watch.py): its test alone on the arrays a tick reads, and a
    whole run with and without it, side by side (medians; the run's difference is within noise)."""
    print("\n## Physics watch: speed, non-finite and world-box test per tick (150 Hz)\n")
    print("| bottles read per tick | watch.check µs/tick | one bare numpy max of the block, µs | "
          "hub µs/tick watched | hub µs/tick unwatched |")
    print("|---:|---:|---:|---:|---:|")
    calls = 20000
    for count in (5, 40, 100):
        bottles = "\n".join(f"  b{i}: {{module: bottle, position: [{0.04 + 0.07 * i:.2f}, 0, 0]}}"
                            for i in range(count))
        path = Path(tempfile.mkdtemp()) / f"watch{count}.yaml"
        path.write_text("planthub: 1\nrun: {duration: 10, physics_rate: 150, sleep_after: 0}\nobjects:\n"
                        f"  belt: {{module: conveyor, position: [0, 0, 0], length: {0.1 + 0.07 * count:.2f}, "
                        "speed: 0.0}\n" + bottles + "\n")
        scenario = load_scenario(path)

        def plant(watched: bool):
            made = Plant(scenario)
            made.world.watch.enabled = watched
            return made

        def steps(made):
            made.world.step(TICKS)

        with Plant(scenario) as made:
            b, watch = made.world.bodies, made.world.watch
            start = time.perf_counter()
            for _ in range(calls):
                watch.check(b.fresh, b.fresh_rows)
            check = (time.perf_counter() - start) / calls * 1e6
            block = b.fresh   # the scale of one numpy call on this machine now (it is noisy: read ratios)
            start = time.perf_counter()
            for _ in range(calls):
                block.max()
            bare = (time.perf_counter() - start) / calls * 1e6
        on = median_us_per_tick(lambda: plant(True), steps)
        off = median_us_per_tick(lambda: plant(False), steps)
        print(f"| {count} | {check:.2f} | {bare:.2f} | {on:.0f} | {off:.0f} |")


def plant_elements() -> None:
    from .bench_queue import queues

    parked_bottles()
    robot_arm()
    gate_switch()
    watch_cost()
    queues()


if __name__ == "__main__":
    import sys

    watch_cost() if sys.argv[1:] == ["watch"] else plant_elements()
