"""Free transport: a bottle riding a belt that nothing can touch leaves the engine and follows its belt's law in numpy.

A bottle carried by a belt, clear of every other body, rail, gate and belt end, costs the
engine its contacts with the floor and the hub two state reads and a force per tick, and all
the engine adds to what the belt's law gives it is a rocking of ~0.5° and a sink of ~2 mm into
the floor. In free transport the hub moves it itself, all such bottles at once: per tick the
velocity change the field would make the engine apply (ForceFields.changes_at: the exact
relaxation on a straight, the same in the rotating surface's frame on a curve, the capped law
with `friction:`), then the engine's own position step, x ← x + v·dt (Bullet's semi-implicit
Euler). On a frictionless floor nothing else acts on it horizontally, so a free bottle moves as
the engine would move it without contacts, to rounding; its height, orientation and the sink
it had stay as they were when it left, its vertical velocity and spin are zero.

In the engine a free bottle is out of play as a parked one is (parking.py): collision off, asleep,
its pose there stale. It re-enters — its exact pose and velocity put back, collision on, awake —
before the tick at which anything could touch it. "Anything" by three tests, each looking
`ahead` ticks forward (the bottle's `lookahead`, default 4) and taken every `ahead − 1` ticks —
at once after a bottle was put down, while a moving part is under way and after a belt changed
its speed:

- bodies: every other body in play (awake, resting, free, just put down). Two steady bottles
  (free, or upright and steady in the engine) by their footprints — the gap between them against
  what their relative velocity, their rocking and the belt's pull can close — so that a line of
  bottles 2 cm apart rides free; any other pair by the wake rule's boxes (rest.py: margins, the
  contact breaking threshold, and where each is headed), each headed `ahead` ticks instead of
  one; a moving part's box likewise;
- fixed geometry: rails and walls, gates and blades whether solid or not, and the spheres robot
  arms reach: the distance of its way ahead (a segment at its velocity) from each box listed
  within LIST of it, against its radius, FIXED_MARGIN and what the belt's pull may add;
- the belt: the point it is headed to lies on a belt at the same height (a hand-over between
  chained belts is crossed free: the field under it is looked up at every tick, half-open as
  the engine-driven bottle's is), and it is not coming to a stop on a still belt (there it
  re-enters, to rest).

A bottle leaves only when it rides a belt upright and steady (tilt under 1°, spin under 2.5
rad/s, vertical speed under 2 cm/s, its base within 5 mm of the surface) and passes the same
tests `2·ahead` ticks forward, so that one at the edge does not go in and out every tick.
Bottles made with `transport: engine`, the paper's two-body model and hull bottles stay in the
engine. `check` (PhysicsWorld.check_free, tests) asks the engine itself at every tick whether
a free bottle, at its pose, touches anything but the floor.
"""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.rest import SHAPE_MARGIN, bounds, boxes, overlapping, swing

with quiet_stderr():
    import pybullet

TILT = 0.0175         # rad (1°): most tilt a bottle may leave the engine with
SPIN = 2.5            # rad/s: most spin (a rocking bottle on a belt: up to 1.7)
RISE = 0.02           # m/s: most vertical speed
SINK = 0.005          # m: most distance between its base and the belt's surface
STILL = 0.005         # m/s: on a still belt a bottle slower than this re-enters, to rest
FIXED_MARGIN = SHAPE_MARGIN + 0.001   # m a free bottle keeps from fixed geometry beyond its travel
LOOKAHEAD = 4         # ticks a free bottle's tests look forward, by default
RETRY = 15            # ticks before a bottle found near something is looked at again
LIST = 0.1            # m: the fixed boxes within this of a free bottle are the ones it is tested against


