"""Observers and stop conditions: what watches a run and what ends it, plugged into the master (libcosim's observer and manipulator roles)."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from hub.core.signals import Signals

#: One event-log row: (tick, slot, detail).
Event = tuple[int, str, str]


@runtime_checkable
class Observer(Protocol):
    """Sees every communication point once its values are final (observe, step 4 of the step loop,
    hub/run/master.py): the tick, the plant's state object and the point's events in tick
    order. It may read anything and change nothing the plant computes; what it writes goes to
    files, the bus or its own figures. `close(reason)` is called once when the run ends, however
    it ends."""

    def observe(self, tick: int, signals: Signals, events: Sequence[Event]) -> None: ...

    def close(self, reason: str) -> None: ...


@dataclass(frozen=True)
class Stop:
    """Why a run ends before its duration: `ended` is a normal end (its orders were delivered),
    otherwise it was stopped (by an operator, a signal)."""

    reason: str
    ended: bool = False


@runtime_checkable
class StopCondition(Protocol):
    """Asked after every communication point: a `Stop` ends the run there, None lets it go on."""

    def stop(self, tick: int) -> Stop | None: ...


@runtime_checkable
class SummarySection(Protocol):
    """A part of the run summary an observer contributes (the plant's figures): printed right after
    the wall time, and in summary.json under `key`."""

    key: str

    def lines(self) -> list[str]: ...

    def as_dict(self) -> dict: ...


@runtime_checkable
class BodyLook(Protocol):
    """What a view shows of the bodies beyond their poses (a bottle's fill and cap state, its
    destination), contributed by the modules that know it (Module.CONTRIBUTES): `look(rows)` gives
    map entries of the bodies message (schemas/scene.schema.json `bodies_message`), one value per row, in the rows' order."""

    def look(self, rows: Sequence[int]) -> dict: ...
