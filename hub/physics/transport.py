"""Free transport: a bottle riding a belt that nothing can touch leaves the engine and follows its belt's law in the hub.

A bottle carried by a belt, clear of every other body, rail, gate and belt end, costs the
engine its contacts with the floor and the hub two state reads and a force per tick, and all
the engine adds to what the belt's law gives it is a rocking of ~0.5° and a sink of ~2 mm into
the floor. In free transport the hub moves it itself, all such bottles at once: per tick the
velocity change the field would make the engine apply (fields.law_at: the exact
relaxation on a straight, the same in the rotating surface's frame on a curve, the capped law
with `friction:`), then the engine's own position step, x ← x + v·dt (Bullet's semi-implicit
Euler). On a frictionless floor nothing else acts on it horizontally, so a free bottle moves as
the engine would move it without contacts, to rounding; its height, orientation and the sink
it had stay as they were when it left, its vertical velocity and spin are zero.

In the engine a free bottle is out of play as a parked or resting one is (parking.py, rest.py):
collision off, asleep, its pose there stale. It re-enters — its exact pose and velocity put
back, collision on, awake — before the tick at which anything could touch it. "Anything" by
three tests, each looking a number of ticks forward (the bottle's `lookahead`, default 6):

- bodies: every other body in play (awake, resting, free, just put down). Two steady bottles
  (free, or upright and hardly rocking in the engine) by their footprints — the gap between
  them against what their relative velocity, their rocking and the belt's pull can close; two
  on one straight belt whose law scales with the mass, both staying on it, by their relative
  velocity and rocking alone (that law never lets two velocities part) — so that a line of
  bottles 2 cm apart rides free, and sets off free together; two such bottles, both free, at
  one velocity and not turning, ride free even touching, as a train (a queue that stood at
  rest in pairs sets off so), and come back into the engine together; any other pair by the
  wake rule's boxes without its contact breaking threshold (a free bottle is in no island),
  each headed as far; a moving part's box likewise;
- fixed geometry: rails and walls, gates and blades whether solid or not: the distance of its
  way ahead — at its velocity, and the belt's pull along its own direction, so that a bottle
  setting off between rails is pulled along them — from each box listed within LIST of it,
  against its radius and FIXED_MARGIN (a robot arm has no collision shapes: the bottle it
  lets go of is a body like the others, looked at whole at once);
- the belt: the point it is headed to lies on a belt at the same height (a hand-over between
  chained belts is crossed free: the field under it is looked up at every tick, half-open as
  the engine-driven bottle's is), and it is not coming to a stop on a still belt: there it rests
  (rest.py) at once if nothing is near, without the engine, or else re-enters.

A look at the state of a tick holds for the ticks it looked ahead. Looks are taken every
`lookahead − 1` ticks; a bottle is looked at whole, LONG look-aheads forward (or one where that
is too far, or where its way crosses onto another belt), only when its last whole look runs out
— what it was looked at against moves by laws the look bounds: fixed geometry and resting
bodies stand, free bottles follow their belts, and each body's pull is its belt's law now (not
the last tick's: one that crossed onto another belt is pulled by that one), bounded by the law
where its way ends — and against the bodies awake in the engine, which contacts may throw, at
every look. Every free bottle is looked at whole at once after a bottle was put down or let go of, while a
moving part is under way and after a belt changed its speed.

A bottle leaves the engine when it rides a belt upright and steady (tilt under 1°, spin under
2.5 rad/s, vertical speed under 2 cm/s, its base within 5 mm of the surface) and passes the same
tests `2·lookahead` ticks forward, so that one at the edge does not go in and out every tick
(looked for every EVERY ticks); and a resting bottle rides off free straight from rest when its
belt starts, if it passes them then. Bottles made with `transport: engine`, the paper's two-body
model and hull bottles stay in the engine. The tests run at every look for dozens of bottles,
so they are compiled loops (numba, transport_kernels.py), not numpy calls. `check`
(PhysicsWorld.check_free, tests; transport_check.py) asks the engine itself at every tick whether a
free bottle, at its pose, touches anything but the floor.
"""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.changes import BeltSpeed, Gripped, LetGo, Parked, Tipped, reached
from hub.physics.transport_check import engine_check
from hub.physics.transport_kernels import (
    _NO_BOXES,
    _NO_PARTS,
    NEAR,
    Body,
    Fixed,
    Way,
    _advance,
    _grow,
    _leave,
    _look,
    with_grid,
)

