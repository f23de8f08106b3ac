"""Bodies at rest: which bottles the engine may leave asleep, and which must wake before a tick.

Bullet stops integrating a body that sleeps, and solves nothing for an island of sleeping
bodies: 81 bottles standing in the bottling plant's stopped magazine cost the engine 1150–1240
µs per tick awake and 480 asleep. Bullet's own rule (slower than 0.8 m/s for 2 s) would put a
bottle riding a belt to sleep — the belt is a force planthub applies, which wakes nothing — so
every body is created with sleeping disabled and the hub decides, from the state it reads at
every tick anyway:

- A body may rest when it has been still (speed under `speed`, spin under `spin`, looked at
  every `every` ticks) for `after` seconds where nothing drives it — on no belt, or on a belt
  standing still — or for HELD_AFTER held still against a running belt (pressed at a closed
  gate or in a queue: resting at once, a bottle kept 0.2 mm of the engine's penetration into
  the gate, which 0.3 s more pressing takes to 0.02; tests/hard/test_tunnelling.py), and is not
  held by an arm, and when its box overlaps no awake body's box (see below; one left awake for
  that tries again `retry` ticks later).
- A resting body is not read, driven or tested at any tick; its last pose stays in the state
  arrays and its velocity is zero, which is what the engine holds for a sleeping body.
- It wakes when its belt's speed changes, when a switchable part overlapping it turns solid or
  void, when an arm grips it, and when an awake body comes near.

"Near" follows Bullet's own rule exactly enough to be safe: Bullet wakes a sleeping body at a
tick when its island — bodies joined by overlapping bounding boxes, each widened by the contact
breaking threshold — holds an awake one. The hub widens the same boxes a little more (for
the shapes' collision margins) and wakes the whole group of resting bodies whose boxes join
an awake body's, before the engine steps. A resting body is also out of the engine's collision
world (Engine.leave: a sleeping body in contact still cost the engine its pairs), so a wake
that came too late would let an awake body pass into it: `PhysicsWorld.check_rest` asks the
engine at every tick that each resting body is where the hub left it and that no awake body
or moving part touches it (tests/physics/test_rest.py, test_moving.py, and every run of
tests/plant_watch.py, the bottling plant's among them).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

HELD_AFTER = 0.3       # s a bottle held still on a running belt stands before it rests (see Rest.candidates)
BREAKING = 0.02        # m: Bullet widens every box by its contact breaking threshold before the pair search
SHAPE_MARGIN = 0.002   # m: for the shapes' collision margins (the boxes hold the engine's within 3 mm, tested)


def _quadratic_forms() -> np.ndarray:
    """(16, 9): the rotation matrix of a unit quaternion q = (x, y, z, w), row by row, as
    linear forms of the products qₐ·q_b: R = (q ⊗ q).reshape(16) @ this."""
    x, y, z, w = range(4)
    forms = np.zeros((4, 4, 9))
    terms = {0: [(w, w, 1), (x, x, 1), (y, y, -1), (z, z, -1)], 1: [(x, y, 2), (w, z, -2)],
             2: [(x, z, 2), (w, y, 2)], 3: [(x, y, 2), (w, z, 2)],
             4: [(w, w, 1), (x, x, -1), (y, y, 1), (z, z, -1)], 5: [(y, z, 2), (w, x, -2)],
             6: [(x, z, 2), (w, y, -2)], 7: [(y, z, 2), (w, x, 2)],
             8: [(w, w, 1), (x, x, -1), (y, y, -1), (z, z, 1)]}
    for entry, products in terms.items():
        for a, b, k in products:
            forms[a, b, entry] += k
    return forms.reshape(16, 9)


_ROTATION = _quadratic_forms()


def boxes(orientations: np.ndarray, radii: np.ndarray, half_heights: np.ndarray,
          velocities: np.ndarray | None = None, spins: np.ndarray | None = None, dt: float = 0.0) -> np.ndarray:
    """Half extents (N,3) of each bottle's box about its centre of mass as the engine pairs it.

    Bullet bounds a shape by its local box — (r, r, h) for a cylinder of radius r and half
    height h, or for the bottle's cylinder with its widest ring — turned into the world: half
    extent i is Σⱼ |Rᵢⱼ|·lⱼ, so a bottle turned 45° about its axis has a box 41 % wider than
    itself. Then margins and the breaking threshold. A moving body's box also covers where it
    is headed in the next tick (Bullet joins the box at the pose predicted from the velocity):
    |vᵢ|·dt, and the turn of its farthest point, |ω|·√(2r² + h²)·dt, both ways."""
    q = np.asarray(orientations, float)
    rotation = np.abs((q[:, :, None] * q[:, None, :]).reshape(-1, 16) @ _ROTATION).reshape(-1, 3, 3)
    local = np.stack((radii, radii, half_heights), axis=1)
    extents = np.einsum("nij,nj->ni", rotation, local) + (SHAPE_MARGIN + BREAKING)
    if velocities is not None:
        extents += (np.abs(velocities) + swing(radii, half_heights, spins)[:, None]) * dt
    return extents


def swing(radii, half_heights, spins) -> np.ndarray:
    """(N,): how fast a bottle's farthest point from its centre of mass moves as it turns, m/s
    (|ω|·√(2r² + h²), at most: a corner of its box)."""
    return np.sqrt((spins * spins).sum(axis=1) * (2.0 * radii * radii + half_heights * half_heights))


def overlapping(centres_a, extents_a, centres_b, extents_b) -> np.ndarray:
    """(A, B): whether each box of a overlaps each box of b."""
    gap = np.abs(centres_a[:, None, :] - centres_b[None, :, :]) - extents_a[:, None, :] - extents_b[None, :, :]
    return (gap < 0.0).all(axis=2)


@njit(cache=True)
def bound(r, h, v, w, horizon, margin):
    """A half extent that holds `boxes` of one upright body (radius r, half height h, velocity v,
    spin w) on every axis in any orientation, headed `horizon` s: Σⱼ |Rᵢⱼ|·lⱼ is at most |l|
    (Cauchy–Schwarz on a row of a rotation), and |vᵢ| at most |v|. The test that comes first."""
    size = math.sqrt(2.0 * r * r + h * h)
    return size + margin + (math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + turning(r, h, w)) * horizon


@njit(cache=True)
def turning(r, h, w):
    """`swing` for one body: how fast its farthest point moves as it turns at spin w, m/s."""
    return math.sqrt((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * (2.0 * r * r + h * h))


class Rest:
    """Still-time counters and the resting set of a world's bodies, in body order (numpy only).

    The methods take the world's state arrays (positions, orientations, velocities, spins) as
    they are after the last read; a resting body's entries stand while it rests."""

    STATE = ("still", "resting", "extents", "fields", "_at_rest")   # hub/core/state.py

    def __init__(self, rate: int, after: float = 0.05, speed: float = 0.005, spin: float = 0.05):
        self.ticks = max(1, round(after * rate)) if after > 0 else 0   # 0: nothing ever rests
        self.held_ticks = max(self.ticks, round(HELD_AFTER * rate))     # still this long when held on a running belt
        self.retry = max(1, round(0.1 * rate))   # ticks between two tries of a still body left awake (0.1 s)
        self.every = max(1, min(3, self.ticks))    # ticks between two looks for still bodies
        self.dt = 1.0 / rate
        self._speed2, self._spin2 = speed * speed, spin * spin
        self.allowed = np.zeros(0, bool)       # the body's kind may rest (a plain rigid bottle)
        self.radii = np.zeros(0)
        self.half_heights = np.zeros(0)
        self.still = np.zeros(0, int)          # ticks it has been still where nothing drives it
        self.resting = np.zeros(0, bool)
        self.extents = np.zeros((0, 3))        # box half extents of resting bodies, fixed while they rest
        self.fields = np.zeros(0, int)         # the belt each resting body stands on (−1: none)
        self._at_rest = None                   # (rows, centres, extents) of the resting set, until it changes

    @property
    def enabled(self) -> bool:
        return self.ticks > 0

    def add(self, allowed: bool, radius: float, half_height: float) -> None:
        self.allowed = np.append(self.allowed, allowed and self.enabled)
        self.radii = np.append(self.radii, radius)
        self.half_heights = np.append(self.half_heights, half_height)
        self.still = np.append(self.still, 0)
        self.resting = np.append(self.resting, False)
        self.extents = np.vstack((self.extents, np.zeros((1, 3))))
        self.fields = np.append(self.fields, -1)

    def rows(self) -> np.ndarray:
        return self._resting_set(None)[0]

    def _resting_set(self, positions):
        if self._at_rest is None:
            rows = np.flatnonzero(self.resting)
            self._at_rest = (rows, None, self.extents[rows])
        if self._at_rest[1] is None and positions is not None:
            rows, _, extents = self._at_rest
            self._at_rest = (rows, positions[rows], extents)
        return self._at_rest

    def boxes(self, rows, orientations, velocities=None, spins=None) -> np.ndarray:
        if velocities is None:
            return boxes(orientations[rows], self.radii[rows], self.half_heights[rows])
        return boxes(orientations[rows], self.radii[rows], self.half_heights[rows], velocities[rows], spins[rows],
                     self.dt)

    def candidates(self, rows: np.ndarray, field: np.ndarray, speeds: np.ndarray, gripped: np.ndarray,
                   velocities: np.ndarray, spins: np.ndarray) -> np.ndarray:
        """A look at the awake `rows` (`field`: the belt under each, −1 none; `speeds`: the
        belts'; `gripped`: per body, held by an arm, never resting), one every `every` ticks: a
        body still at this look counts `every` more still ticks, one that moves starts from
        zero. The rows that have now been still long enough to rest: `after` where nothing
        drives them (no belt, or one standing still), `held_after` held still against a running
        belt. All that are due go together (a queue whose bottles came to rest a tick apart rests
        as one group), when one has just become due or one left awake is due to try again. One
        compiled loop (`_candidates`)."""
        return _candidates(np.asarray(rows, np.int64), np.asarray(field, np.int64), speeds, gripped, velocities,
                           spins, self.allowed, self.still, self.every, self.ticks, self.held_ticks, self.retry,
                           self._speed2, self._spin2)

    def settle(self, candidates: np.ndarray, awake: np.ndarray, positions, orientations, velocities,
               spins) -> np.ndarray:
        """Of the candidates, those whose boxes join no box of a body that stays awake: a body
        that would be woken at once is left awake, to try again `retry` ticks later."""
        others = np.setdiff1d(awake, candidates, assume_unique=True)
        extents = self.boxes(candidates, orientations)
        keep = np.ones(len(candidates), bool)
        near = self._near(positions[candidates], extents, others, positions, velocities, spins)
        blockers_p = positions[near]
        blockers_e = self.boxes(near, orientations, velocities, spins)
        while len(blockers_p):
            hit = overlapping(positions[candidates], extents, blockers_p, blockers_e).any(axis=1) & keep
            if not hit.any():
                break
            keep &= ~hit          # a candidate left awake blocks those that join it in turn
            blockers_p, blockers_e = positions[candidates[hit]], extents[hit]
        return candidates[keep]

    def _near(self, centres, extents, awake, positions, velocities, spins) -> np.ndarray:
        """The awake rows whose bound comes within the boxes (centres, extents)."""
        if len(awake) == 0 or len(centres) == 0:
            return awake[:0]
        return awake[_within(awake, positions, velocities, spins, self.radii, self.half_heights, self.dt,
                             np.ascontiguousarray(centres), np.ascontiguousarray(extents))]

    def put(self, rows: np.ndarray, orientations, fields: np.ndarray) -> None:
        self.resting[rows] = True
        self.extents[rows] = self.boxes(rows, orientations)
        self.fields[rows] = fields
        self._at_rest = None

    def woken_by(self, awake: np.ndarray, positions, orientations, velocities, spins) -> np.ndarray:
        """The resting rows whose boxes join an awake body's, directly or through other resting
        boxes (the island Bullet would wake). The awake bodies' bounds first, their boxes only
        where a bound reaches a resting box."""
        resting, centres, extents = self._resting_set(positions)
        if len(resting) == 0 or len(awake) == 0:
            return resting[:0]
        return resting[_woken(np.asarray(awake, np.int64), positions, orientations, velocities, spins, self.radii,
                              self.half_heights, self.dt, np.ascontiguousarray(centres), extents)]

    def joining(self, centres, extents, positions) -> np.ndarray:
        """The resting rows (and their groups) whose boxes overlap any of the boxes (centres, extents)."""
        resting, rest_centres, rest_extents = self._resting_set(positions)
        if len(resting) == 0:
            return resting
        seeds = overlapping(rest_centres, rest_extents, np.asarray(centres, float), np.asarray(extents, float)).any(axis=1)
        return self._group(seeds, positions) if seeds.any() else resting[:0]

    def on_field(self, field: int, positions) -> np.ndarray:
        """The resting rows standing on `field`, with their groups."""
        resting = self._resting_set(positions)[0]
        seeds = self.fields[resting] == field
        return self._group(seeds, positions) if seeds.any() else resting[:0]

    def _group(self, seeds: np.ndarray, positions) -> np.ndarray:
        # Outwards from the seeds, the newly joined against every resting box: the cost grows with
        # the group, not with the square of the resting set (a hall's thousand resting bottles).
        resting, centres, extents = self._resting_set(positions)
        woken = seeds.copy()
        frontier = seeds
        while frontier.any():
            frontier = overlapping(centres[frontier], extents[frontier], centres, extents).any(axis=0) & ~woken
            woken |= frontier
        return resting[woken]

    def wake(self, rows: np.ndarray) -> None:
        self.resting[rows] = False
        self.still[rows] = 0
        self._at_rest = None

    def forget(self, row: int) -> None:
        """The body left play or was moved by the plant: not resting, its still time from zero."""
        if self.resting[row]:
            self._at_rest = None
        self.resting[row] = False
        self.still[row] = 0


