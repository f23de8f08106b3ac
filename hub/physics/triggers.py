"""Volume triggers: box tests on positions already read, latched across physics substeps."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from hub.core import state
from hub.physics.frames import Boxes


@state.value   # taken and replaced at each point: saved whole
@dataclass
class Latch:
    """What one trigger saw since it was last taken: (tick, body) enters and leaves, in order."""

    STATE = ("entered", "left", "stayed", "inside")   # hub/core/state.py

    entered: list[tuple[int, int]] = field(default_factory=list)
    left: list[tuple[int, int]] = field(default_factory=list)
    stayed: bool = False          # something was inside at some tick
    inside: tuple[int, ...] = ()  # bodies inside at the latest tick, in body order


class VolumeTriggers:
    """Box volumes that report upright cylinders (radius r, half height hz) overlapping them.

    The test is exact for an upright cylinder against a yawed box: in the box frame the
    horizontal distance from the axis to the box must be at most r and the vertical extents
    must overlap. Each evaluation compares with the previous tick, so an object that enters
    and leaves between two communication points still produces both events.
    """

    STATE = ("boxes", "latches", "_inside", "_stayed", "_occupants", "shifted")   # boxes move with an arm's tool

    def __init__(self):
        self.boxes = Boxes()
        self.latches: list[Latch] = []
        self._inside = np.zeros((0, 0), bool)
        self._stayed = np.zeros(0, bool)      # per trigger: something was inside since the last take
        self._occupants = None                # per trigger: the bodies inside now, worked out once per change
        self.shifted: set[int] = set()        # boxes moved since the last evaluation (see `move`)

    def __len__(self) -> int:
        return len(self.boxes)

    def add(self, center, half_extents, yaw: float) -> int:
        index = self.boxes.add(center, half_extents, yaw)
        self.latches.append(Latch())
        self._inside = np.zeros((len(self.boxes), self._inside.shape[1]), bool)
        self._stayed = np.append(self._stayed, False)
        self._occupants = None
        return index

    def jumpable(self, step: float, radii: np.ndarray) -> list[str]:
        """The triggers a bottle could cross between two ticks unseen, moving `step` m per tick
        (the fastest belt's speed × dt): the test samples positions at ticks, so a box thinner
        than the step less the thinnest bottle's diameter lets one jump it (a light barrier 5 mm
        deep misses a 6 cm bottle above 9.75 m/s at 150 Hz). Reported at load, not fixed."""
        if len(self) == 0 or not len(radii) or step <= 0:
            return []
        diameter = 2.0 * float(np.min(radii))
        depth = 2.0 * self.boxes.half_extents[:, :2].min(1)
        out = []
        for t in np.flatnonzero(step > depth + diameter):
            c = ", ".join(f"{x:.3f}" for x in self.boxes.centers[t])
            out.append(f"trigger {int(t)} at ({c}) m is {depth[t] * 1000:.1f} mm deep: a bottle of "
                       f"{diameter * 1000:.0f} mm moving {step * 1000:.1f} mm per tick (the fastest belt) can "
                       "cross it between two ticks unseen; make it deeper or the physics rate higher")
        return out

    def evaluate(self, tick: int, positions: np.ndarray, radii: np.ndarray, half_heights: np.ndarray,
                 rows: np.ndarray | None = None, moved: np.ndarray | None = None) -> bool:
        """Compare occupancy with the previous tick and latch the changes; True if there was one.
        `rows`: the bodies that can be inside anything (the others, parked off stage, are not).
        `moved`: the only bodies that can have moved since the last evaluation (the others, at
        rest, keep their occupancy); None: any of `rows`.

        Runs at every tick: the test is one compiled loop over (triggers, bodies) (`_overlap`)."""
        if len(self) == 0:
            return False
        if moved is not None and self._inside.shape == (len(self), len(positions)):
            # The common tick: only the bodies that moved, compared and latched in one compiled loop;
            # a box that moved (with an arm's tool) against every body in play.
            b = self.boxes
            shifted = np.zeros(len(self), np.bool_)
            if self.shifted:
                shifted[sorted(self.shifted)] = True
                self.shifted.clear()
            every = np.arange(len(positions)) if rows is None else np.asarray(rows, np.int64)
            changes = _moved(self._inside, self._stayed, np.asarray(moved, np.int64), every, shifted, positions, radii,
                             half_heights, b.centers, b.half_extents, b.cos, b.sin)
            if len(changes) == 0:
                return False
            self._occupants = None
            for t, n, entered in changes.tolist():
                (self.latches[t].entered if entered else self.latches[t].left).append((tick, n))
            return True
        if rows is not None:
            inside = np.zeros((len(self), len(positions)), bool)
            inside[:, rows] = self._test(positions[rows], radii[rows], half_heights[rows])
        else:
            inside = self._test(positions, radii, half_heights)
        self.shifted.clear()
        previous = self._inside
        self._inside = inside
        self._stayed |= inside.any(axis=1)
        if previous.shape != inside.shape:
            previous = np.zeros_like(inside)
        elif np.array_equal(inside, previous):
            return False
        self._occupants = None
        changed = inside != previous
        if not changed.any():
            return False
        for t, n in zip(*np.nonzero(changed & inside)):
            self.latches[t].entered.append((tick, int(n)))
        for t, n in zip(*np.nonzero(changed & previous)):
            self.latches[t].left.append((tick, int(n)))
        return True

    def _test(self, positions, radii, half_heights) -> np.ndarray:
        """(triggers, bodies): whether each upright cylinder overlaps each box."""
        b = self.boxes
        return _overlap(np.ascontiguousarray(positions, float), np.ascontiguousarray(radii, float),
                        np.ascontiguousarray(half_heights, float), b.centers, b.half_extents, b.cos, b.sin)

    def occupied(self) -> np.ndarray:
        """Per trigger: whether a body is inside at the last evaluation."""
        inside = self._inside
        return inside.any(axis=1) if inside.shape[0] == len(self) else np.zeros(len(self), bool)

    def move(self, trigger: int, center) -> None:
        """Put a box's centre elsewhere (a gripper's trigger follows the tool)."""
        self.boxes.centers[trigger] = center
        self.shifted.add(trigger)

    def take(self, trigger: int) -> Latch:
        """Hand over what the trigger latched and start a new latch with the current occupancy."""
        latch = self.latches[trigger]
        latch.stayed = bool(self._stayed[trigger])
        self._stayed[trigger] = False
        if self._occupants is None:
            # One pass over all triggers, reused by every take until the occupancy changes: a
            # plant takes each of its ~20 triggers at every communication point.
            occupants = [[] for _ in range(len(self))]
            for t, n in zip(*(a.tolist() for a in np.nonzero(self._inside))):
                occupants[t].append(n)
            self._occupants = [tuple(o) for o in occupants]
        latch.inside = self._occupants[trigger]
        self.latches[trigger] = Latch()
        return latch


@njit(cache=True)
def _overlap(positions, radii, half_heights, centers, half_extents, cos, sin):
    """(boxes, bodies): whether each upright cylinder (centre, radius, half height) overlaps each
    yawed box (`_inside`)."""
    out = np.zeros((centers.shape[0], positions.shape[0]), np.bool_)
    for t in range(centers.shape[0]):
        cx, cy, cz = centers[t, 0], centers[t, 1], centers[t, 2]
        hx, hy, hz = half_extents[t, 0], half_extents[t, 1], half_extents[t, 2]
        c, s = cos[t], sin[t]
        for n in range(positions.shape[0]):
            out[t, n] = _inside(positions[n, 0], positions[n, 1], positions[n, 2], radii[n], half_heights[n],
                                cx, cy, cz, hx, hy, hz, c, s)
    return out


@njit(cache=True)
def _inside(px, py, pz, r, h, cx, cy, cz, hx, hy, hz, c, s):
    """Whether the upright cylinder about (px, py, pz) (radius r, half height h) overlaps the box
    (centre, half extents, cos and sin of its yaw; scalars, not rows, at a call per pair): in the
    box's frame the horizontal distance from its axis to the box at most r, and the heights
    overlapping."""
    dx, dy = px - cx, py - cy
    gx = max(abs(c * dx + s * dy) - hx, 0.0)
    gy = max(abs(c * dy - s * dx) - hy, 0.0)
    return gx * gx + gy * gy <= r * r and abs(pz - cz) <= hz + h


@njit(cache=True)
def _moved(inside, stayed, moved, every, shifted, positions, radii, half_heights, centers, half_extents, cos, sin):
    """One tick's occupancy in place: each trigger against the `moved` bodies (the others keep
    theirs), or, if it was `shifted`, against `every` body in play; then whether anything is
    inside it now (`stayed`). The changes, (trigger, body, entered) each, trigger by trigger and
    within one the bodies that entered in body order, then those that left."""
    changes = []
    for t in range(inside.shape[0]):
        cx, cy, cz = centers[t, 0], centers[t, 1], centers[t, 2]
        hx, hy, hz = half_extents[t, 0], half_extents[t, 1], half_extents[t, 2]
        c, s = cos[t], sin[t]
        left = []
        for n in (every if shifted[t] else moved):
            now = _inside(positions[n, 0], positions[n, 1], positions[n, 2], radii[n], half_heights[n],
                          cx, cy, cz, hx, hy, hz, c, s)
            if now != inside[t, n]:
                inside[t, n] = now
                if now:
                    changes.append((t, n, 1))
                else:
                    left.append((t, n, 0))
        for change in left:
            changes.append(change)
        for n in range(inside.shape[1]):
            if inside[t, n]:
                stayed[t] = True
                break
    return np.array(changes, np.int64).reshape(-1, 3) if changes else np.zeros((0, 3), np.int64)
