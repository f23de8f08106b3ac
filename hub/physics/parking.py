"""Parked bodies: bottles out of play (in a source's store, taken out by a sink) wait off stage, asleep, unread."""
from __future__ import annotations

import math

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.rest import boxes

with quiet_stderr():
    import pybullet

PARKED = (-100.0, 0.0, -100.0)   # off stage: parked bodies wait here, 0.5 m apart along y


class Parking:
    """Takes bodies out of play and puts them back: parked bodies are off stage, without
    collision, asleep in the engine and not read per tick. Measured: 100 parked bottles take
    the engine from 37 to 43 µs per tick (awake without collision, 99 µs), 1000 add ~0.2 µs
    each to the engine and ~0.15 µs each to the numpy over all rows (`make bench`); reading
    each would add ~2.5 µs."""

    def __init__(self, engine, bodies, bottles, rest, sleep):
        self.engine = engine
        self.bodies = bodies
        self.bottles = bottles
        self.rest = rest
        self.sleep = sleep

    def park(self, body: int) -> None:
        call = self.engine.call
        spot = (PARKED[0], PARKED[1] + 0.5 * body, PARKED[2])
        for b, z in self.bottles.parts(body):
            call(pybullet.resetBasePositionAndOrientation, b, (spot[0], spot[1], spot[2] + z), (0, 0, 0, 1))
            call(pybullet.resetBaseVelocity, b, (0, 0, 0), (0, 0, 0))
            self.engine.leave(b)
        self.bodies.parked.add(body)
        self.rest.forget(body)
        self.bodies.moved()

    def unpark(self, body: int, base) -> None:
        """Put a parked body back into play, upright and at rest, standing on `base`."""
        call, half_heights = self.engine.call, self.bodies.half_heights
        for b, z in self.bottles.parts(body):
            center = (base[0], base[1], base[2] + half_heights[body] + z)
            call(pybullet.resetBasePositionAndOrientation, b, center, (0, 0, 0, 1))
            call(pybullet.resetBaseVelocity, b, (0, 0, 0), (0, 0, 0))
            self.engine.rejoin(b)
        self.bodies.parked.discard(body)
        self.rest.forget(body)
        centre = (base[0], base[1], base[2] + half_heights[body])
        self.bodies.placed[body] = centre
        if self.rest.resting.any():
            # The state arrays learn where it stands at the next read; what rests near it wakes now.
            upright = boxes(np.array([(0.0, 0.0, 0.0, 1.0)]), self.bodies.radii[[body]], half_heights[[body]])
            self.sleep.wake_in([centre], upright)
        self.bodies.moved()

    def lay(self, body: int, heading: float) -> None:
        """Lay a body in play on its side where it stands, its axis along `heading` (rad, in the
        plane), at rest (a tipped bottle: hub/run/faults.py). Like `unpark`, a reset the engine sees
        the same way in every run that makes it at the same tick."""
        call, bodies = self.engine.call, self.bodies
        x, y, z = bodies.positions[body].tolist()
        floor = z - float(bodies.half_heights[body])   # where it stands (upright, as a bottle in play does)
        centre = (x, y, floor + float(bodies.radii[body]))
        c, s = math.cos(heading), math.sin(heading)
        half = math.sqrt(0.5)   # a quarter turn about the horizontal axis across the heading
        turn = (-s * half, c * half, 0.0, half)
        for b, offset in self.bottles.parts(body):
            part = (centre[0] + c * offset, centre[1] + s * offset, centre[2])
            call(pybullet.resetBasePositionAndOrientation, b, part, turn)
            call(pybullet.resetBaseVelocity, b, (0, 0, 0), (0, 0, 0))
            self.engine.rejoin(b)
        self.rest.forget(body)
        bodies.placed[body] = centre
        if self.rest.resting.any():
            lying = boxes(np.array([turn]), bodies.radii[[body]], bodies.half_heights[[body]])
            self.sleep.wake_in([centre], lying)
        bodies.moved()

    def is_parked(self, body: int) -> bool:
        return body in self.bodies.parked