with quiet_stderr():
    import pybullet

LOOKAHEAD = 6         # ticks a free bottle's tests look forward, by default
EVERY = 15            # ticks between two looks for bottles that may leave the engine
RETRY = 15            # ticks before a bottle found near something is looked at again


class FreeTransport:
    """The free set of a world's bodies and the tests that take bottles out of and back into the engine."""

    #: hub/core/state.py: which bottles ride free and what their looks found; the laws and limits are structure.
    STATE = ("free", "listed_at", "near", "near_count", "rows", "pulls", "most", "due", "clear", "_everything",
             "next_try", "entered", "left", "started", "stopped", "offsets", "_parts_at_rest", "_trains_seen",
             "_slides_seen", "_checked")

    def __init__(self, engine, bodies, fields, rest, dt: float):
        self.engine = engine
        self.bodies = bodies
        self.fields = fields
        self.rest = rest
        self.dt = dt
        self.every = EVERY
        self.ahead = np.zeros(0)            # per body: the ticks its tests look forward
        self.allowed = np.zeros(0, bool)    # the bottle's kind and its `transport:` let it go free
        self.free = np.zeros(0, bool)
        self.enabled = False                # some bottle may ride free
        self.listed_at = np.zeros((0, 3))   # where each bottle's fixed boxes were listed
        self.near = np.zeros((0, NEAR), np.int64)   # per body: the fixed boxes within LIST of it then
        self.near_count = np.zeros(0, np.int64)     # and how many (more than NEAR: too many to list)
        self.rows = np.zeros(0, int)        # the free rows, in body order
        self.pulls = np.zeros((0, 2))       # per body: its belt's velocity change now (x, y), m/s (_pulls)
        self.most = np.zeros(0)            # per body: the most its belts may pull it over a look, m/s (_pulls)
        self.due = 0                        # the tick at which the free bottles are looked at next
        self.clear = np.zeros(0, int)       # per body: the tick up to which its last whole look holds
        self._everything = False            # every free bottle is looked at whole next time (a belt's speed changed)
        self.next_try = np.zeros(0, int)    # per body: the tick from which it may be looked at to go free
        self.entered = 0                    # how many times a bottle left the engine (for figures)
        self.left = 0                       # and came back
        self.started = 0                    # how many times a resting bottle rode off free (from_rest)
        self.stopped = 0                    # and a free one came to rest without the engine (_settle)
        self._fixed = _NO_BOXES             # fixed boxes, one a row: centre, half extents, cos and sin of the yaw
        self._moving = None                 # MovingParts, tested at every look (their boxes move)
        self.offsets = np.zeros(0)          # per body: where a belt grips it, its centre's height over that (arm)
        self._parts_at_rest = None          # their boxes while none moves
        self._probes: dict[int, int] = {}   # body row → collision shape, for `check`
        self._trains_seen: dict = {}        # for `check`: free pairs that touch (a train's), their depth then
        self._slides_seen: dict = {}        # for `check`: (free row, fixed body) touching, the depth when first seen
        self._checked: set[int] = set()     # the free rows at the last `check`

    def add(self, allowed: bool, ahead: int = LOOKAHEAD) -> None:
        if not (isinstance(ahead, int) and ahead >= 2):
            raise ValueError(f"the look-ahead must be a whole number of ticks, at least 2, not {ahead!r}")
        self.ahead = np.append(self.ahead, float(ahead))
        self.allowed = np.append(self.allowed, allowed)
        self.enabled = self.enabled or bool(allowed)
        self.free = np.append(self.free, False)
        self.listed_at = np.vstack((self.listed_at, np.full((1, 3), np.inf)))
        self.near = np.vstack((self.near, np.zeros((1, NEAR), np.int64)))
        self.near_count = np.append(self.near_count, 0)
        self.pulls = np.vstack((self.pulls, np.zeros((1, 2))))
        self.most = np.append(self.most, 0.0)
        self.next_try = np.append(self.next_try, 0)
        self.clear = np.append(self.clear, 0)

    def arm(self, fixed_boxes, moving, offsets: dict) -> None:
        """At the start: the fixed geometry a free bottle keeps clear of — boxes (centre, half
        extents, yaw) of rails, walls, gates and blades, not the floors — the moving parts, and
        where a belt grips each bottle (`offsets`, row → its centre's height over the base, for
        `grip_at: base`; Bottles.base_offsets).
        A robot arm has no collision shapes, and the bottle it carries none while it is held:
        the bottle it lets go of is an awake body like any other, looked at whole against every
        free bottle before the next tick (`look_whole`)."""
        if fixed_boxes:
            c = np.array([b[0] for b in fixed_boxes], float)
            h = np.array([b[1] for b in fixed_boxes], float)
            yaw = np.array([b[2] for b in fixed_boxes], float)
            self._fixed = with_grid(np.column_stack((c, h, np.cos(yaw), np.sin(yaw))))
        self._moving = moving
        self.offsets = np.zeros(len(self.free))
        for row, offset in offsets.items():
            self.offsets[row] = offset

    # --- the tests ------------------------------------------------------------------------
    def _trains(self, seeds: np.ndarray, pool: np.ndarray) -> np.ndarray:
        """`seeds` (a mask over bodies) grown by the bodies of `pool` (rows) whose footprints
        come within 2·SHAPE_MARGIN of one it holds, until it holds the whole train of each."""
        out = seeds.copy()
        _grow(out, np.asarray(pool, np.int64), self._body())
        return out

    def _body(self, positions: np.ndarray | None = None) -> Body:
        """The bodies' state as the kernels take it (`positions`: in place of the bodies' own)."""
        b = self.bodies
        return Body(b.positions if positions is None else positions, b.orientations, b.velocities,
                    b.angular_velocities, b.masses, b.radii, b.half_heights)

    def _way(self) -> Way:
        return Way(self.ahead, self.most, self.pulls)

    def _lists(self) -> Fixed:
        """The fixed boxes and each bottle's list of those near it, as the kernels take them."""
        return Fixed(*self._fixed, self.listed_at, self.near, self.near_count)

    def _part_boxes(self) -> np.ndarray:
        """The moving parts' boxes as the wake rule widens them for one tick, one a row: centre,
        half extents, and how fast each half extent grows with the time a look goes forward (a part
        headed on along its axis: `_grown`); while none moves, the same boxes at every look."""
        moving = self._moving
        if moving is None or not moving.parts:
            return _NO_PARTS
        if not moving.moving and self._parts_at_rest is not None:
            return self._parts_at_rest
        parts = [(p.box(), p) for p in moving.parts]
        boxes = np.hstack((np.array([box[0] for box, _ in parts], float), np.array([box[1] for box, _ in parts], float),
                           np.array([np.abs(p.axis) * abs(p.velocity) for _, p in parts], float)))
        self._parts_at_rest = None if moving.moving else boxes
        return boxes

    # --- before a tick: who must come back ------------------------------------------------
    def release_near(self, tick: int, placed: dict, moving: bool, awake: np.ndarray) -> None:
        """Before a tick: free bottles that could be touched within their look-ahead re-enter the
        engine; one that came to a stop on a still belt with nothing near rests.

        A look at the state of `tick` holds for the ticks it looked ahead, so looks are taken
        once every look-ahead less one tick, and a bottle is looked at whole only when the last
        whole look at it runs out (`clear`): then LONG × its look-ahead forward, or its look-ahead
        where that is too far or its way crosses onto another belt. Everything it was looked at
        against moves by a law that look bounds — fixed geometry and resting bodies stand, free
        bottles follow their belts, each body's pull is taken afresh from its belt's law
        (`_pulls`) and bounded by the law where its way ends — except the bodies awake in the
        engine, which contacts may throw: against those (`awake`) every free bottle is looked at
        each time. Every free bottle is looked at whole at once after a body was put down
        (`placed`), while a moving part is under way (`moving`) and after a belt changed its speed."""
        rows = self.rows
        if len(rows) == 0 or (tick < self.due and not placed and not moving):
            return
        ahead = self.ahead[rows]
        self.due = tick + max(1, int(ahead.min()) - 1)
        b = self.bodies
        positions = b.positions
        if placed:   # bodies put down since the last read stand there already
            positions = positions.copy()
            for n, centre in placed.items():
                positions[n] = centre
        whole = bool(placed or moving or self._everything)
        self._everything = False
        fields = self.fields
        # One compiled call for the whole look (`_look`): its tests' arrays cross into it once.
        due, back, ok, still, near, now = _look(
            tick, whole, rows, b.in_play_rows() if b.moved_rows is None else b.moved_rows,
            np.asarray(awake, np.int64), b.in_play_rows(), self.dt, self._body(positions), self._way(), self.clear,
            self.free, fields.explicit, fields.regions(), self._part_boxes(), self._lists())
        settle = None
        if due.any():
            look = rows[due]
            # One that stops on a still belt with nothing near rests at once, without the engine;
            # a train rests whole or not at all (the rest of it would ride on into the part at rest).
            settle = still & ~near & self.rest.allowed[look]
            if settle.any():
                resting = np.zeros(len(self.free), bool)
                resting[look[settle]] = True
                torn = self._trains(resting, rows) & ~resting
                if torn.any():
                    settle &= ~self._trains(torn, rows)[look]
            back[due] = (~ok | near) & ~settle
        if back.any():
            # A train comes back whole: its bottles touch, and the engine must hold both sides.
            out = np.zeros(len(self.free), bool)
            out[rows[back]] = True
            back = self._trains(out, rows)[rows]
        if settle is not None and settle.any():
            self._settle(look[settle], now[settle])
        if back.any():
            self.release(rows[back])

    # --- what the plant changes (changes.py) -------------------------------------------------
    def hear(self, change) -> None:
        """A change a part made: a belt's new speed has every free bottle looked at whole before
        the next tick, and the resting bodies on it that may ride free ride off (`from_rest`,
        the others left for sleep to wake); a body an arm grips or a fault tips comes back into the
        engine, a parked one is forgotten, and one let go of has every free bottle looked at whole.
        A gate or blade turning changes nothing here (a free bottle keeps clear of every part's
        boxes, solid or not), nor does a moving part under way (looked at, at every look, as it
        moves), nor a body put down (looked at whole: `placed`)."""
        if isinstance(change, BeltSpeed):
            self.look_whole()
            if self.enabled:
                rows = reached(change, self.rest, self.bodies.positions)
                if len(rows):
                    change.woken = self.from_rest(rows)
        elif isinstance(change, (Gripped, Tipped)):
            self.release([change.body])
        elif isinstance(change, Parked):
            self.forget(change.body)
        elif isinstance(change, LetGo):
            self.look_whole()

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

    def _settle(self, rows, field) -> None:
        """Free `rows` that came to a stop on a still belt go straight to rest (rest.py): their
        pose put into the engine and read back as the engine holds it (the resting set's pose is
        the engine's, bit for bit), velocity and spin zero. They stay out of its collision world
        and asleep, as free and resting bodies both are. What is left of their speed (under
        STILL) is dropped: on a still belt it would take them at most STILL/k further (0.3 mm at
        k = 16/s)."""
        b, call = self.bodies, self.engine.call
        for n in rows.tolist():
            body = b.ids[n]
            call(pybullet.resetBasePositionAndOrientation, body, b.positions[n].tolist(), b.orientations[n].tolist())
            call(pybullet.resetBaseVelocity, body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
            self.engine.sleep(body)
            position, orientation = call(pybullet.getBasePositionAndOrientation, body)
            b.positions[n], b.orientations[n] = position, orientation
        b.velocities[rows] = 0.0
        b.angular_velocities[rows] = 0.0
        self.rest.put(rows, b.orientations, field)
        self.free[rows] = False
        self.stopped += len(rows)
        self._changed()

    def from_rest(self, rows: np.ndarray) -> np.ndarray:
        """A belt's speed changed under the resting `rows` (rest.on_field: those on it and their
        groups). Those that may ride free and pass `take_free`'s tests as they stand — their
        velocity zero, the belt's pull at its new speed — ride off free straight from rest: they
        are already out of the engine's collision world and asleep there, with their exact pose.
        Returns the others, which the engine must wake."""
        b = self.bodies
        # The pull each gets at the belt's new speed (a resting body's is from before it rested).
        moving = b.in_play_rows() if b.moved_rows is None else b.moved_rows
        # Standing still together, they may set off as trains (_touching): those that stay must
        # keep their trains with them.
        candidates = rows[self.allowed[rows]]
        joined = self.free.copy()
        joined[candidates] = True
        go = self._leaving(candidates, np.union1d(moving, rows), joined)[0]
        stay = np.zeros(len(joined), bool)
        stay[candidates] = True
        stay[go] = False
        stay = self._trains(stay, np.union1d(candidates, self.rows))
        go = go[~stay[go]]
        self.release(np.flatnonzero(stay & self.free))
        if len(go) == 0:
            return rows
        self.rest.wake(go)
        self.free[go] = True
        self.started += len(go)
        self._changed()
        return rows[~np.isin(rows, go)]

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
        # No trains: none of `rows` is joined.
        go, near = self._leaving(rows, b.in_play_rows() if b.moved_rows is None else b.moved_rows, self.free)
        self.next_try[near] = tick + RETRY
        if len(go) == 0:
            return
        for n in go.tolist():
            self.engine.leave(b.ids[n])
        self.clear[go] = tick + 2 * self.ahead[go]
        b.velocities[go, 2] = 0.0
        b.angular_velocities[go] = 0.0
        self.free[go] = True
        self.entered += len(go)
        self._changed()

    def _leaving(self, rows, pulled, joined) -> tuple[np.ndarray, np.ndarray]:
        """(go, near): of `rows`, those upright and steady, standing on a belt (base within SINK
        of its surface) and passing the tests `2·ahead` ticks forward; and those that ride a belt
        but are near something (`joined`: who may form a train). Every pull is taken afresh
        first, for `pulled` (`_pulls`). One compiled call (`_leave`)."""
        b, fields = self.bodies, self.fields
        go, near = _leave(np.asarray(rows, np.int64), np.asarray(pulled, np.int64), b.in_play_rows(), self.dt,
                          self._body(), self._way(), self.free, joined, fields.explicit, fields.regions(),
                          self._part_boxes(), self._lists())
        return rows[go], rows[near]

    # --- the tick itself --------------------------------------------------------------------
    def look_whole(self) -> None:
        """A belt's speed changed, or an arm let go of a bottle: the free bottles are looked at
        whole before the next tick (whose look takes every pull afresh, at the new speed)."""
        self.due = 0
        self._everything = True

    def advance(self) -> None:
        """After the engine's step: every free bottle one tick on — the velocity change the law
        of the belt under it gives it, where the engine would have it gripped (its centre, or its
        base for `grip_at: base`, as Bottles.drive takes it), then x ← x + v·dt, as the engine
        integrates — in one compiled loop, from the state the tick began with (the engine's
        step changes nothing of a free bottle's)."""
        rows = self.rows
        if len(rows) == 0:
            return
        b = self.bodies
        fields = self.fields
        _advance(rows, b.positions, b.orientations, b.velocities, b.masses, self.offsets, fields.dt, fields.explicit,
                 *fields.regions())

    def _changed(self) -> None:
        self.rows = np.flatnonzero(self.free)
        self.bodies.free = self.free
        self.bodies.stale = True

    # --- the engine's own word, for tests -----------------------------------------------------
    def check(self, tick: int, floors: set[int], fixed: set[int] = frozenset(), held=()) -> None:
        """Every free bottle at its pose, asked of the engine (transport_check.py)."""
        engine_check(self, tick, floors, fixed, held)
