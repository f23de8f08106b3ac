"""The Python API: load a scenario, swap in your logic, run until a time or a condition, read slots."""
from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

from hub.core.errors import PlanthubError
from hub.scenario.expectations import Expectation, NoJam, Outcome, Watcher
from hub.run.master import Master, RunResult
from hub.run.plant import Plant
from modules.plant.summary import PlantTally
from hub.run.recorder import Recorder
from hub.core.registry import did_you_mean
from hub.run.summary import RunSummary
from hub.scenario.checker import load_scenario
from hub.core.slots import Direction, SlotRef, SlotType


class Simulation:
    """One scenario, built and at its first communication point.

        with Simulation("scenarios/switch_logic.yaml", logic={"sw": "my_switch.fmu"}) as sim:
            sim.run_until(lambda s: s["branch_end.count.total"] == 1, timeout=10)
            assert sim["main_end.count.total"] == 0
            assert all(outcome.passed for outcome in sim.check())

    `overrides` take dotted keys as `--set` does; `logic` maps an object to a replacement FMU for
    its state logic. Every source slot is computed (not only the ones flows and the recording
    read), so any slot can be read at any point. `out` writes recording.csv and events.csv, and
    summary.json when the simulation is closed. `summary()` gives the run summary at any point:
    for a plant (sinks, sources) bottles in, delivered, misrouted, on the line, throughput, jams.
    """

    def __init__(self, scenario, overrides: dict | None = None, logic: dict | None = None,
                 out: Path | None = None):
        changes = dict(overrides or {})
        for name, file in (logic or {}).items():
            changes[f"objects.{name}.logic"] = {"file": str(Path(file).resolve())}
        self.scenario = load_scenario(scenario, changes)
        self.out = out
        self.wall_seconds = 0.0   # spent in run and run_until
        self.plant = Plant(self.scenario)
        try:
            for comp in self.plant.components:
                comp.needed = frozenset(s.name for s in comp.SLOTS if s.direction is Direction.SOURCE)
            run = self.scenario.run
            columns = [(ref, kind, self.plant.index[ref]) for ref, kind in self.scenario.record]
            self.events: list[tuple[float, str, str]] = []
            self.recorder = _Recorder(columns, run.physics_rate, out, log=self.events)
            self.master = Master(self.plant, self.recorder)
            slots = [e for e in self.scenario.expect if isinstance(e, Expectation)]
            self.watcher = Watcher(slots, self.plant.index, run.physics_rate)
            self.tally = PlantTally.for_plant(self.plant)
            self.master.start()   # participants on the bus are launched and awaited here
            self.master.communicate()
            self._observe(self.master.tick)
        except BaseException:
            self.close()
            raise

    @property
    def time(self) -> float:
        return self.master.tick / self.scenario.run.physics_rate

    def run(self, until: float | None = None) -> RunResult:
        """Run to `until` seconds (default: the scenario's duration)."""
        end = None if until is None else round(until * self.scenario.run.physics_rate)
        result = self.master.run(end, progress=lambda tick, _: self._observe(tick))
        self.wall_seconds += result.wall_seconds
        return result

    def run_until(self, condition: Callable[["Simulation"], bool], timeout: float) -> bool:
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
                self._observe(self.master.tick)
            return True
        finally:
            self.wall_seconds += time.perf_counter() - started

    def _observe(self, tick: int) -> None:
        self.watcher.observe(tick, self.plant.signals)
        if self.tally is not None:
            self.tally.observe(tick)

    def summary(self) -> RunSummary:
        """The run summary now: what `planthub run` prints and writes to summary.json. Its
        `plant` (None without sinks and sources) has bottles_in, delivered, by_destination,
        sinks, misrouted, on_line, per_minute and jams; `as_dict()` is the JSON form."""
        run = self.scenario.run
        return RunSummary(self.scenario.name, self.scenario.path, self.master.tick, run.physics_rate, run.substeps,
                          self.wall_seconds, self.recorder.stats, len(self.scenario.record), self.out,
                          self.tally.summary() if self.tally is not None else None)

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
        """The scenario's expectations judged on what was seen so far, in the scenario's order."""
        on_slots = iter(self.watcher.judge())
        jams = self.tally.summary().jams if self.tally is not None else ()
        return [e.judge(jams, self.time) if isinstance(e, NoJam) else next(on_slots) for e in self.scenario.expect]

    def close(self) -> None:
        try:
            if getattr(self, "master", None) is not None:
                self.master.close()
                if self.out is not None and hasattr(self, "tally"):   # built far enough to summarise
                    self.summary().write(Path(self.out) / "summary.json")
        finally:
            try:
                if getattr(self, "recorder", None) is not None:
                    self.recorder.close()
            finally:
                self.plant.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class _Recorder(Recorder):
    """A recorder that also keeps the event log in memory, as (time, slot, detail)."""

    def __init__(self, columns, rate, directory, log: list):
        super().__init__(columns, rate, directory)
        self.log = log

    def event(self, tick: int, slot: str, detail: str) -> None:
        super().event(tick, slot, detail)
        self.log.append((tick / self.rate, slot, detail))
