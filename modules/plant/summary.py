"""The plant engineer's view of a run: bottles in, delivered by sink and destination, rejected, misrouted, on the line, throughput, jams."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

from hub.physics.world import PARKED
from modules.belt import BeltDrive
from modules.gate import Holders, TwoPositions
from modules.plant.jams import Jam, JamWatch
from modules.plant.report import NO_DESTINATION, plant_lines  # noqa: F401 (NO_DESTINATION: part of the summary's API)
from modules.sink import Bin
from modules.source import Store

BUSY = 0.9           # the line is full while it holds at least this share of the most bottles seen on it


@dataclass(frozen=True)
class Misroute:
    bottle: str
    destination: str
    sink: str
    time: float


@dataclass(frozen=True)
class Reject:
    """A bottle the line rejected: taken out at a reject sink (`rejects: true`), not delivered."""

    bottle: str
    destination: str
    sink: str
    time: float


@dataclass(frozen=True)
class SinkCount:
    name: str
    accepts: tuple[str, ...] | None     # None: the sink judges no destination
    by_destination: dict[str, int]      # sorted by destination
    misrouted: int
    rejects: bool = False               # a reject sink: what it took is rejected, not delivered

    @property
    def total(self) -> int:
        return sum(self.by_destination.values())


@dataclass(frozen=True)
class OnLine:
    bottle: str
    belt: str | None      # the belt under it, None: off every belt
    position: tuple[float, float, float]


@dataclass(frozen=True)
class Busy:
    """The part of a run while at least `at_least` bottles were on the line (90 % of the most):
    simulated and wall seconds between the looks that saw them, and so the real-time factor
    of a full line."""

    at_least: int
    sim_seconds: float
    wall_seconds: float

    @property
    def realtime_factor(self) -> float | None:
        return self.sim_seconds / self.wall_seconds if self.wall_seconds > 0 else None

    def as_dict(self) -> dict:
        return {"at_least": self.at_least, "simulated_seconds": self.sim_seconds,
                "wall_seconds": self.wall_seconds, "realtime_factor": self.realtime_factor}


@dataclass(frozen=True)
class PlantSummary:
    """What came in, what went out where, what is left and what got stuck, over [start, end] s:
    the plant's section of the run summary (hub/core/observer.py SummarySection)."""

    key = "plant"

    start: float
    end: float
    placed: int                          # bottles on the line from the start (`bottle` objects)
    released: dict[str, int]             # source → bottles it put on the line
    sinks: tuple[SinkCount, ...]
    delivery_times: tuple[float, ...]    # every delivery, in order (rejects are not deliveries)
    misrouted: tuple[Misroute, ...] | None   # None: no sink states `accepts`, nothing was judged
    on_line: tuple[OnLine, ...]
    jams: tuple[Jam, ...]
    jam_after: float
    most_on_line: int = 0                # the most bottles on the line at one look (every 0.1 s)
    most_on_line_at: float = 0.0         # s, the first look that saw them
    busy: Busy | None = None             # the run while the line was near its fullest (wall time: not in as_dict)
    rejected: tuple[Reject, ...] | None = None   # in time order; None: the plant has no reject sink

    @property
    def bottles_in(self) -> int:
        return self.placed + sum(self.released.values())

    @property
    def delivered(self) -> int:
        return len(self.delivery_times)

    @property
    def by_destination(self) -> dict[str, int]:
        """Deliveries by destination, over the sinks that deliver (not the reject sinks)."""
        out: dict[str, int] = {}
        for sink in self.sinks:
            if sink.rejects:
                continue
            for dest, n in sink.by_destination.items():
                out[dest] = out.get(dest, 0) + n
        return dict(sorted(out.items()))

    @property
    def per_minute(self) -> float:
        """Deliveries per simulated minute over the whole window [start, end]."""
        span = self.end - self.start
        return 60.0 * self.delivered / span if span > 0 else 0.0

    @property
    def steady_per_minute(self) -> float | None:
        """Deliveries per minute between the first and the last delivery (the line's pace once
        full); None with fewer than two deliveries or all at one point."""
        times = self.delivery_times
        if len(times) < 2 or times[-1] == times[0]:
            return None
        return 60.0 * (len(times) - 1) / (times[-1] - times[0])

    def lines(self) -> list[str]:
        """The plant block of the printed summary."""
        return plant_lines(self)

    def wall_detail(self) -> str:
        """What the wall-time line adds: the real-time factor while the line was near its fullest."""
        busy = self.busy
        if busy is None or not busy.realtime_factor:
            return ""
        return f"{busy.realtime_factor:.1f}× while {busy.at_least} or more bottles were on the line, {busy.sim_seconds:.1f} s"

    def wall_figures(self) -> dict:
        """summary.json's `wall.full_line`: the same figures for machines."""
        return {"full_line": None if self.busy is None else self.busy.as_dict()}

    def as_dict(self) -> dict:
        """The machine-readable form (summary.json's `plant`): plain JSON types, equal runs give equal dicts."""
        return {
            "window": [self.start, self.end],
            "bottles_in": self.bottles_in,
            "placed": self.placed,
            "released": dict(self.released),
            "delivered": self.delivered,
            "by_destination": self.by_destination,
            "sinks": {s.name: {"total": s.total, "accepts": None if s.accepts is None else list(s.accepts),
                               "by_destination": dict(s.by_destination), "misrouted": s.misrouted,
                               "rejects": s.rejects}
                      for s in self.sinks},
            "rejected": None if self.rejected is None else [
                {"bottle": r.bottle, "destination": r.destination, "sink": r.sink, "time": r.time}
                for r in self.rejected],
            "misrouted": None if self.misrouted is None else [
                {"bottle": m.bottle, "destination": m.destination, "sink": m.sink, "time": m.time}
                for m in self.misrouted],
            "on_line": [{"bottle": b.bottle, "belt": b.belt, "position": list(b.position)} for b in self.on_line],
            "most_on_line": {"bottles": self.most_on_line, "time": self.most_on_line_at},
            "throughput": {"per_minute": self.per_minute, "window": [self.start, self.end],
                           "first_to_last_per_minute": self.steady_per_minute,
                           "first": self.delivery_times[0] if self.delivery_times else None,
                           "last": self.delivery_times[-1] if self.delivery_times else None},
            "jam_after": self.jam_after,
            "jams": [{"bottle": j.bottle, "belt": j.belt, "since": j.since, "until": j.until,
                      "seconds": j.seconds(self.end)} for j in self.jams],
        }


