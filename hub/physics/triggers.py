"""Volume triggers: box tests on positions already read, latched across physics substeps."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from hub.core import state
from hub.physics.frames import Boxes
from hub.physics.grid import MARGIN, at_point, extents, grid_of


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

    STATE = ("boxes", "latches", "_inside", "_held", "_within", "_stayed", "_occupants", "shifted")   # boxes move with an arm's tool

    def __init__(self):
        self.boxes = Boxes()
        self.latches: list[Latch] = []
        self._inside = np.zeros((0, 0), bool)
        self._stayed = np.zeros(0, bool)      # per trigger: something was inside since the last take
        self._occupants = None                # per trigger: the bodies inside now, worked out once per change
        self.shifted: set[int] = set()        # boxes moved since the last evaluation (see `move`)
        self._held = np.zeros(0, np.int64)    # per trigger: the bodies inside it now
        self._within = np.zeros(0, np.int64)  # per body: the triggers it is inside now
        self._mobile: set[int] = set()        # triggers that have moved (`move`): not in the grid
        self._made = None                     # the grid and what it was made of (`_grid`)

    def __len__(self) -> int:
        return len(self.boxes)

    def add(self, center, half_extents, yaw: float) -> int:
        index = self.boxes.add(center, half_extents, yaw)
        self.latches.append(Latch())
        self._inside = np.zeros((len(self.boxes), self._inside.shape[1]), bool)
        self._held, self._within = np.zeros(len(self.boxes), np.int64), np.zeros(self._inside.shape[1], np.int64)
        self._made = None
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

        Runs at every tick: the bodies that moved, in one compiled loop, each tested against the
        triggers near it (`_moved`); after a park, an unpark or a body added, every body against
        every trigger (`_overlap`)."""
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
            grid, still, mobile = self._grid(radii)
            changes = _moved(self._inside, self._stayed, self._held, self._within, np.asarray(moved, np.int64), every,
                             shifted, positions, radii, half_heights, b.centers, b.half_extents, b.cos, b.sin, grid,
                             still, mobile)
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
        self._held, self._within = inside.sum(axis=1), inside.sum(axis=0)
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
        self._mobile.add(trigger)

    def _grid(self, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The grid (hub/physics/grid.py) of the triggers that never moved, each box widened by the
        widest body's radius (`reach`), with their numbers (the grid's boxes, in order), and the
        numbers of those that did (`_moved` tests these against every moved body). Made at the
        first tick that moves bodies, and again when a trigger is added or moves for the first
        time, when bodies are added, or after a restore (`restored`). Not state: it follows from
        the boxes."""
        made = self._made
        if made is None or made[0] != len(self._mobile) or made[1] != len(radii):
            b = self.boxes
            mobile = np.array(sorted(self._mobile), np.int64)
            still = np.setdiff1d(np.arange(len(self)), mobile)
            widest = reach(radii)
            widened = b.half_extents[still] + [widest, widest, 0.0]
            grid = grid_of(np.column_stack((b.centers[still], widened, b.cos[still], b.sin[still])))
            self._made = (len(self._mobile), len(radii), grid, still, mobile)
        return self._made[2:]

    def restored(self) -> None:
        """After a checkpoint is put back (hub/core/state.py): the grid is made again from the boxes."""
        self._made = None

    def take(self, trigger: int) -> Latch:
        """Hand over what the trigger latched and start a new latch with the current occupancy."""
        latch = self.latches[trigger]
        latch.stayed = bool(self._stayed[trigger])
        self._stayed[trigger] = False
        if self._occupants is None:
            # One pass over all triggers, reused by every take until the occupancy changes: a
            # plant takes each of its ~20 triggers at every communication point.
            occupants = [()] * len(self)
            for t in np.flatnonzero(self._held).tolist():
                occupants[t] = tuple(np.flatnonzero(self._inside[t]).tolist())
            self._occupants = occupants
        latch.inside = self._occupants[trigger]
        self.latches[trigger] = Latch()
        return latch


@njit(cache=True)
def reach(radii):
    """How far beyond a box a body may stand and still overlap it: the widest body's radius, and
    MARGIN against rounding."""
    return (radii.max() if radii.shape[0] else 0.0) + MARGIN


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
def _moved(inside, stayed, held, within, moved, every, shifted, positions, radii, half_heights, centers,
           half_extents, cos, sin, grid, still, mobile):
    """One tick's occupancy in place: each trigger against the `moved` bodies (the others keep
    theirs), or, if it was `shifted`, against `every` body in play; then whether anything is
    inside it now (`stayed`). The changes, (trigger, body, entered) each, trigger by trigger and
    within one the bodies that entered in body order, then those that left.

    `held` (per trigger) and `within` (per body) count the pairs inside, kept up to date here. A
    moved body is tested against the triggers it was inside, those `mobile` (moved with an arm's
    tool) and those of `still` its cell of `grid` lists (VolumeTriggers._grid: the others are too
    far to hold it); a shifted box against the bodies within its bounds: the result of testing
    every pair, without testing every pair of a hall. The changes come sorted, which is the order
    above because `moved` and `every` are ascending (bodies.py's rows, np.flatnonzero)."""
    n_bodies = inside.shape[1]
    keys = [np.int64(k) for k in range(0)]   # t·2N + n for an entry, t·2N + N + n for a leave
    widest = reach(radii)
    for t in range(inside.shape[0]):
        if shifted[t]:   # the box's bounds first: a body beyond them is not inside (and was not, or is tested)
            ex, ey = extents(cos[t], sin[t], half_extents[t, 0], half_extents[t, 1])
            for n in every:
                if inside[t, n] or (abs(positions[n, 0] - centers[t, 0]) <= ex + widest
                                    and abs(positions[n, 1] - centers[t, 1]) <= ey + widest):
                    _flip(keys, inside, held, within, t, n, positions, radii, half_heights, centers, half_extents,
                          cos, sin)
    held_now = np.flatnonzero(held)   # a body inside a trigger is inside one of these
    for n in moved:
        if within[n]:   # first the triggers it was inside: those it left
            for t in held_now:
                if inside[t, n] and not shifted[t]:
                    _flip(keys, inside, held, within, t, n, positions, radii, half_heights, centers, half_extents,
                          cos, sin)
        first, last = at_point(grid, positions[n, 0], positions[n, 1])
        for s in range(first, last):
            t = still[grid[s]]
            if not inside[t, n] and not shifted[t]:
                _flip(keys, inside, held, within, t, n, positions, radii, half_heights, centers, half_extents,
                      cos, sin)
        for t in mobile:
            if not inside[t, n] and not shifted[t]:
                _flip(keys, inside, held, within, t, n, positions, radii, half_heights, centers, half_extents,
                      cos, sin)
    for t in range(inside.shape[0]):
        if held[t]:
            stayed[t] = True
    keys.sort()
    out = np.empty((len(keys), 3), np.int64)
    for i in range(len(keys)):
        t, rest = divmod(keys[i], 2 * n_bodies)
        out[i, 0], out[i, 1], out[i, 2] = t, rest % n_bodies, 1 if rest < n_bodies else 0
    return out


@njit(cache=True)
def _flip(keys, inside, held, within, t, n, positions, radii, half_heights, centers, half_extents, cos, sin):
    """Test one pair (`_moved`); if its occupancy changed, set it, count it and add its key."""
    now = _inside(positions[n, 0], positions[n, 1], positions[n, 2], radii[n], half_heights[n],
                  centers[t, 0], centers[t, 1], centers[t, 2], half_extents[t, 0], half_extents[t, 1],
                  half_extents[t, 2], cos[t], sin[t])
    if now != inside[t, n]:
        inside[t, n] = now
        change = 1 if now else -1
        held[t] += change
        within[n] += change
        n_bodies = inside.shape[1]
        keys.append(np.int64(t * 2 * n_bodies + (n if now else n_bodies + n)))