@njit(cache=True)
def _candidates(rows, field, speeds, gripped, velocities, spins, allowed, still, every, ticks, held_ticks, retry,
                speed2, spin2):
    """Rest.candidates, row by row (`still` counted in place)."""
    due = np.zeros(rows.shape[0], np.bool_)
    fresh = False
    for i in range(rows.shape[0]):
        n, k = rows[i], field[i]
        undriven = k < 0 or speeds[k] == 0.0
        v, w = velocities[n], spins[n]
        count = 0
        if (not gripped[n] and allowed[n] and v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < speed2
                and w[0] * w[0] + w[1] * w[1] + w[2] * w[2] < spin2):
            count = still[n] + every
        still[n] = count
        need = ticks if undriven else held_ticks
        if count >= need:
            due[i] = True
            fresh = fresh or (count - need) % retry < every
    return rows[due] if fresh else rows[:0]


@njit(cache=True)
def _within(rows, positions, velocities, spins, radii, half_heights, dt, centres, extents):
    """(len(rows),): whether each body's bound (`bound`: its size, margins and one tick's way)
    comes within any of the boxes (centres, extents) on every axis — the first box around all
    of them, then box by box."""
    near = np.zeros(rows.shape[0], np.bool_)
    if centres.shape[0] == 0:
        return near
    lo, hi = centres[0] - extents[0], centres[0] + extents[0]
    for m in range(1, centres.shape[0]):
        for a in range(3):
            lo[a] = min(lo[a], centres[m, a] - extents[m, a])
            hi[a] = max(hi[a], centres[m, a] + extents[m, a])
    for i in range(rows.shape[0]):
        n = rows[i]
        reach = bound(radii[n], half_heights[n], velocities[n], spins[n], dt, SHAPE_MARGIN + BREAKING)
        p = positions[n]
        if not (p[0] + reach > lo[0] and p[0] - reach < hi[0] and p[1] + reach > lo[1] and p[1] - reach < hi[1]
                and p[2] + reach > lo[2] and p[2] - reach < hi[2]):
            continue
        for m in range(centres.shape[0]):
            if (abs(p[0] - centres[m, 0]) - extents[m, 0] < reach and abs(p[1] - centres[m, 1]) - extents[m, 1] < reach
                    and abs(p[2] - centres[m, 2]) - extents[m, 2] < reach):
                near[i] = True
                break
    return near


