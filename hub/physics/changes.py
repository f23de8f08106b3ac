"""What the plant changes in the world, announced once and heard by every level of detail that listens."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Change:
    """One change a part of the plant made to the world (a belt's speed, a gate, a moving part, an
    arm's grip, a body parked or put down), as a level of detail hears it.

    `woken`: the resting bodies it reaches (with their groups, rest.py), worked out by the first
    listener that needs them (`reached`); a listener heard before another may take some of them
    over (free transport lets those that can ride off free from rest, and leaves the rest to wake)."""
    woken: np.ndarray | None = field(default=None, init=False, repr=False)


@dataclass
class BeltSpeed(Change):
    """A belt's field runs at a new speed (already set in the fields' table)."""
    field: int
    speed: float


@dataclass
class PartTurned(Change):
    """A switchable part (a gate, a blade) turns solid or void: its box (centre, half extents)."""
    part: int
    solid: bool
    centre: np.ndarray
    extents: np.ndarray


@dataclass
class PartsMoving(Change):
    """Before a tick: moving parts under way (a pusher's plate) will sweep these boxes (centres,
    half extents (M, 3), as the wake rule widens them)."""
    centres: np.ndarray
    extents: np.ndarray


@dataclass
class Gripped(Change):
    """An arm grips a body: it leaves the dynamics and follows the tool (from the next tick on)."""
    body: int


@dataclass
class LetGo(Change):
    """An arm let go of a body: it collides again from the next tick on."""
    body: int


@dataclass
class Parked(Change):
    """A body leaves play (a sink takes it, the watch removes it): it is about to go off stage."""
    body: int


@dataclass
class Placed(Change):
    """A body was put down in play where it had not been (a source's bottle unparked): its box
    (centre, half extents (1, 3)) as it stands now."""
    body: int
    centre: tuple
    extents: np.ndarray


@dataclass
class Tipped(Change):
    """A body in play is about to be laid on its side where it stands (a fault): its box (centre,
    half extents (1, 3)) lying."""
    body: int
    centre: tuple
    extents: np.ndarray


#: Every kind of change; a level of detail hears each one (tests/physics/test_changes.py).
KINDS = (BeltSpeed, PartTurned, PartsMoving, Gripped, LetGo, Parked, Placed, Tipped)


def reached(change: Change, rest, positions) -> np.ndarray:
    """The resting rows `change` reaches, with their groups: those on its belt, or whose boxes
    overlap its boxes; none for a change without a place. Worked out once per change."""
    if change.woken is None:
        if not rest.resting.any():
            change.woken = np.zeros(0, int)
        elif isinstance(change, BeltSpeed):
            change.woken = rest.on_field(change.field, positions)
        elif isinstance(change, PartTurned):
            change.woken = rest.joining([change.centre], [change.extents], positions)
        elif isinstance(change, PartsMoving):
            change.woken = rest.joining(change.centres, change.extents, positions)
        elif isinstance(change, (Placed, Tipped)):
            change.woken = rest.joining([change.centre], change.extents, positions)
        else:
            change.woken = np.zeros(0, int)
    return change.woken


class Changes:
    """The world's one place where changes are announced: every level of detail that listens
    (free transport, rest and sleep, …) hears every change, in the order they registered — free
    transport before sleep, so that it may take a resting body off free before sleep wakes it."""

    def __init__(self):
        self.listeners: list = []

    def listen(self, listener) -> None:
        """`listener.hear(change)` is called for every change from now on (one that does not
        concern it, it ignores)."""
        self.listeners.append(listener)

    def announce(self, change: Change) -> Change:
        for listener in self.listeners:
            listener.hear(change)
        return change
