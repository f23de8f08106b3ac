"""The master: steps the plant in communication steps on an integer tick clock."""
from __future__ import annotations

import time
from dataclasses import dataclass

from hub.bus.session import Bus, local_endpoint
from hub.bus.commands import Commands
from hub.core.component import Component
from hub.bus.dataplane import DataPlane
from hub.bus.lockstep import Lockstep
from modules.plant.orders import Orders
from hub.run.plant import Plant
from hub.run.recorder import Recorder
from hub.bus.settings import BusSettings
from hub.core.slots import Direction, SlotType
from hub.bus.wire import check_run_name


@dataclass(frozen=True)
class RunResult:
    ticks: int
    rate: int
    wall_seconds: float
    stopped_by: str = ""    # why the run ended before the scenario's end (an operator's stop, its orders)

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
    then, to reach the next point, 5. the world runs the communication step's physics
    substeps (with `event_driven`, it stops at the tick after a trigger event), and 6. logic
    components (FMUs) step over the same interval from t with the inputs flows gave them at t
    (Jacobi: their outputs appear at the next point; without `event_driven` they are stepped
    before the physics, which gives the same results and lets participants compute meanwhile).
    Time is the physics tick count; seconds are only derived for output.

    With a bus (given, or opened from `run.bus` when logic is served by participants): before
    the first point the participants are launched and awaited (`hub.lockstep`); operator
    commands are applied at a point, sources after 1 and targets after 2 (`hub.commands`); and
    after 4 the slots subscribers watch are published (`hub.dataplane`). A `pacer` holds each
    point until its wall-clock time. A Master that ran to the scenario's end, was stopped or
    failed has closed its bus side; one stopped earlier with `until_tick` is closed by `close`.
    """

    def __init__(self, plant: Plant, recorder: Recorder | None = None, *, bus=None, commands=None,
                 pacer=None, log=None):
        self.plant = plant
        self.world = plant.world
        self.recorder = recorder or Recorder([], plant.scenario.run.physics_rate)
        self.bus = bus
        self.commands = commands          # hub.commands.Commands (a replay), or None: live from the bus
        self.pacer = pacer
        self.log = log or (lambda text: None)
        self.lockstep = self.dataplane = None
        self._remote = [s for c in plant.components if getattr(s := getattr(c, "slave", None), "on_bus", False)]
        self._own_bus = False
        self._started = self._closed = False
        self.stopped_by = ""    # set, the run is over (an operator's stop, or its orders delivered)
        self.orders = Orders.for_plant(plant)
        comps = plant.components
        # Only components that do something in a hook are called: a scene of 100 bottles should
        # not pay 200 empty calls per communication step.
        self._sensing = [c for c in comps if type(c).sense is not Component.sense]
        self._actuating = [c for c in comps if type(c).actuate is not Component.actuate]
        self._emitters = [c for c in comps if _may_emit(c)]
        self._communicated = False
        self._answering = False   # the last step ended early on an event

    @property
    def tick(self) -> int:
        return self.world.tick

    def communicate(self) -> None:
        """One communication point at the current tick (steps 1–5 above)."""
        signals, tick = self.plant.signals, self.world.tick
        signals.begin_step()
        for comp in self._sensing:
            comp.sense(tick)
        commands = self.commands
        events = []
        if commands is not None:
            events = commands.take(tick)
            commands.apply(signals, Direction.SOURCE)
        for evaluate in self.plant.plan:
            evaluate()
        if commands is not None:
            commands.apply(signals, Direction.TARGET)
        for comp in self._emitters:
            prefix = f"{comp.obj}.{comp.name}."
            events.extend((t, prefix + slot, detail) for t, slot, detail in comp.events(tick))
        events.sort(key=lambda e: e[0])   # stable: same-tick events keep component order
        for t, slot, detail in events:
            self.recorder.event(t, slot, detail)
        for comp in self._actuating:
            comp.actuate()
        self.recorder.sample(tick, signals)
        if self.dataplane is not None:
            self.dataplane.publish(tick, signals)
        if self.lockstep is not None:
            self.lockstep.poll()
        self._communicated = True

    def advance(self, until_tick: int | None = None) -> None:
        """Run one communication step's physics, then step the logic over the same interval.

        Logic steps from t with the inputs it got at t, so running it after the physics changes
        nothing in its results, and lets an event-driven step end early: the physics stops at
        the tick after a trigger event, the logic steps over exactly that interval, and the
        next step lasts one tick, so the logic's answer reaches the plant a tick later instead
        of a whole communication step later. Without events the interval is known beforehand,
        and the logic is stepped first: participants on the bus then compute while the physics
        runs (same results, as they only answer at the next point).
        """
        run = self.plant.scenario.run
        start = self.world.tick
        # After an early stop the logic gets one tick to answer the event, then the steps end
        # on the regular grid again.
        end = start + 1 if self._answering else (start // run.substeps + 1) * run.substeps
        if until_tick is not None:
            end = min(end, until_tick)
        if not run.event_driven:
            self.plant.step_logic(start, end - start)   # Jacobi or Gauss-Seidel (run.master)
            self.world.step(end - start, stop_on_event=False)
            return
        ticks = self.world.step(end - start, stop_on_event=True)
        self._answering = start + ticks < end
        self.plant.step_logic(start, ticks)

    def start(self) -> None:
        """Join the bus, launch and await the participants (once, before the first point)."""
        if self._started:
            return
        self._started = True
        scenario = self.plant.scenario
        if self.bus is None and self._remote:
            self.bus, self._own_bus = Bus(scenario.run.bus or BusSettings()), True
        if self.bus is None:
            return
        settings = self.bus.settings
        run = check_run_name(scenario.name)
        where = ", ".join(local_endpoint(e) for e in self.bus.endpoints) or ", ".join(settings.connect)
        self.log(f"run {run!r} on the bus ({settings.mode}, {where}): plant/{run}/**")
        # Everything that listens is declared before the hub's liveliness token, which tells others
        # the hub is there: a put made before a subscription is known goes nowhere.
        self.dataplane = DataPlane(self.bus, run, self.plant, settings)
        if self.commands is None:
            self.commands = Commands(self.plant, self.recorder)
            self.commands.listen(self.bus, run)
        self.lockstep = Lockstep(self.bus, run, self._remote, lease=settings.lease, on_loss=settings.on_loss,
                                 rate=self.world.rate, log=self._notice, warn=self.log)
        self.lockstep.start(self.world.tick)

    def _notice(self, text: str) -> None:
        self.recorder.notice(self.world.tick, text)
        self.log(text)

    def run(self, until_tick: int | None = None, progress=None) -> RunResult:
        """Communicate at every point from now to `until_tick` (default: the scenario's end)."""
        end = self.plant.scenario.run.end_tick if until_tick is None else until_tick
        start_tick, started = self.world.tick, time.perf_counter()
        try:
            self.start()
            if not self._communicated:
                self.communicate()
            pacer = self.pacer
            if pacer is not None:
                pacer.start(self.world.tick)
            orders = self.orders
            while self.world.tick < end and not self.stopped_by and not self._stop_requested():
                self.advance(end)
                self.communicate()
                if pacer is not None:
                    pacer.wait(self.world.tick)
                if progress is not None:
                    progress(self.world.tick, end)
                if orders is not None and orders.done():
                    self.stopped_by = orders.reason(self.world.tick / self.world.rate)
                    break
        except BaseException:
            self.close("the run failed")
            raise
        if self._stop_requested():
            self.stopped_by = f"stopped by an operator at t = {self.world.tick / self.world.rate:.9g} s"
        if self.stopped_by or self.world.tick >= self.plant.scenario.run.end_tick:
            self.close(self.stopped_by or "the run reached its end")
        return RunResult(self.world.tick - start_tick, self.world.rate, time.perf_counter() - started,
                         self.stopped_by)

    def _stop_requested(self) -> bool:
        return self.commands is not None and self.commands.stop_requested

    def close(self, reason: str = "closed") -> None:
        """Tell participants the run is over, stop the processes it launched, close a bus it opened."""
        if self._closed:
            return
        self._closed = True
        try:
            if self.lockstep is not None:
                self.lockstep.close(reason)
        finally:
            if self._own_bus:
                self.bus.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _may_emit(comp: Component) -> bool:
    overrides = type(comp).events is not Component.events
    has_void = any(s.type is SlotType.VOID and s.direction is Direction.SOURCE for s in comp.SLOTS)
    return overrides or has_void
