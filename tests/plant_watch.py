"""Run a scenario while watching every bottle at every communication point: tilt, falls, speed, gates passed while closed."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hub.run.assembly import Run
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario
from modules.gate import TwoPositions
from modules.robot_arm import Gripper

FALLEN = 0.02   # m: a bottle whose centre is this far below standing on the z = 0 surface has fallen
OFF_STAGE = -50.0   # m: parked bodies wait far below (hub/physics/world.py PARKED)


@dataclass
class Watch:
    """What the worst bottle did over a run; `crossings` lists (time, gate, bottle) of closed gates passed."""

    plant: Plant
    max_tilt: float = 0.0          # degrees, over bottles in play
    max_speed: float = 0.0         # m/s, horizontal
    lowest: float = math.inf       # m, centre height minus half height
    crossings: list = field(default_factory=list)
    _sides: dict = field(default_factory=dict)

    def __post_init__(self):
        self.gates = [(f"{c.obj}.{c.name}", c.blocker) for c in self.plant.components
                      if isinstance(c, TwoPositions) and len(c.blocker.boxes) == 1]
        self.grippers = [c for c in self.plant.components if isinstance(c, Gripper)]

    def close(self, reason: str) -> None:
        """The figures stay readable."""

    def observe(self, tick: int, signals=None, events=()) -> None:
        world = self.plant.world
        # A body put into play at this point is read from the next tick on: skip it until then.
        # A held body moves with the arm, out of the dynamics: it is not judged.
        held = {g.body for g in self.grippers}
        live = [n for n in range(len(world.labels))
                if not world.is_parked(n) and world.positions[n, 2] > OFF_STAGE and n not in held]
        if not live:
            return
        p, v = world.positions[live], world.velocities[live]
        self.max_tilt = max(self.max_tilt, max(math.degrees(world.tilt(n)) for n in live))
        self.max_speed = max(self.max_speed, float(np.hypot(v[:, 0], v[:, 1]).max()))
        self.lowest = min(self.lowest, float((p[:, 2] - world.half_heights[live]).min()))
        for name, blocker in self.gates:
            local = blocker.boxes.local(p)[0]
            e = blocker.boxes.half_extents[0]
            for n, (x, y, _) in zip(live, local.tolist()):
                side = x > 0
                key = (name, n)
                across = abs(y) < e[1] + world.radii[n]
                if key in self._sides and across and blocker.closed and self._sides[key][1] and side != self._sides[key][0]:
                    self.crossings.append((tick / world.rate, name, world.labels[n]))
                self._sides[key] = (side, blocker.closed)

    def assert_sound(self, belt_speed: float = 0.5) -> None:
        """No bottle tipped over (> 10°), fell off, ran faster than 2× the belt or passed a closed gate."""
        assert self.max_tilt <= 10.0, f"a bottle tipped by {self.max_tilt:.1f}°"
        assert self.lowest > -FALLEN, f"a bottle fell: its base reached {self.lowest:.3f} m"
        assert self.max_speed <= 2 * belt_speed, f"a bottle ran at {self.max_speed:.2f} m/s"
        assert not self.crossings, f"bottles passed closed gates: {self.crossings}"


def run_watched(path, out: Path | None = None, overrides: dict | None = None):
    """Load, build and run a scenario under a Watch; return (scenario, recorder, watch). The
    world asks the engine about every resting bottle and every one in free transport at every
    tick (PhysicsWorld.check_rest, check_free)."""
    scenario = load_scenario(path, overrides)
    with Run(scenario, out=out) as run:
        run.plant.world.check_rest = run.plant.world.check_free = True
        watch = Watch(run.plant)
        run.master.observers.append(watch)
        run.run()
    return scenario, run.recorder, watch
