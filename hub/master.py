"""The master: steps the plant in communication steps on an integer tick clock."""
from __future__ import annotations

import time
from dataclasses import dataclass

from .component import Component
from .plant import Plant
from .recorder import Recorder
from .slots import Direction, SlotType


@dataclass(frozen=True)
class RunResult:
    ticks: int
    rate: int
    wall_seconds: float

    @property
    def sim_seconds(self) -> float:
        return self.ticks / self.rate

    @property
    def realtime_factor(self) -> float:
        return self.sim_seconds / self.wall_seconds if self.wall_seconds > 0 else float("inf")


class Master:
    """Runs the step loop of DESIGN.md. At every communication point, in this order:

    1. every component senses: physics-side sources are written (triggers latched since the
       last point, poses, velocities; logic outputs from the last logic step);
    2. flows and connectors are evaluated in the order fixed at load time;
    3. every component actuates: targets are applied to the world;
    4. the row for this point is recorded and the events of the step logged;
    then, to reach the next point, 5. logic components (FMUs) step from t to t + h with the
    inputs flows gave them at t (Jacobi: their outputs appear at the next point), and 6. the
    world runs the communication step's physics substeps.
    Time is the physics tick count; seconds are only derived for output.
    """

    def __init__(self, plant: Plant, recorder: Recorder | None = None):
        self.plant = plant
        self.world = plant.world
        self.recorder = recorder or Recorder([], plant.scenario.run.physics_rate)
        comps = plant.components
        # Only components that do something in a hook are called: a scene of 100 bottles should
        # not pay 200 empty calls per communication step.
        self._sensing = [c for c in comps if type(c).sense is not Component.sense]
        self._actuating = [c for c in comps if type(c).actuate is not Component.actuate]
        self._stepping = [c for c in comps if type(c).step is not Component.step]
        self._emitters = [c for c in comps if _may_emit(c)]
        self._communicated = False

    @property
    def tick(self) -> int:
        return self.world.tick

    def communicate(self) -> None:
        """One communication point at the current tick (steps 1–5 above)."""
        signals, tick = self.plant.signals, self.world.tick
        signals.begin_step()
        for comp in self._sensing:
            comp.sense(tick)
        for evaluate in self.plant.plan:
            evaluate()
        events = []
        for comp in self._emitters:
            prefix = f"{comp.obj}.{comp.name}."
            events.extend((t, prefix + slot, detail) for t, slot, detail in comp.events(tick))
        events.sort(key=lambda e: e[0])   # stable: same-tick events keep component order
        for t, slot, detail in events:
            self.recorder.event(t, slot, detail)
        for comp in self._actuating:
            comp.actuate()
        self.recorder.sample(tick, signals)
        self._communicated = True

    def advance(self) -> None:
        """Step the logic components over one communication step, then run its physics substeps."""
        run = self.plant.scenario.run
        t, h = self.world.tick / run.physics_rate, run.substeps / run.physics_rate
        for comp in self._stepping:
            comp.step(t, h)
        self.world.step(run.substeps)

    def run(self, until_tick: int | None = None, progress=None) -> RunResult:
        """Communicate at every point from now to `until_tick` (default: the scenario's end)."""
        end = self.plant.scenario.run.end_tick if until_tick is None else until_tick
        start_tick, started = self.world.tick, time.perf_counter()
        if not self._communicated:
            self.communicate()
        while self.world.tick < end:
            self.advance()
            self.communicate()
            if progress is not None:
                progress(self.world.tick, end)
        return RunResult(self.world.tick - start_tick, self.world.rate, time.perf_counter() - started)


def _may_emit(comp: Component) -> bool:
    overrides = type(comp).events is not Component.events
    has_void = any(s.type is SlotType.VOID and s.direction is Direction.SOURCE for s in comp.SLOTS)
    return overrides or has_void
