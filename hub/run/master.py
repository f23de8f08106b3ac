"""The master: steps the plant in communication steps on an integer tick clock."""
from __future__ import annotations

import time
from dataclasses import dataclass

from hub.core.component import Component
from hub.core.observer import Observer, Stop, StopCondition
from hub.core.slots import Direction
from hub.run.events import EventRows
from hub.run.plant import Plant


@dataclass(frozen=True)
class RunResult:
    ticks: int
    rate: int
    wall_seconds: float
    stopped_by: str = ""    # why the run ended before the scenario's end (an operator's stop, its orders)
    ended: bool = False     # that was a normal end (its orders out), not a stop

    @property
    def sim_seconds(self) -> float:
        return self.ticks / self.rate

    @property
    def realtime_factor(self) -> float:
        return self.sim_seconds / self.wall_seconds if self.wall_seconds > 0 else float("inf")


class Master:
    """Runs the step loop. This docstring is where the loop is written down; hub/run/README.md's
    "The step loop" quotes it word for word (tests/test_layers.py checks), and every other file refers to it.

    Time is an integer count of physics ticks (`1/physics_rate` s); seconds are derived only for
    output. One communication step holds `communication_step × physics_rate` ticks. At each
    communication point, in this order:

    1. **sense** — every component writes its sources from the world: volume triggers report
       what happened at every tick since the last point (latched, so a bottle that enters and
       leaves between two points gives both events), bodies their pose and velocity, logic the
       outputs of its last step; then operator commands set sources;
    2. **flows** — flows and zero-delay components are evaluated in the order fixed at load
       time; then operator commands set targets;
    3. **actuate** — every component applies its targets to the world (belt speed, run/stop);
    4. **observe** — every observer sees the point's final values and its events in tick order:
       the recorder writes the row and the event log, the bus publishes what subscribers watch,
       the plant's figures take their look; then every stop condition may end the run here.

    Then, to reach the next point, the physics runs the step's ticks (force fields applied and
    triggers evaluated at every tick), and the logic steps over the same interval from t with
    the inputs it got at this point: with `run.master: jacobi` (the default) every logic
    component alike, its outputs sensed at the next point; with `gauss-seidel` in the order of
    the flows between them, a flow from one's output to another's input handing the fresh value
    over between their two steps (a ring is cut at its first declared member). Without events
    the logic steps before the physics, which gives the same results and lets participants on
    the bus compute meanwhile. A source reports the world as sensed in step 1, so an actuator's
    own state source (`belt.drive.running`) shows a command from the next point on.

    With `run.event_driven: true`, a trigger event (an object entering or leaving a volume) ends
    the communication step at the tick after it happened, and the following step lasts one
    tick: the logic sees the event at once and its answer reaches the plant one physics tick
    later, whatever the communication step. The regular grid of points is kept; event points
    come in between.

    The master knows no plant element, transport or file: what records, publishes, tallies or
    judges a run is an Observer, what ends it early a StopCondition, what sets slots from outside
    (operator commands, a replay) a manipulator (hub/core/observer.py); the run assembly
    (hub/run/assembly.py) plugs them in. A pacer holds each point until its wall-clock time, and
    an operator's hold (pause, single steps) keeps the run at a point until it is resumed.
    """

    def __init__(self, plant: Plant, *, observers: list[Observer] = (), stops: list[StopCondition] = (),
                 manipulators=(), pacer=None, hold=None):
        self.observers = list(observers)
        self.stops = list(stops)
        self.manipulators = list(manipulators)   # take(tick) -> events, apply(signals, direction)
        self.pacer = pacer
        self.hold = hold   # hub/run/hold.py: an operator's pause, resume and single steps
        self._closed = False
        self.stopped: Stop | None = None   # set, the run is over (an operator's stop, its orders out)
        self._bind(plant)
        self.communicated = False
        self._answering = False   # the last step ended early on an event
        self.then = None          # called once this point is complete: a rewind asked at it (hub/run/rewind.py)

    def _bind(self, plant: Plant) -> None:
        self.plant = plant
        self.world = plant.world
        comps = plant.components
        # Only components that do something in a hook are called: a scene of 100 bottles should
        # not pay 200 empty calls per communication step.
        self._sensing = [c for c in comps if type(c).sense is not Component.sense
                         and not (c.QUIET_UNLESS_NEEDED and not c.needed)]
        self._actuating = [c for c in comps if type(c).actuate is not Component.actuate]
        self._events = EventRows(comps)

    def rebind(self, plant: Plant, replaced: dict[int, object]) -> None:
        """Step `plant`, built again by a rewind (hub/run/rewind.py), from now on: each observer,
        stop condition and manipulator made for the old plant gives way to the one made for the new
        (`replaced`: id of the old → the new, or None where there is none now)."""
        self._bind(plant)
        for parts in (self.observers, self.stops, self.manipulators):
            parts[:] = [p for p in (replaced.get(id(p), p) for p in parts) if p is not None]

    @property
    def tick(self) -> int:
        return self.world.tick

    def communicate(self) -> None:
        """One communication point at the current tick (steps 1–4 of the loop)."""
        signals, tick = self.plant.signals, self.world.tick
        signals.begin_step()
        for comp in self._sensing:
            comp.sense(tick)
        events = []
        for manipulator in self.manipulators:
            events.extend(manipulator.take(tick))
            manipulator.apply(signals, Direction.SOURCE)
        for evaluate in self.plant.plan:
            evaluate()
        for manipulator in self.manipulators:
            manipulator.apply(signals, Direction.TARGET)
        events = self._events.gather(tick, signals, events)
        for comp in self._actuating:
            comp.actuate()
        for observer in self.observers:
            observer.observe(tick, signals, events)
        self.communicated = True
        if self.then is not None:
            then, self.then = self.then, None
            then()

    def advance(self, until_tick: int | None = None) -> None:
        """Steps 5 and 6 of the loop: one communication step's physics and logic.

        Logic steps from t with the inputs it got at t, so running it after the physics changes
        nothing in its results, and lets an event-driven step end early: the physics stops at
        the tick after a trigger event, the logic steps over exactly that interval, and the
        next step lasts one tick, so the logic's answer reaches the plant a tick later instead
        of a whole communication step later.
        """
        run = self.plant.scenario.run
        start = self.world.tick
        # After an early stop the logic gets one tick to answer the event, then the steps end
        # on the regular grid again.
        end = start + 1 if self._answering else (start // run.substeps + 1) * run.substeps
        if until_tick is not None:
            end = min(end, until_tick)
        algorithm = self.plant.algorithm
        if not run.event_driven:
            algorithm.step(start, end - start)
            self.world.step(end - start, stop_on_event=False)
            return
        ticks = self.world.step(end - start, stop_on_event=True)
        self._answering = start + ticks < end
        algorithm.step(start, ticks)

    def stop_now(self) -> Stop | None:
        """The first stop condition that ends the run at this point, if any."""
        tick = self.world.tick
        for condition in self.stops:
            stop = condition.stop(tick)
            if stop is not None:
                return stop
        return None

    def run(self, until_tick: int | None = None) -> RunResult:
        """Communicate at every point from now to `until_tick` (default: the scenario's end)."""
        scenario_end = self.plant.scenario.run.end_tick
        end = scenario_end if until_tick is None else until_tick
        start_tick, started = self.world.tick, time.perf_counter()
        try:
            if not self.communicated:
                self.communicate()
            pacer = self.pacer
            if pacer is not None:
                pacer.start(self.world.tick)
            stop = self.stopped or self.stop_now()
            while stop is None and self.world.tick < end:
                self.advance(end)
                self.communicate()
                if pacer is not None:
                    pacer.wait(self.world.tick)
                stop = self.stop_now()
                if stop is None and self.hold is not None and self.hold.holding():
                    self.hold.wait(self.world.tick, self.stop_now)
                    stop = self.stop_now()
        except BaseException:
            self.close("the run failed")
            raise
        self.stopped = stop
        wall = time.perf_counter() - started   # the stepping: what the observers' closing takes is not in it
        if stop is not None or self.world.tick >= scenario_end:
            self.close(stop.reason if stop is not None else "the run reached its end")
        return RunResult(self.world.tick - start_tick, self.world.rate, wall,
                         stop.reason if stop is not None else "", stop is not None and stop.ended)

    def close(self, reason: str = "closed") -> None:
        """Tell every observer the run is over (once), in reverse order of plugging in."""
        if self._closed:
            return
        self._closed = True
        errors = []
        for observer in reversed(self.observers):
            try:
                observer.close(reason)
            except BaseException as exc:   # every observer gets closed; the first failure is raised
                errors.append(exc)
        if errors:
            raise errors[0]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
