"""Writes recorded slots (one CSV row per communication point) and the event log while a run goes."""
from __future__ import annotations

import csv
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from hub.core.files import written
from hub.core.signals import Signals
from hub.core.slots import SlotRef, SlotType

#: s of wall time between two flushes of the run's files (their cost: `make bench`)
FLUSH_PERIOD = 0.5

_SUFFIXES = {SlotType.VEC3: ("x", "y", "z"), SlotType.QUAT: ("x", "y", "z", "w")}


def _cell(kind: SlotType, value, fired: bool):
    if kind is SlotType.VOID:
        return ("1" if fired else "0",)
    if kind is SlotType.BOOL:
        return ("1" if value else "0",)
    if kind is SlotType.REAL:
        return (repr(value),)
    if kind in _SUFFIXES:
        return tuple(repr(v) for v in value)
    return (str(value),)


@dataclass
class EventStats:   # a plain value in a snapshot (hub/core/state.py)
    count: int = 0
    first_tick: int | None = None
    first_detail: str = ""


@dataclass
class Recorder:
    """Streams `recording.csv` and `events.csv` into `directory` (or only counts, without one).

    recording.csv: a `time` column in seconds, then one column per recorded slot (vec3 and quat
    slots take one column per component, `slot.x` …); a void source shows 1 in steps where it
    fired, a void target 1 in steps where a flow fed it; bool slots 1/0; reals are written with every digit, so equal runs give equal files.
    events.csv: `time,tick,slot,detail`, one row per event in order of the physics tick.
    commands.csv (from the first operator command on): `time,tick,op,slot,value,by`, the value
    as JSON — what `planthub run --replay` applies again at the same ticks.
    bus_log.csv (from the first notice on): `time,tick,detail`, what happened to the run on the
    bus (a pause for a lost participant, the resumption). It is kept apart from events.csv, which
    holds only what the plant did: a pause depends on the wall clock and the network, so no
    re-run reproduces it, while events.csv and recording.csv of a replay equal the original's.
    A rewind (hub/run/rewind.py) cuts recording.csv and events.csv back to its checkpoint's point
    (`marks`, `cut`) and writes what it cut beside, in recording.branchN.csv and events.branchN.csv.
    """

    columns: list[tuple[SlotRef, SlotType, int]]   # (slot, type, index in the plant's Signals)
    rate: int
    directory: Path | None = None
    stats: dict[str, EventStats] = field(default_factory=dict)
    #: hub/core/state.py: what the summary counts; the files of a resumed run start at its resume point.
    STATE: ClassVar[tuple[str, ...]] = ("stats",)

    def __post_init__(self):
        self._files = []
        self._named = {}   # file name → its handle
        self._flush_due = 0.0
        self._rows = self._events = self._commands = self._notices = None
        if self.directory is not None:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._rows = self._open("recording.csv")
            header = ["time"]
            for ref, kind, _ in self.columns:
                header += [f"{ref}.{s}" for s in _SUFFIXES[kind]] if kind in _SUFFIXES else [str(ref)]
            csv.writer(self._files[-1], quoting=csv.QUOTE_ALL, lineterminator="\n").writerow(header)
            self._events = self._open("events.csv")
            self._events.writerow(["time", "tick", "slot", "detail"])
            self.flush()   # the headers are there from the start

    def _open(self, name: str):
        handle = open(self.directory / name, "w", newline="", encoding="utf-8")
        self._files.append(handle)
        self._named[name] = handle
        return csv.writer(handle, lineterminator="\n")

    def observe(self, tick: int, signals: Signals, events) -> None:
        """An observer of the run (hub/core/observer.py): the point's events, then its row; the
        files are flushed every FLUSH_PERIOD of wall time, so a hub killed outright leaves them
        readable up to that long before the kill."""
        for t, slot, detail in events:
            self.event(t, slot, detail)
        self.sample(tick, signals)
        now = time.monotonic()
        if now >= self._flush_due:
            self.flush()
            self._flush_due = now + FLUSH_PERIOD

    def flush(self) -> None:
        for handle in self._files:
            handle.flush()

    def sample(self, tick: int, signals: Signals) -> None:
        if self._rows is None:
            return
        row = [repr(tick / self.rate)]
        values = signals.values
        for _, kind, i in self.columns:
            row.extend(_cell(kind, values[i], signals.fired(i)))
        self._rows.writerow(row)

    def event(self, tick: int, slot: str, detail: str) -> None:
        stats = self.stats.setdefault(slot, EventStats())
        if stats.first_tick is None:
            stats.first_tick, stats.first_detail = tick, detail
        stats.count += 1
        if self._events is not None:
            self._events.writerow([repr(tick / self.rate), tick, slot, detail])

    def command(self, tick: int, op: str, slot: str, value: str, by: str) -> None:
        if self.directory is None:
            return
        if self._commands is None:
            self._commands = self._open("commands.csv")
            self._commands.writerow(["time", "tick", "op", "slot", "value", "by"])
        self._commands.writerow([repr(tick / self.rate), tick, op, slot, value, by])

    def notice(self, tick: int, detail: str) -> None:
        if self.directory is None:
            return
        if self._notices is None:
            self._notices = self._open("bus_log.csv")
            self._notices.writerow(["time", "tick", "detail"])
        self._notices.writerow([repr(tick / self.rate), tick, detail])

    #: the files a rewind cuts back: what the plant did (commands.csv and bus_log.csv keep every branch)
    BRANCHED = ("recording.csv", "events.csv")

    def marks(self) -> dict[str, int] | None:
        """Where recording.csv and events.csv end now, in bytes (None without a folder): taken with a
        checkpoint, after this point's row, so that a rewind to it can cut them back there."""
        if self.directory is None:
            return None
        out = {}
        for name in self.BRANCHED:
            handle = self._named[name]
            handle.flush()
            out[name] = handle.tell()
        return out

    def cut(self, marks: dict[str, int] | None, branch: int) -> list[Path]:
        """Cut recording.csv and events.csv back to `marks` (Recorder.marks); what followed goes,
        under the file's header, to NAME.branchN.csv beside it. Returns the files written."""
        if self.directory is None or marks is None:
            return []
        made = []
        for name in self.BRANCHED:
            handle = self._named[name]
            handle.flush()
            path = self.directory / name
            with open(path, "rb") as whole:
                header = whole.readline()
                whole.seek(marks[name])
                after = whole.read()
            stem, suffix = name.rsplit(".", 1)
            beside = self.directory / f"{stem}.branch{branch}.{suffix}"
            with written(beside, "wb") as out:
                out.write(header + after)
            handle.seek(marks[name])
            handle.truncate()
            made.append(beside)
        return made

    def close(self, reason: str = "") -> None:
        for handle in self._files:
            handle.close()
        self._files = []
