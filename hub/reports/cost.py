"""Cost per physics tick of the bottle levels of detail, on a running belt and off every belt, measured in one run."""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from hub.core.registry import default_registry
from hub.physics import PhysicsWorld
from hub.physics.frames import Pose, Straight

MODELS = (("simple", "centre"), ("base_point", "base"), ("base_body", "base_body"))
SHAPES = ("cylinder", "hull")


@dataclass(frozen=True)
class Cost:
    model: str
    shape: str
    on_belt: bool
    microseconds: float           # per physics tick, the whole world (engine, field, state reads)


def _profile(radius: float, height: float):
    # The bottle module's own shape, found by name: the kernel imports no module type.
    return default_registry().get("bottle").default_hull(radius, height)


def world_cost(model: str, shape: str, bottles: int, on_belt: bool, ticks: int, rate: int = 150) -> float:
    """Seconds for `ticks` ticks of a world with `bottles` bottles in a row on a 0.5 m/s belt
    (or on the same floor with no belt)."""
    grip_at = dict(MODELS)[model]
    spacing, radius, height = 0.08, 0.03, 0.1
    length = bottles * spacing + 0.5 * ticks / rate + 1.0
    hull = _profile(radius, height) if shape == "hull" else None
    with PhysicsWorld(rate) as world:
        world.add_support(0.0, (0.0, -0.06, length, 0.06))
        if on_belt:
            line = Straight(Pose(0.0, 0.0, 0.0, 0.0), length)
            # k = 4: the belt takes the bottles up gently enough that none rocks over (a0 = 2 m/s²).
            world.add_belt_field(line, 0.05, -0.02, 0.3, 4.0, 0.5)
        for i in range(bottles):
            world.add_bottle((0.04 + i * spacing, 0.0, 0.0), radius, height, 0.05, f"b{i}", hull=hull, grip_at=grip_at)
        world.start()
        world.step(rate // 5)   # settle, and let the belt take the bottles up
        started = time.perf_counter()
        world.step(ticks)
        elapsed = time.perf_counter() - started
        tilted = max(world.tilt(n) for n in range(bottles))
        if tilted > 0.1:   # a lying bottle costs differently: the measurement would mean nothing
            raise RuntimeError(f"{model}/{shape}: a bottle tilted {tilted:.2f} rad during the cost run")
        return elapsed


def lod_costs(bottles: int = 20, ticks: int = 300, repeats: int = 3) -> list[Cost]:
    """Median cost per tick of every model × shape, on a belt and off it."""
    out = []
    for on_belt in (True, False):
        for shape in SHAPES:
            for model, _ in MODELS:
                samples = [world_cost(model, shape, bottles, on_belt, ticks) for _ in range(repeats)]
                out.append(Cost(model, shape, on_belt, 1e6 * statistics.median(samples) / ticks))
    return out
