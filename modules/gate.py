"""Gates: fixed bodies whose collision the plant switches on and off, as the paper's switches and separators do.

Timing, in physics ticks at communication points: opening turns the collision off at once (the
gate leaves the path) and reports `on_opened` after `travel_time`; closing turns it on after
`travel_time`, and only once no bottle comes within MARGIN of the gate's boxes, because
switching on a body inside a bottle pushes it out, or the wrong way. Measured at 0.5 m/s,
150 Hz: a 5 mm gate enabled 0–25 mm into a bottle tilts it by under 1° (it touches the gate
at its contact ring, hub/physics/world.py; a plain cylinder tipped by 3–5°), 30 mm in pushes
it through to the far side; the switch blade enabled 2–21 mm into a (plain cylinder) bottle
tipped it by 2.0–3.7°, 32 mm in by 12°. Bullet pushes out gently (no bottle ran faster than
the belt), so the wait is about wrong sides, not launching. A command to the state the
gate is in or heading for changes nothing; the opposite command while moving turns it round
from that moment. Reached states are reported from the communication point after they are
reached, like every source that reports the world.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from hub.core.component import Component
from hub.core.slots import Slot
from hub.physics.frames import Boxes

# A bottle must keep this far from a gate's boxes for it to close. Only overlap at the moment
# of switching is harmful: a bottle that runs into the gate in the next tick is stopped by the
# contact like at any closed gate.
MARGIN = 0.001


def overlap(boxes: Boxes, positions: np.ndarray, radii: np.ndarray, half_heights: np.ndarray) -> float:
    """How deep the deepest upright cylinder reaches into any of the boxes, m (≤ 0: none touches)."""
    if len(positions) == 0:
        return -math.inf
    return float(depths(boxes, positions, radii, half_heights).max())


def depths(boxes: Boxes, positions: np.ndarray, radii: np.ndarray, half_heights: np.ndarray) -> np.ndarray:
    """How deep each upright cylinder reaches into each box, m, array (boxes, N) (≤ 0: it does
    not touch; −inf: it is above or below the box).

    In each box's frame: r minus the horizontal distance from the axis to the box, or, with the
    axis inside the box, r plus the distance to the nearest side face. One compiled loop: the
    gates test at communication points and the jam watch at its looks, where numpy's overhead
    per call on a few boxes and bottles was the cost (~100 µs a look in the bottling plant)."""
    return _depths(np.ascontiguousarray(positions, float), np.ascontiguousarray(radii, float),
                   np.ascontiguousarray(half_heights, float), boxes.centers, boxes.half_extents, boxes.cos, boxes.sin)


@njit(cache=True)
def _depths(positions, radii, half_heights, centers, half_extents, cos, sin):
    """`depths`, box by box and body by body."""
    out = np.empty((centers.shape[0], positions.shape[0]))
    for k in range(centers.shape[0]):
        c, s = cos[k], sin[k]
        ex, ey, ez = half_extents[k, 0], half_extents[k, 1], half_extents[k, 2]
        for n in range(positions.shape[0]):
            dx, dy = positions[n, 0] - centers[k, 0], positions[n, 1] - centers[k, 1]
            dz = positions[n, 2] - centers[k, 2]
            x, y = c * dx + s * dy, -s * dx + c * dy
            if abs(dz) > ez + half_heights[n]:
                out[k, n] = -math.inf
                continue
            inside = min(ex - abs(x), ey - abs(y))
            if inside > 0:
                out[k, n] = radii[n] + inside
            else:
                out[k, n] = radii[n] - math.hypot(max(abs(x) - ex, 0.0), max(abs(y) - ey, 0.0))
    return out


class Blocker:
    """The physics of one gate: its boxes, whether they collide, and the test whether a bottle is
    in the way. `push` is how deep a bottle may reach into the boxes and still be pushed out
    when they turn solid (0: the way must be clear by MARGIN)."""

    STATE = ("target", "solid", "arrive", "waiting", "held_open", "reached")

    def __init__(self, world, centers, half_extents, yaws, solid: bool, travel_ticks: int, push: float = 0.0):
        self.world = world
        self.part = world.add_switchable_boxes(centers, half_extents, yaws, solid)
        self.boxes = Boxes()
        for c, h, y in zip(centers, half_extents, yaws):
            self.boxes.add(c, h, y)
        self.allowed = push - MARGIN
        self.travel = travel_ticks
        self.target = solid          # the commanded state
        self.solid = solid           # the collision now
        self.arrive: int | None = None   # tick the move ends, None when not moving
        self.waiting = False             # a due close waits for the way to clear
        self.interlock: Blocker | None = None   # a gate that must be closed before this one opens
        self.held_open = False           # an open waits for the interlock
        self.reached: bool | None = None  # state reached at the last actuation, reported next sense

    def in_the_way(self) -> bool:
        w = self.world
        return overlap(self.boxes, w.positions, w.radii, w.half_heights) > self.allowed

    @property
    def closed(self) -> bool:
        return self.solid and self.arrive is None

    def command(self, tick: int, solid: bool) -> None:
        if not solid and self.interlock is not None and not self.interlock.closed:
            self.held_open = self.target   # open once the interlock is closed (if not open already)
            return
        self.held_open = False
        if solid == self.target:
            return
        self.target = solid
        self.arrive = tick + self.travel
        self.waiting = False
        if not solid and self.solid:
            self.solid = False
            self.world.set_solid(self.part, False)

    def actuate(self, tick: int) -> None:
        """Finish a move that is due: an opening is reported, a closing happens if the way is clear."""
        if self.held_open and self.interlock.closed:
            self.command(tick, False)
        if self.arrive is None or tick < self.arrive:
            return
        self.waiting = self.target and self.in_the_way()
        if self.waiting:
            return   # try again at the next point
        if self.target:
            self.solid = True
            self.world.set_solid(self.part, True)
        self.arrive = None
        self.reached = self.target


class Holders:
    """The parts that hold bottles back on purpose when closed (TwoPositions.HOLDS: stoppers and
    separator gates), as one set of boxes, for the jam rule (modules/plant/jams.py): how close each bottle
    is to a closed one, in one numpy pass however many there are."""

    STATE = ("_closed",)   # which parts were closed at the last look, and their boxes

    def __init__(self, blockers: list[Blocker]):
        self.blockers = blockers
        self.boxes = Boxes()
        owner = []
        for k, b in enumerate(blockers):
            for c, h, cos, sin in zip(b.boxes.centers, b.boxes.half_extents, b.boxes.cos, b.boxes.sin):
                self.boxes.add(c, h, math.atan2(sin, cos))
                owner.append(k)
        self.owner = np.array(owner, dtype=int)
        self._closed: tuple[tuple[bool, ...], Boxes | None] = ((), None)   # the parts closed at the last look, their boxes

    def depths(self, positions: np.ndarray, radii: np.ndarray, half_heights: np.ndarray) -> np.ndarray:
        """How deep each upright cylinder reaches into the nearest closed part, m (−inf: none is closed)."""
        solid = tuple(b.solid for b in self.blockers)
        if solid != self._closed[0]:
            # Only the closed parts' boxes, kept until a part opens or closes: the same values as
            # every box's depths with the open ones set to −inf (bottling plant: 71 → 65 µs a look).
            closed = np.array(solid, bool)[self.owner]
            boxes = None
            if closed.any():
                boxes = Boxes()
                boxes.centers, boxes.half_extents = self.boxes.centers[closed], self.boxes.half_extents[closed]
                boxes.cos, boxes.sin = self.boxes.cos[closed], self.boxes.sin[closed]
            self._closed = (solid, boxes)
        boxes = self._closed[1]
        if boxes is None:
            return np.full(len(positions), -math.inf)
        return depths(boxes, positions, radii, half_heights).max(axis=0)


class TwoPositions(Component):
    """A component for one Blocker; subclasses name the slots (NAMES: role → slot name)."""

    NAMES: dict[str, str] = {}
    #: Whether the part, closed, holds bottles back on purpose (a stopper, a separator's gates):
    #: bottles queued at it stand still without being jammed (modules/plant/jams.py). A switch blade guides.
    HOLDS: bool = False

    STATE = ("_at", "blocker")

    def __init__(self, obj, name, blocker: Blocker):
        super().__init__(obj, name)
        self.blocker = blocker

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers by role, settled once: sense and actuate run at every point for every part.
        self._at = {role: index[name] for role, name in self.NAMES.items()}
        at = self._at
        self._states = (at["is_solid"], at["is_passable"], at["blocked"])
        self._commands = (at["level"], at["to_passable"], at["to_solid"])

    def sense(self, tick):
        b = self.blocker
        values, active = self.signals.values, self.signals.active
        if b.reached is not None:
            active[self._at["reached_solid"] if b.reached else self._at["reached_passable"]] = True
            b.reached = None
        settled = b.arrive is None
        solid, passable, blocked = self._states
        values[solid] = settled and b.solid
        values[passable] = settled and not b.target
        values[blocked] = b.waiting
        active[solid] = active[passable] = active[blocked] = True

    def actuate(self):
        b, updated = self.blocker, self.signals.updated
        level, to_passable, to_solid = self._commands
        if not (updated[level] or updated[to_passable] or updated[to_solid]):
            # No command, no move and no open waiting for the interlock: Blocker.actuate has
            # nothing to do (the case at most points for the bottling plant's 9 parts).
            if b.arrive is None and not b.held_open:
                return
            b.actuate(b.world.tick)
            return
        tick = b.world.tick
        if updated[level]:
            b.command(tick, self.signals.values[level])
        if updated[to_passable]:
            b.command(tick, False)
        if updated[to_solid]:
            b.command(tick, True)
        b.actuate(tick)


class Gate(TwoPositions):
    SLOTS = (
        Slot.target("open", "void", "open: let bottles pass"),
        Slot.target("close", "void", "close: block the belt (waits until no bottle is in the way)"),
        Slot.target("closed", "bool", "true closes, false opens (a level instead of two events)"),
        Slot.source("is_closed", "bool", "the gate is closed and blocks, every step"),
        Slot.source("is_open", "bool", "the gate is open, every step (both false while it moves)"),
        Slot.source("on_closed", "void", "the gate reached closed"),
        Slot.source("on_opened", "void", "the gate reached open"),
        Slot.source("blocked", "bool", "a close waits for a bottle to clear the gate, every step"),
    )
    NAMES = {"to_passable": "open", "to_solid": "close", "level": "closed", "is_solid": "is_closed",
             "is_passable": "is_open", "reached_solid": "on_closed", "reached_passable": "on_opened",
             "blocked": "blocked"}
    HOLDS = True


GATE_PARAMETERS = {
    "width": {"type": "number", "exclusiveMinimum": 0, "default": 0.1,
              "description": "clear width of the belt the gate closes, m"},
    "height": {"type": "number", "exclusiveMinimum": 0, "default": 0.08,
               "description": "gate height above the surface, m (above a bottle's contact ring at its centre of "
                              "mass, so it does not tip it)"},
    "thickness": {"type": "number", "exclusiveMinimum": 0, "default": 0.005, "description": "gate thickness along the belt, m"},
    "travel_time": {"type": "number", "minimum": 0, "default": 0.1, "description": "time to open or close, s"},
}


def gate_across(world, point, yaw: float, params: dict, closed: bool, push: float = 0.0) -> Blocker:
    """A gate from rail to rail standing across a belt at `point` (on its centre line, at its surface)."""
    x, y, z = point
    half = (params["thickness"] / 2, params["width"] / 2, params["height"] / 2)
    return Blocker(world, [(x, y, z + half[2])], [half], [yaw], closed, round(params["travel_time"] * world.rate), push)


def along(point, yaw_degrees: float, distance: float):
    """The point `distance` metres from `point` along a heading."""
    yaw = math.radians(yaw_degrees)
    return point[0] + distance * math.cos(yaw), point[1] + distance * math.sin(yaw), point[2]
