"""Jams: a bottle standing still on a running belt for longer than `run.jam_after`, unless a closed gate holds it on purpose."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

TOUCH = 0.003        # m: a bottle this close to a gate, or to a bottle held at one, is held too
CHECK_PERIOD = 0.1   # s of simulated time between two looks (at the first point at or after each)


@dataclass(frozen=True)
class Jam:
    """One jam: the bottle, the belt it stood on, from when it stood, and until when (None: at the end)."""

    bottle: str
    belt: str
    since: float          # s: the look that first saw it at the spot where it stuck
    until: float | None   # s: the first look that saw it move on (or held, or gone); None: jammed at the end

    def seconds(self, end: float) -> float:
        return (end if self.until is None else self.until) - self.since


class JamWatch:
    """Looks at the bottles in play every CHECK_PERIOD and keeps the jams, by this rule:

    a bottle is *jammed* when, for `after` seconds (run.jam_after), it has stayed on a running
    belt (the force field its centre lies in has a nonzero speed) within its own diameter of
    one spot — or within half the way the belt runs in that time, if that is less, for slow
    belts — without being *held*: within TOUCH of a closed part that holds bottles on purpose
    (a stopper, a separator's gate), or within TOUCH of a held bottle (the queue behind such a
    gate, however long). It is jammed against a rail, a switch blade, an obstacle or another
    jammed bottle, from the look that first saw it at that spot until the look that sees it
    move away, held or gone. A stopper holding a bottle and its queue for a station is never a
    jam, whatever the time; a bottle stuck at a blade is.

    Why a spot and not a speed: a bottle the belt presses against a rail jitters at up to
    0.01 m/s in the contact, and a queue pressed against a gate or a rail swings to and fro by
    up to 5 cm (Bullet's compliant contacts), so neither its speed at a tick nor its way between
    two looks says whether it gets anywhere; whether it leaves the spot does.

    The looks run at the first communication point at or after each multiple of CHECK_PERIOD,
    on arrays the world already read (numpy over the bottles in play and the closed gates), and
    equal runs see equal jams.
    """

    STATE = ("due", "spot", "since", "open", "found")

    def __init__(self, world, belts: dict[int, str], holders, after: float):
        self.world = world
        self.belts = belts                 # force field → belt name
        self.holders = holders             # modules/gate.py Holders: parts that hold on purpose when closed; or None
        self.after = max(1, round(after * world.rate))
        self.period = max(1, round(CHECK_PERIOD * world.rate))
        self.due = 0
        n = len(world.labels)
        self.spot = np.zeros((n, 2))       # where each bottle was seen to stop
        self.since = np.full(n, -1)        # tick it has stood there unheld from; −1: not on a running belt
        self.open: dict[int, int] = {}     # body → index in `found` of its jam still going
        self.found: list[Jam] = []

    def observe(self, tick: int) -> None:
        """Look, if a look is due at this point."""
        if tick < self.due:
            return
        self.due = (tick // self.period + 1) * self.period
        world = self.world
        rows, field, speed = world.belts_under()
        p = world.positions[rows, :2]
        running = speed != 0.0
        away = p - self.spot[rows]
        reach = np.minimum(2.0 * world.radii[rows], 0.5 * np.abs(speed) * self.after / world.rate)
        staying = running & (self.since[rows] >= 0) & (np.hypot(away[:, 0], away[:, 1]) <= reach)
        free = np.zeros(len(self.since), bool)
        if staying.any():
            bodies = rows[staying]
            held = self._held(bodies)
            self.since[bodies[held]] = tick   # held on purpose: its time standing free starts again
            free[bodies[~held]] = True
        moved = rows[running & ~staying]      # moving, or just onto a running belt: a new spot
        self.spot[moved] = p[running & ~staying]
        tracked = np.zeros(len(self.since), bool)
        tracked[rows[running]] = True
        self.since[moved] = tick
        self.since[~tracked] = -1
        for body in [b for b in self.open if not free[b]]:
            i = self.open.pop(body)
            self.found[i] = Jam(self.found[i].bottle, self.found[i].belt, self.found[i].since, tick / world.rate)
        jammed = np.nonzero(free & (tick - self.since >= self.after))[0]
        for body in jammed.tolist():
            if body not in self.open:
                f = int(field[np.searchsorted(rows, body)])
                self.open[body] = len(self.found)
                self.found.append(Jam(world.labels[body], self.belts.get(f, "?"), int(self.since[body]) / world.rate,
                                      None))

    def _held(self, bodies: np.ndarray) -> np.ndarray:
        """For standing bodies: whether each is held at a closed gate, directly or through a queue."""
        world = self.world
        p, r, h = world.positions[bodies], world.radii[bodies], world.half_heights[bodies]
        held = self.holders.depths(p, r, h) > -TOUCH if self.holders is not None else np.zeros(len(bodies), bool)
        if not held.any():
            return held
        # The queues: the bottles reached from a held one through bottles touching in turn.
        return _queues(p, r, held)

    def jams(self) -> list[Jam]:
        """Every jam so far, in the order they became jams."""
        return list(self.found)


@njit(cache=True)
def _queues(p, r, held):
    """`held` grown by every body whose footprint comes within TOUCH of one it holds, in turn."""
    out = held.copy()
    stack = [i for i in range(p.shape[0]) if held[i]]
    while stack:
        i = stack.pop()
        for j in range(p.shape[0]):
            if not out[j] and math.hypot(p[i, 0] - p[j, 0], p[i, 1] - p[j, 1]) <= r[i] + r[j] + TOUCH:
                out[j] = True
                stack.append(j)
    return out