class PlantTally:
    """Collects a PlantSummary while a plant runs: an observer (hub/core/observer.py) that sources
    and sinks contribute to every run that holds one (Module.CONTRIBUTES).

    Sinks keep their own deliveries and sources their bottles, so the only work per point is the
    jam watch (modules/plant/jams.py), which looks every few ticks.
    """

    STATE = ("looks", "watch")

    def __init__(self, plant):
        world = self.world = plant.world
        comps = plant.components
        self.rate = world.rate
        self.start = world.tick
        self.sinks = [c for c in comps if isinstance(c, Bin)]
        self.sources = [c for c in comps if isinstance(c, Store)]
        self.belts = {c.field: c.obj if c.name == "drive" else f"{c.obj}.{c.name}"
                      for c in comps if isinstance(c, BeltDrive)}
        stored = {b for s in self.sources for b in s.bodies}
        self.placed = [n for n in range(len(world.labels)) if n not in stored]
        holders = Holders([c.blocker for c in comps if isinstance(c, TwoPositions) and c.HOLDS])
        self.jam_after = plant.scenario.run.jam_after
        self.watch = JamWatch(world, self.belts, holders, self.jam_after)
        self.looks: list[tuple[int, int, float]] = []   # (tick, bottles on the line, wall clock) at each look

    def observe(self, tick: int, signals=None, events=()) -> None:
        if tick >= self.watch.due:   # a look: how many bottles are on the line, and the clock
            on_line = int((self.world.positions[:, 2] > PARKED[2] / 2).sum())
            self.looks.append((tick, on_line, time.perf_counter()))
        self.watch.observe(tick)

    def close(self, reason: str) -> None:
        """The figures stay readable after the run."""

    def section(self) -> PlantSummary:
        """This observer's part of the run summary, now."""
        return self.summary()

    def _busy(self) -> tuple[int, int, Busy | None]:
        """(most on the line, the tick of the first look that saw them, the run while ≥ 90 % of them were)."""
        if not self.looks:
            return 0, self.start, None
        most, at = max((n, -tick) for tick, n, _ in self.looks)
        at_least = math.ceil(BUSY * most)
        sim = wall = 0.0
        for (tick, n, clock), (later, _, then) in zip(self.looks, self.looks[1:]):
            if n >= at_least:
                sim += (later - tick) / self.rate
                wall += then - clock
        return most, -at, Busy(at_least, sim, wall) if most else None

    def summary(self) -> PlantSummary:
        """The summary at the world's tick now."""
        world, rate = self.world, self.rate
        # In time order; at one point, in the order of the sinks in the scenario, then as taken.
        deliveries = sorted(((d.tick, k, i), d, sink.obj) for k, sink in enumerate(self.sinks)
                            for i, d in enumerate(sink.deliveries))
        deliveries = [(key[0], d, obj) for key, d, obj in deliveries]
        delivered = {d.body for _, d, _ in deliveries}   # taken out by any sink, rejects included
        rejecting = {sink.obj for sink in self.sinks if sink.rejects}
        rejected = tuple(Reject(d.bottle, d.destination, obj, tick / rate)
                         for tick, d, obj in deliveries if obj in rejecting) if rejecting else None
        deliveries = [(tick, d, obj) for tick, d, obj in deliveries if obj not in rejecting]
        rows, field, _ = world.belts_under()
        # A bottle put out at the last point has not been stepped: its state read is still off
        # stage. Like the event log, which reports a release at the point after, leave it out.
        seen = world.positions[rows, 2] > PARKED[2] / 2
        rows, field = rows[seen], field[seen]
        in_play = set(rows.tolist())
        released = {s.obj: sum(1 for b in s.bodies if b in delivered or b in in_play) for s in self.sources}
        counts = []
        for sink in self.sinks:
            by: dict[str, int] = {}
            for d in sink.deliveries:
                by[d.destination] = by.get(d.destination, 0) + 1
            counts.append(SinkCount(sink.obj, sink.accepts, dict(sorted(by.items())),
                                    sum(d.misrouted for d in sink.deliveries), sink.rejects))
        judged = any(sink.accepts is not None for sink in self.sinks)
        misrouted = tuple(Misroute(d.bottle, d.destination, obj, tick / rate)
                          for tick, d, obj in deliveries if d.misrouted) if judged else None
        on_line = tuple(OnLine(world.labels[n], self.belts.get(int(f)) if f >= 0 else None,
                               tuple(world.positions[n].tolist()))
                        for n, f in zip(rows.tolist(), field.tolist()))
        most, at, busy = self._busy()
        return PlantSummary(self.start / rate, world.tick / rate, len(self.placed), released, tuple(counts),
                            tuple(tick / rate for tick, _, _ in deliveries), misrouted, on_line,
                            tuple(self.watch.jams()), self.jam_after, most, at / rate, busy, rejected)