@njit(cache=True)
def _woken(awake, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents):
    """Rest.woken_by in one call, over the resting boxes (centres, extents): the awake bodies
    whose bound comes near one (`_within`), the resting boxes their boxes overlap (`_seeds`), and
    every resting box joined to one of those through resting boxes that overlap in turn."""
    near = awake[_within(awake, positions, velocities, spins, radii, half_heights, dt, centres, extents)]
    woken = _seeds(near, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents)
    stack = [m for m in range(centres.shape[0]) if woken[m]]
    while stack:
        m = stack.pop()
        for k in range(centres.shape[0]):
            if (not woken[k] and abs(centres[m, 0] - centres[k, 0]) - extents[m, 0] - extents[k, 0] < 0.0
                    and abs(centres[m, 1] - centres[k, 1]) - extents[m, 1] - extents[k, 1] < 0.0
                    and abs(centres[m, 2] - centres[k, 2]) - extents[m, 2] - extents[k, 2] < 0.0):
                woken[k] = True
                stack.append(k)
    return woken


@njit(cache=True)
def _seeds(rows, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents):
    """(len(centres),): which resting boxes (centres, extents) the box of any of `rows` (`boxes`,
    headed one tick) overlaps."""
    seeds = np.zeros(centres.shape[0], np.bool_)
    for n in rows:
        box = np.empty(3)
        for axis in range(3):
            box[axis] = extent(orientations[n], radii[n], half_heights[n], velocities[n], spins[n], dt, axis,
                               SHAPE_MARGIN + BREAKING)
        for m in range(centres.shape[0]):
            if (abs(positions[n, 0] - centres[m, 0]) < box[0] + extents[m, 0]
                    and abs(positions[n, 1] - centres[m, 1]) < box[1] + extents[m, 1]
                    and abs(positions[n, 2] - centres[m, 2]) < box[2] + extents[m, 2]):
                seeds[m] = True
    return seeds


@njit(cache=True)
def extent(q, r, h, v, w, horizon, axis, margin):
    """`boxes` for one upright body (quaternion q, radius r, half height h) on one axis: Σⱼ |Rᵢⱼ|·lⱼ
    turned into the world, `margin`, and its way over `horizon` s at velocity v and spin w, both ways."""
    x, y, z, s = q[0], q[1], q[2], q[3]
    if axis == 0:
        a, b, c = s * s + x * x - y * y - z * z, 2.0 * (x * y - s * z), 2.0 * (x * z + s * y)
    elif axis == 1:
        a, b, c = 2.0 * (x * y + s * z), s * s - x * x + y * y - z * z, 2.0 * (y * z - s * x)
    else:
        a, b, c = 2.0 * (x * z - s * y), 2.0 * (y * z + s * x), s * s - x * x - y * y + z * z
    return abs(a) * r + abs(b) * r + abs(c) * h + margin + (abs(v[axis]) + turning(r, h, w)) * horizon
