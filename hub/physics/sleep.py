"""Sleep in the engine: bodies that rest.py says may rest are put to sleep in pybullet, and woken by its rule."""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.changes import Gripped, Parked, Placed, Tipped, reached
from hub.physics.rest import overlapping

with quiet_stderr():
    import pybullet


class Sleep:
    """The engine's side of rest (rest.py holds the rule and the resting set, in numpy): puts the
    bodies that have been still long enough to sleep, wakes them, and checks that the engine did
    not move a resting body behind the hub's back (`check`)."""

    def __init__(self, engine, bodies, rest):
        self.engine = engine
        self.bodies = bodies
        self.rest = rest

    def settle(self, fields, held, moving) -> None:
        """Put to rest the bodies that have been still long enough where nothing drives them:
        not held (`held`: rows an arm grips), and not in the way of a moving part (`moving`:
        MovingParts, whose boxes would wake them at the next tick)."""
        b, rest = self.bodies, self.rest
        rows = b.awake_rows()
        field = b.under
        if len(rows) == 0 or field is None:   # None: a body was taken out since this tick's read (the
            return                            # watch's `remove`): the fields under the rest are looked up next tick
        gripped = np.zeros(len(rest.allowed), bool)
        if held:
            gripped[held] = True
        state = b.positions, b.orientations, b.velocities, b.angular_velocities
        candidates = rest.candidates(rows, field, fields.speeds, gripped, state[2], state[3])
        if len(candidates):
            candidates = rest.settle(candidates, rows, *state)
        if len(candidates) and moving.moving:
            centres, extents = moving.boxes()
            clear = ~overlapping(b.positions[candidates], rest.boxes(candidates, b.orientations),
                                 centres, extents).any(axis=1)
            candidates = candidates[clear]
        if len(candidates):
            for body in (b.ids[n] for n in candidates.tolist()):
                self.engine.leave(body)
            rest.put(candidates, b.orientations, field[np.searchsorted(rows, candidates)])
            # What the engine holds for a sleeping body from its next tick on.
            b.velocities[candidates] = 0.0
            b.angular_velocities[candidates] = 0.0
            b.stale = True

    def hear(self, change) -> None:
        """A change a part made (changes.py): a body the plant takes in hand (gripped, parked,
        put down, tipped) leaves the resting set, one gripped at rest wakes first; the resting
        bodies the change reaches wake (those free transport took off free from rest excepted)."""
        rest = self.rest
        if isinstance(change, (Gripped, Parked, Placed, Tipped)):
            if isinstance(change, Gripped) and rest.resting[change.body]:
                self.wake(np.array([change.body]))
            rest.forget(change.body)
        self.wake(reached(change, rest, self.bodies.positions))

    def wake_near(self) -> None:
        """Before a tick: wake the resting bodies an awake body has come near (the island Bullet wakes)."""
        b = self.bodies
        self.wake(self.rest.woken_by(b.awake_rows(), b.positions, b.orientations, b.velocities,
                                     b.angular_velocities))

    def wake_all(self) -> None:
        """Wake every resting body (they rest again once still for sleep_after)."""
        self.wake(self.rest.rows())

    def wake(self, rows: np.ndarray) -> None:
        if len(rows) == 0:
            return
        ids = self.bodies.ids
        for body in (ids[n] for n in rows.tolist()):
            self.engine.rejoin(body)
        self.rest.wake(rows)
        self.bodies.stale = True

    def check(self, tick: int, parts: set[int]) -> None:
        """Every resting body as the engine holds it: where planthub left it, not moving — and,
        since it is out of the collision world (Engine.leave), touched by no awake body or moving
        part, which would pass through it unseen (asked of the engine: closest points at 0; a
        bottle may rest against fixed bodies and switchable `parts`, which wake it when they turn;
        bottles in free transport are asked about by FreeTransport.check, at their own pose)."""
        b, client = self.bodies, self.engine.client
        resting = self.rest.rows().tolist()
        still = {b.ids[n] for n in resting} | self.engine.fixed_bodies() | parts
        if b.free is not None:   # out of the collision world, their pose there stale (transport.check asks for them)
            still |= {b.ids[n] for n in np.flatnonzero(b.free).tolist()}
        for n in resting:
            lo, hi = self.engine.aabb(b.ids[n])
            for other, _ in pybullet.getOverlappingObjects(lo, hi, physicsClientId=client) or ():
                if other in still:
                    continue
                if pybullet.getClosestPoints(b.ids[n], other, 0.0, physicsClientId=client):
                    raise RuntimeError(f"tick {tick}: {b.labels[n]} rests in planthub but body {other} "
                                       "touches it: the wake came too late")
        for n in resting:
            position, orientation = pybullet.getBasePositionAndOrientation(b.ids[n], client)
            velocity, spin = pybullet.getBaseVelocity(b.ids[n], client)
            if (tuple(b.positions[n]) != position or tuple(b.orientations[n]) != orientation
                    or velocity != (0.0, 0.0, 0.0) or spin != (0.0, 0.0, 0.0)):
                raise RuntimeError(
                    f"tick {tick}: {b.labels[n]} rests in planthub but the engine moved it: "
                    f"at {position} moving {velocity}, held at {tuple(b.positions[n])}")