class FreeTransport:
    """The free set of a world's bodies and the tests that take bottles out of and back into the engine."""

    def __init__(self, engine, bodies, fields, dt: float):
        self.engine = engine
        self.bodies = bodies
        self.fields = fields
        self.dt = dt
        self.ahead = np.zeros(0)            # per body: the ticks its tests look forward
        self.allowed = np.zeros(0, bool)    # the bottle's kind and its `transport:` let it go free
        self.free = np.zeros(0, bool)
        self.enabled = False                # some bottle may ride free
        self.listed_at = np.zeros((0, 2))   # where each bottle's fixed boxes were listed (x, y)
        self._pair_row = np.zeros(0, int)   # (bottle, fixed box) pairs within LIST: the boxes each may reach
        self._pair_box = np.zeros(0, int)
        self.rows = np.zeros(0, int)        # the free rows, in body order
        self.pull = np.zeros(0)             # per body: the velocity change the belt gave it at the last tick, m/s
        self._handed = None                 # this tick's (rows, dvx, dvy) from Bottles.drive
        self.due = 0                        # the tick at which the free bottles are looked at next
        self.next_try = np.zeros(0, int)    # per body: the tick from which it may be looked at to go free
        self.entered = 0                    # how many times a bottle left the engine (for figures)
        self.left = 0                       # and came back
        self._fixed = None                  # (centres, half extents, cos, sin) of fixed boxes
        self._spheres = (np.zeros((0, 3)), np.zeros(0))
        self._moving = None                 # MovingParts, tested at every look (their boxes move)
        self._probes: dict[int, int] = {}   # body row → collision shape, for `check`

    def add(self, allowed: bool, ahead: int = LOOKAHEAD) -> None:
        if not (isinstance(ahead, int) and ahead >= 2):
            raise ValueError(f"the look-ahead must be a whole number of ticks, at least 2, not {ahead!r}")
        self.ahead = np.append(self.ahead, float(ahead))
        self.allowed = np.append(self.allowed, allowed)
        self.enabled = self.enabled or bool(allowed)
        self.free = np.append(self.free, False)
        self.listed_at = np.vstack((self.listed_at, np.full((1, 2), np.inf)))
        self.pull = np.append(self.pull, 0.0)
        self.next_try = np.append(self.next_try, 0)

    def arm(self, fixed_boxes, spheres, moving) -> None:
        """At the start: the fixed geometry a free bottle keeps clear of — boxes (centre, half
        extents, yaw) of rails, walls, gates and blades, not the floors — the spheres robot arms
        reach (centre, radius), and the moving parts."""
        if fixed_boxes:
            c = np.array([b[0] for b in fixed_boxes], float)
            h = np.array([b[1] for b in fixed_boxes], float)
            yaw = np.array([b[2] for b in fixed_boxes], float)
            self._fixed = (c, h, np.cos(yaw), np.sin(yaw))
        if spheres:
            self._spheres = (np.array([s[0] for s in spheres], float), np.array([s[1] for s in spheres], float))
        self._moving = moving

    # --- the tests ------------------------------------------------------------------------
    def _gaps(self, points, radii, half_heights) -> np.ndarray:
        """(N, boxes): how far each upright bottle's footprint at `points` is from each fixed box
        (negative: into it); inf where they are apart in height."""
        c, h, cos, sin = self._fixed
        dx = points[:, 0, None] - c[None, :, 0]
        dy = points[:, 1, None] - c[None, :, 1]
        gx = np.maximum(np.abs(cos * dx + sin * dy) - h[:, 0], 0.0)
        gy = np.maximum(np.abs(cos * dy - sin * dx) - h[:, 1], 0.0)
        apart = np.abs(points[:, 2, None] - c[None, :, 2]) > h[:, 2] + half_heights[:, None] + FIXED_MARGIN
        return np.where(apart, np.inf, np.hypot(gx, gy) - radii[:, None])

    def _list(self, rows, positions) -> None:
        """Note for each of `rows` the fixed boxes within LIST of it (the only ones it can reach
        before it has moved LIST/2 and is listed again)."""
        b = self.bodies
        keep = ~np.isin(self._pair_row, rows)
        self._pair_row, self._pair_box = self._pair_row[keep], self._pair_box[keep]
        self.listed_at[rows] = positions[rows, :2]
        if self._fixed is None:
            return
        near = self._gaps(positions[rows], b.radii[rows], b.half_heights[rows]) < LIST
        r, k = np.nonzero(near)
        self._pair_row = np.concatenate([self._pair_row, rows[r]])
        self._pair_box = np.concatenate([self._pair_box, k])

    def _fixed_hit(self, rows, times: int, positions, velocities) -> np.ndarray:
        """(len(rows),): whether each of `rows`, headed on for `times` × its look-ahead, could
        reach a fixed box or an arm's sphere: the distance of the way ahead (a segment, straight
        at its velocity) from each box it may reach, against its radius widened by what the
        belt's pull may add to the way and FIXED_MARGIN. (Its ends and the box's corners give the
        distance whenever the segment is shorter than the bottle is wide.)"""
        b = self.bodies
        if len(rows) == 0:
            return np.zeros(0, bool)
        moved = np.hypot(*(positions[rows, :2] - self.listed_at[rows]).T)
        stale = moved > LIST / 2.0
        if stale.any():
            self._list(rows[stale], positions)
        p, v = positions[rows], velocities[rows]
        horizon = self.ahead[rows] * times * self.dt
        speed = np.hypot(v[:, 0], v[:, 1])
        # The belt's pull relaxes: in n ticks it moves a bottle at most n(n+1)/2 of its last change·dt further.
        n = self.ahead[rows] * times
        widen = self.pull[rows] * n * (n + 1) / 2.0 * self.dt + FIXED_MARGIN
        hit = np.zeros(len(rows), bool)
        mine = np.zeros(len(self.free), int)
        mine[rows] = np.arange(len(rows)) + 1
        pairs = np.flatnonzero(mine[self._pair_row])
        if len(pairs):
            at = mine[self._pair_row[pairs]] - 1
            c, h, cos, sin = (a[self._pair_box[pairs]] for a in self._fixed)
            # The way ahead, a segment, in each box's frame; its distance from the box.
            ax, ay = p[at, 0] - c[:, 0], p[at, 1] - c[:, 1]
            ux, uy = v[at, 0] * horizon[at], v[at, 1] * horizon[at]
            a0, a1 = cos * ax + sin * ay, cos * ay - sin * ax
            d0, d1 = cos * ux + sin * uy, cos * uy - sin * ux
            gap = np.minimum(_box_distance(a0, a1, h), _box_distance(a0 + d0, a1 + d1, h))
            length2 = np.maximum(d0 * d0 + d1 * d1, 1e-300)
            for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                kx, ky = sx * h[:, 0] - a0, sy * h[:, 1] - a1
                t = np.clip((kx * d0 + ky * d1) / length2, 0.0, 1.0)
                gap = np.minimum(gap, np.hypot(kx - t * d0, ky - t * d1))
            near = ((gap < b.radii[rows[at]] + widen[at])
                    & (np.abs(p[at, 2] - c[:, 2]) <= h[:, 2] + b.half_heights[rows[at]] + FIXED_MARGIN))
            hit[at[near]] = True
        centres, reach = self._spheres
        if len(reach):
            d = np.sqrt(((p[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)) - reach
            hit |= (d < (b.radii[rows] + speed * horizon + widen)[:, None]).any(axis=1)
        return hit

    def steady(self, rows, orientations, velocities, spins) -> np.ndarray:
        """(len(rows),): upright and steady as a riding bottle is (tilt under TILT, spin under
        SPIN, vertical speed under RISE), or free."""
        x, y = orientations[rows, 0], orientations[rows, 1]
        w = spins[rows]
        return (((1.0 - 2.0 * (x * x + y * y) > np.cos(TILT)) & ((w * w).sum(axis=1) < SPIN * SPIN)
                 & (np.abs(velocities[rows, 2]) < RISE)) | self.free[rows])

    def _touching(self, rows, times: int, positions, orientations, velocities, spins) -> np.ndarray:
        """(len(rows),): whether each of `rows` could touch another body in play or a moving part
        within `times` × its look-ahead. Their bounds first (rest.bounds; pairs found by a sweep
        along the plant's longer axis when there are many), then for each pair whose bounds meet:
        two steady bottles (free, or upright and steady in the engine) by their footprints and
        their relative motion — the difference of their velocities, of the belt's pull and their
        rocking brings them together, nothing else; any other pair by the wake rule's boxes,
        each body headed as far."""
        b = self.bodies
        play = b.in_play_rows()
        k = self.ahead[play] * times
        bound = bounds(b.radii[play], b.half_heights[play], velocities[play] * k[:, None], spins[play] * k[:, None],
                       self.dt)
        me = np.searchsorted(play, rows)
        i, j = _meeting(me, positions[play], bound)
        touching = np.zeros(len(rows), bool)
        if len(i):
            a, o = rows[i], play[j]
            both = np.concatenate([a, o])
            tight = self.steady(both, orientations, velocities, spins)
            tight = tight[:len(a)] & tight[len(a):]
            loose = ~tight
            if loose.any():
                la, lo = a[loose], o[loose]
                both, at = np.unique(np.concatenate([la, lo]), return_inverse=True)   # one boxes call for all
                kk = (self.ahead[both] * times)[:, None]
                box = boxes(orientations[both], b.radii[both], b.half_heights[both], velocities[both] * kk,
                            spins[both] * kk, self.dt)
                hit = (np.abs(positions[la] - positions[lo]) < box[at[:len(la)]] + box[at[len(la):]]).all(axis=1)
                touching[i[loose][hit]] = True
            if tight.any():
                ta, to = a[tight], o[tight]
                n = np.maximum(self.ahead[ta], self.ahead[to]) * times
                apart = positions[ta] - positions[to]
                closing = velocities[ta, :2] - velocities[to, :2]
                rock = (swing(b.radii[ta], b.half_heights[ta], spins[ta])
                        + swing(b.radii[to], b.half_heights[to], spins[to]))
                reach = ((np.hypot(closing[:, 0], closing[:, 1]) + rock) * n * self.dt
                         + (self.pull[ta] + self.pull[to]) * n * (n + 1) / 2.0 * self.dt)
                gap = np.hypot(apart[:, 0], apart[:, 1]) - b.radii[ta] - b.radii[to] - 2.0 * SHAPE_MARGIN
                hit = (gap < reach) & (np.abs(apart[:, 2]) < b.half_heights[ta] + b.half_heights[to])
                touching[i[tight][hit]] = True
        moving = self._moving
        if moving is not None and moving.parts:
            # A part's box as the wake rule widens it for one tick, and headed as far again as the
            # farthest look; against each bottle's bound (which holds its box).
            horizon = float(self.ahead[rows].max()) * times * self.dt
            centres = np.array([p.box()[0] for p in moving.parts])
            extents = np.array([p.box()[1] + np.abs(p.axis) * abs(p.velocity) * horizon for p in moving.parts])
            mine = np.repeat(bound[me][:, None], 3, axis=1)
            touching |= overlapping(positions[rows], mine, centres, extents).any(axis=1)
        return touching

    def _on_belt(self, rows, now, times: int, positions, velocities) -> np.ndarray:
        """(len(rows),): riding a belt now (`now`: the field under each) and, `times` × its
        look-ahead on, one at the same height; not coming to a stop on a still belt."""
        fields = self.fields
        there = fields.which(positions[rows] + velocities[rows] * (self.ahead[rows, None] * times * self.dt))
        ok = (now >= 0) & (there >= 0)
        ok[ok] = fields.surfaces[now[ok]] == fields.surfaces[there[ok]]
        if ok.any():
            v = velocities[rows]
            still = (fields.speeds[np.maximum(now, 0)] == 0.0) & ((v[:, 0] ** 2 + v[:, 1] ** 2) < STILL * STILL)
            ok &= ~still
        return ok

    def _fields(self, rows, read_rows, under, positions) -> np.ndarray:
        """The field under each of `rows` as the last read found it (`under`, per `read_rows`),
        or looked up afresh when the row sets changed since."""
        if under is None or (self.bodies.stale and read_rows is not None):
            return self.fields.which(positions[rows])
        return under[rows] if read_rows is None else under[np.searchsorted(read_rows, rows)]

    # --- before a tick: who must come back ------------------------------------------------
    def release_near(self, tick: int, placed: dict, moving: bool) -> None:
        """Before a tick: free bottles that could be touched within their look-ahead re-enter the
        engine. A look at the state of `tick` holds for the look-ahead's ticks, so it is taken
        once every look-ahead less one tick — and at once after a body was put down (`placed`),
        while a moving part is under way (`moving`) or after a belt changed its speed."""
        rows = self.rows
        if len(rows) == 0 or (tick < self.due and not placed and not moving):
            return
        self.due = tick + max(1, int(self.ahead[rows].min()) - 1)
        b = self.bodies
        positions = b.positions
        if placed:   # bodies put down since the last read stand there already
            positions = positions.copy()
            for n, centre in placed.items():
                positions[n] = centre
        now = self._fields(rows, b.moved_rows, b.moved_under, positions)
        back = ~self._on_belt(rows, now, 1, positions, b.velocities)
        back |= self._fixed_hit(rows, 1, positions, b.velocities)
        back |= self._touching(rows, 1, positions, b.orientations, b.velocities, b.angular_velocities)
        if back.any():
            self.release(rows[back])

    def release(self, rows) -> None:
        """Put free bottles back into the engine with their pose and velocity (spin zero)."""
        rows = [int(n) for n in np.atleast_1d(rows) if self.free[int(n)]]
        if not rows:
            return
        b, call = self.bodies, self.engine.call
        for n in rows:
            body = b.ids[n]
            call(pybullet.resetBasePositionAndOrientation, body, b.positions[n].tolist(), b.orientations[n].tolist())
            call(pybullet.resetBaseVelocity, body, b.velocities[n].tolist(), (0.0, 0.0, 0.0))
            self.engine.rejoin(body)
        self.free[rows] = False
        self.left += len(rows)
        self._changed()

    def forget(self, row: int) -> None:
        """The body left play (parked): no longer free, nothing to put back."""
        if self.free[row]:
            self.free[row] = False
            self._changed()

    # --- after a tick: who may go -----------------------------------------------------------
    def take_free(self, tick: int, rows: np.ndarray, held) -> None:
        """After a tick's read: of the awake `rows`, the bottles riding a belt steadily and clear
        of everything for `2·ahead` ticks leave the engine. One that rides a belt but is near
        something is looked at again RETRY ticks later (a queue stays one for a while)."""
        b = self.bodies
        rows = rows[self.allowed[rows] & (self.next_try[rows] <= tick)]
        if held:
            rows = rows[~np.isin(rows, held)]
        if len(rows) == 0:
            return
        p, q, v, w = b.positions, b.orientations, b.velocities, b.angular_velocities
        rows = rows[self.steady(rows, q, v, w)]
        if len(rows) == 0:
            return
        field = self._fields(rows, b.live_rows, b.under, p)
        on = field >= 0
        rows, field = rows[on], field[on]
        base = p[rows, 2] - b.half_heights[rows]
        level = np.abs(base - self.fields.surfaces[field]) < SINK
        rows, field = rows[level], field[level]
        if len(rows) == 0:
            return
        rows = rows[self._on_belt(rows, field, 2, p, v)]     # twice the look-ahead, as below
        if len(rows) == 0:
            return
        near = self._touching(rows, 2, p, q, v, w)
        near[~near] = self._fixed_hit(rows[~near], 2, p, v)
        self.next_try[rows[near]] = tick + RETRY
        rows = rows[~near]
        if len(rows) == 0:
            return
        for n in rows.tolist():
            self.engine.leave(b.ids[n])
        v[rows, 2] = 0.0
        w[rows] = 0.0
        self.free[rows] = True
        self.entered += len(rows)
        self._changed()

    # --- the tick itself --------------------------------------------------------------------
    def speed_changed(self) -> None:
        """A belt's speed changed: the free bottles are looked at before the next tick."""
        self.due = 0

    def hand(self, rows, dvx, dvy) -> None:
        """Before the engine's step: the velocity changes the belts' law gives the free `rows` on
        a belt this tick (Bottles.drive works them out with the engine-driven bottles', in one go)."""
        self._handed = (rows, dvx, dvy)

    def advance(self) -> None:
        """After the engine's step: every free bottle one tick on — the velocity change it was
        handed, then x ← x + v·dt, as the engine integrates — in numpy."""
        rows = self.rows
        if len(rows) == 0:
            return
        b, dt = self.bodies, self.dt
        v = b.velocities[rows]
        handed, self._handed = self._handed, None
        if handed is not None and len(handed[0]):
            on, dvx, dvy = handed
            at = np.searchsorted(rows, on)
            v[at, 0] += dvx
            v[at, 1] += dvy
        b.velocities[rows] = v
        b.positions[rows, :2] += v[:, :2] * dt

    def _changed(self) -> None:
        self.rows = np.flatnonzero(self.free)
        self.bodies.free = self.free
        self.bodies.stale = True

    # --- the engine's own word, for tests -----------------------------------------------------
    def check(self, tick: int, floors: set[int]) -> None:
        """Every free bottle at its pose, asked of the engine: a cylinder of its full radius there
        touches no body but a floor (free bottles' engine poses are stale: they are compared with
        each other here, as upright cylinders)."""
        b, client = self.bodies, self.engine.client
        rows = self.rows.tolist()
        skip = floors | {b.ids[n] for n in rows}
        for n in rows:
            at, orientation = b.positions[n].tolist(), b.orientations[n].tolist()
            half = boxes(b.orientations[[n]], b.radii[[n]], b.half_heights[[n]])[0]
            lo, hi = (b.positions[n] - half).tolist(), (b.positions[n] + half).tolist()
            for other, _ in pybullet.getOverlappingObjects(lo, hi, physicsClientId=client) or ():
                if other in skip:
                    continue
                touch = pybullet.getClosestPoints(-1, other, 0.0, collisionShapeA=self._probe(n),
                                                  collisionShapePositionA=at, collisionShapeOrientationA=orientation,
                                                  physicsClientId=client)
                if touch:
                    raise RuntimeError(f"tick {tick}: {b.labels[n]} is in free transport but touches body {other} "
                                       f"at {tuple(round(float(c), 4) for c in touch[0][5])}")
            for m in rows:
                apart = b.positions[m] - b.positions[n]
                if (m != n and np.hypot(apart[0], apart[1]) < b.radii[m] + b.radii[n]
                        and abs(apart[2]) < b.half_heights[m] + b.half_heights[n]):
                    raise RuntimeError(f"tick {tick}: free bottles {b.labels[n]} and {b.labels[m]} touch")

    def _probe(self, n: int) -> int:
        """A collision shape standing for bottle `n` in `check` (made once, outside the world)."""
        shape = self._probes.get(n)
        if shape is None:
            b = self.bodies
            shape = self._probes[n] = self.engine.call(
                pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=float(b.radii[n]),
                height=2.0 * float(b.half_heights[n]))
        return shape


def _box_distance(x, y, half) -> np.ndarray:
    """Distance from points (x, y), in a box's frame, to the box of half extents `half` (0 inside)."""
    return np.hypot(np.maximum(np.abs(x) - half[:, 0], 0.0), np.maximum(np.abs(y) - half[:, 1], 0.0))


SWEEP = 20000   # (rows × bodies) above which pairs are found by a sweep rather than all at once


def _meeting(me, points, bound):
    """The pairs (i, j): row i of `me` (indices into `points`) and point j whose boxes of half
    extent `bound` (per point, every axis) overlap, j ≠ me[i]."""
    if len(me) * len(points) <= SWEEP:
        gap = np.abs(points[me][:, None, :] - points[None, :, :]) - bound[me][:, None, None] - bound[None, :, None]
        meet = (gap < 0.0).all(axis=2)
        meet[np.arange(len(me)), me] = False
        return np.nonzero(meet)
    # Sorted along the longer axis, each point against the next, the one after, …, until no pair is near.
    axis = int(np.argmax(np.ptp(points[:, :2], axis=0)))
    order = np.argsort(points[:, axis], kind="stable")
    p, r = points[order], bound[order]
    wanted = np.full(len(points), -1)
    wanted[me] = np.arange(len(me))
    w = wanted[order]
    found_i, found_j = [], []
    for shift in range(1, len(p)):
        near = (np.abs(p[shift:] - p[:-shift]) < (r[shift:] + r[:-shift])[:, None]).all(axis=1)
        if not (p[shift:, axis] - p[:-shift, axis] < r[shift:] + r[:-shift]).any():
            break
        lo, hi = np.flatnonzero(near), np.flatnonzero(near) + shift
        for x, y in ((lo, hi), (hi, lo)):
            keep = w[x] >= 0
            found_i.append(w[x][keep])
            found_j.append(order[y][keep])
    if not found_i:
        return np.zeros(0, int), np.zeros(0, int)
    return np.concatenate(found_i), np.concatenate(found_j)
