"""The Python API: load a scenario, swap in your logic, run until a time or a condition, read slots."""
from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from hub.core.errors import PlanthubError
from hub.core.registry import did_you_mean
from hub.core.slots import SlotRef, SlotType
from hub.run.assembly import Run
from hub.run.master import RunResult
from hub.run.summary import RunSummary
from hub.scenario.checker import load_scenario
from hub.scenario.expectations import NoJam, Outcome, interrupted
from hub.scenario.model import Scenario


class Simulation:
    """One scenario, built and at its first communication point.

        with Simulation("scenarios/switch_logic.yaml", logic={"sw": "my_switch.fmu"}) as sim:
            sim.run_until(lambda s: s["branch_end.count.total"] == 1, timeout=10)
            assert sim["main_end.count.total"] == 0
            assert all(outcome.passed for outcome in sim.check())

    `scenario` is a file, or a Scenario loaded already with its overrides (`planthub test` loads it
    first, to write a JUnit file for a scenario that does not load). `overrides` take dotted keys
    as `--set` does; `logic` maps an object to a replacement FMU for its state logic. Every source
    slot is computed (not only the ones flows, the recording and the expectations read), so any
    slot can be read at any point; `every_source=False` computes
    only those (`planthub test`: every bottle's pose at every point is a third of a plant's run). `out` writes recording.csv and events.csv, and
    summary.json when the simulation is closed. `summary()` gives the run summary at any point:
    for a plant (sinks, sources) bottles in, delivered, misrouted, on the line, throughput, jams.
    The other keywords are those of hub.run.assembly.Run (`bus`, `replay`, `pacer`, `log`,
    `signals`). With `signals`, a SIGINT or SIGTERM ends the run at its next point, and `check()`
    then judges only what the part that ran can tell; `on_emergency(sim, reason)` is called when
    the process ends from a helper thread instead (a stuck step, a second signal: hub/run/interruption.py).
    """

    def __init__(self, scenario, overrides: dict | None = None, logic: dict | None = None,
                 out: Path | None = None, on_emergency=None, every_source: bool = True, **run_options):
        changes = dict(overrides or {})
        for name, file in (logic or {}).items():
            changes[f"objects.{name}.logic"] = {"file": str(Path(file).resolve())}
        if isinstance(scenario, Scenario):
            if changes:
                raise TypeError("overrides and logic go with a scenario's file: this Scenario is loaded already")
            self.scenario = scenario
        else:
            self.scenario = load_scenario(scenario, changes)
        self.out = out
        self.events: list[tuple[float, str, str]] = []   # the event log: (time, slot, detail)
        self._run = Run(self.scenario, out=out, every_source=every_source, observers=[_EventLog(self)], **run_options)
        self.watcher = self._run.watcher
        try:
            self.plant = self._run.plant
            self.master = self._run.master
            if on_emergency is not None and self.interruption is not None:
                self.interruption.reporters.append(lambda reason: on_emergency(self, reason))
            self._run.start()   # participants on the bus are launched and awaited here (and a checkpoint put back)
            if not self.master.communicated:
                self.master.communicate()
        except BaseException:
            self._run.close("the run failed")
            raise

    @property
    def recorder(self):
        return self._run.recorder

    @property
    def interruption(self):
        """The signals' stop condition (hub/run/interruption.py) with `signals=True`, else None."""
        return self._run.interruption

    @property
    def time(self) -> float:
        return self.master.tick / self.scenario.run.physics_rate

    @property
    def figures(self) -> list:
        """The observers the scenario's modules contribute that add to the summary (a plant's tally)."""
        return self._run.figures

    @property
    def wall_seconds(self) -> float:
        return self._run.wall_seconds

    def run(self, until: float | None = None) -> RunResult:
        """Run to `until` seconds (default: the scenario's duration)."""
        end = None if until is None else round(until * self.scenario.run.physics_rate)
        return self._run.run(end)

    def run_until(self, condition: Callable[[Simulation], bool], timeout: float) -> bool:
        """Step until `condition(sim)` holds at a communication point (True) or `timeout`
        simulated seconds have passed (False)."""
        limit = self.master.tick + round(timeout * self.scenario.run.physics_rate)
        started = time.perf_counter()
        try:
            while not condition(self):
                if self.master.tick >= limit:
                    return False
                self.master.advance(limit)
                self.master.communicate()
            return True
        finally:
            self._run.wall_seconds += time.perf_counter() - started

    def summary(self) -> RunSummary:
        """The run summary now: what `planthub run` prints and writes to summary.json. Its
        `plant` (None without sinks and sources) has bottles_in, delivered, by_destination,
        sinks, misrouted, on_line, per_minute and jams; `as_dict()` is the JSON form."""
        return self._run.summary()

    def __getitem__(self, slot: str):
        """The slot's value now (a void slot: whether it fired at this point)."""
        ref = self._ref(slot)
        i = self.plant.index[ref]
        if self.plant.signals.slots[i].type is SlotType.VOID:
            return self.plant.signals.fired(i)
        return self.plant.signals.values[i]

    def _ref(self, slot: str) -> SlotRef:
        parts = slot.split(".")
        if len(parts) == 3:
            ref = SlotRef(*parts)
            if ref in self.plant.index:
                return ref
        elif len(parts) == 2:
            found = [r for r in self.plant.index if (r.obj, r.slot) == tuple(parts)]
            if len(found) == 1:
                return found[0]
        names = [str(r) for r in self.plant.index]
        raise PlanthubError(f"no slot {slot!r} in {self.scenario.path}{did_you_mean(slot, names)}")

    def check(self) -> list[Outcome]:
        """The scenario's expectations judged on what was seen so far, in the scenario's order, then
        what its settings imply (with `run.orders`: that the run ends with its orders out)."""
        on_slots = iter(self.watcher.judge())
        plant = self.summary().plant
        jams = plant.jams if plant is not None else ()
        outcomes = [e.judge(jams, self.time) if isinstance(e, NoJam) else next(on_slots) for e in self.scenario.expect]
        # What the scenario's settings promise, judged by the modules that contribute them (run.orders).
        outcomes += [c.outcome(self.master.tick) for c in self._run.contributed if hasattr(c, "outcome")]
        # An exercise's goals and its score (hub/run/exercise.py Score), each judged as a case.
        outcomes += [o for c in self._run.contributed if hasattr(c, "outcomes") for o in c.outcomes(self.master.tick)]
        if self.interruption is not None and self.interruption.interrupted:
            return interrupted(outcomes, self.master.tick, self.scenario.run.physics_rate)
        return outcomes

    def close(self) -> None:
        self._run.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._run.failure = exc[1]   # summary.json says the run failed, and how
        self._run.close("the run failed" if exc[0] is not None else "closed")


class _EventLog:
    """Keeps the event log in memory, as (time, slot, detail), for `Simulation.events`."""

    def __init__(self, sim: Simulation):
        self.log = sim.events
        self.rate = sim.scenario.run.physics_rate

    def observe(self, tick, signals, events) -> None:
        self.log.extend((t / self.rate, slot, detail) for t, slot, detail in events)

    def close(self, reason: str) -> None:
        """Nothing to release: the log stays readable."""
