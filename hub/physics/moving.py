"""Moving kinematic parts: bodies of boxes the plant drives along a straight axis at set speeds (a pusher's plate).

A part is a fixed-base pybullet multibody whose one link holds the boxes and slides on a
prismatic joint. Its offset along the axis is a function of the integer tick (a `Travel`: legs
at constant speed and holds, worked out when a move starts), and after every tick the joint is
set to it with the velocity that carries the link to the next tick's offset; a velocity motor
with a large force keeps that velocity through the tick. Why a jointed link and not a moved
fixed box: Bullet gives a fixed body no velocity in the contact solver, so a box put 3.3 mm
further at every tick (0.5 m/s at 150 Hz) pushed a bottle 3 cm deep into itself before the
penetration recovery kept pace, and the bottle left at 0.4 m/s. The link's velocity reaches the
contact: the bottle is pushed at the plate's speed, touching it. It leaves a little faster,
because in the tick of the first contact the plate is up to one tick's travel into it and the
engine pushes it out with velocity of its own (a multibody contact has no split impulse):
measured at 0.5 m/s and 150 Hz, 0.51–0.59 m/s on a floor (tests/physics/test_moving.py), up to
0.66 m/s against a running belt's grip in the bottling plant, tilting the bottle by up to 3°.

The link collides only with dynamic bodies (filter group 4, mask 1): it slides through the
rails and over the floor it stands next to. Standing, it is asleep in the engine and its motor
holds it against anything that leans on it.

A resting bottle (rest.py) is asleep in the engine, and a kinematic link that comes near it
must wake it first: the hub wakes, before every tick of a move, the resting bodies whose boxes
join the part's box — the engine's box of the link at its offset, widened like every awake
body's by the shapes' margins and the contact breaking threshold, and by where the part is
headed in that tick — and their groups, the rule rest.py applies to awake bottles. A still
bottle is not put to rest inside a moving part's box either (hub/physics/sleep.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hub.core import state
from hub.physics._quiet import quiet_stderr
from hub.physics.changes import PartsMoving
from hub.physics.rest import BREAKING, SHAPE_MARGIN

with quiet_stderr():
    import pybullet

MASS = 100.0      # kg: the link's mass, heavy against a bottle, so a contact within a tick barely slows it
FORCE = 1e4       # N: the joint motor's limit, far beyond what bottles lean on it with
GROUP, MASK = 4, 1   # collides with dynamic bodies (pybullet's group 1) only, not with fixed ones (group 2)


@dataclass(frozen=True)
class Leg:
    """Go to `to` (m along the part's axis from where it was made) at `speed` m/s, then hold there `hold` s."""

    to: float
    speed: float
    hold: float = 0.0


@state.value
class Travel:
    """A part's offset as a function of the integer tick: its legs one after the other from
    `start`, each at constant speed over a whole number of ticks (the last tick of a leg moves
    what is left), each hold a whole number of ticks. No time is accumulated."""

    def __init__(self, start: int, offset: float, legs, rate: int):
        self.start = start
        self.arrivals: list[int] = []   # the tick each leg arrives at its offset
        self._segments: list[tuple[int, int, float, float]] = []   # (from tick, until tick, offset, m per tick)
        tick, at = start, float(offset)
        for leg in legs:
            if not leg.speed > 0.0:
                raise ValueError(f"a leg's speed must be positive, not {leg.speed!r}")
            distance, per_tick = abs(leg.to - at), leg.speed / rate
            ticks = math.ceil(distance / per_tick - 1e-9) if distance > 0.0 else 0
            self._segments.append((tick, tick + ticks, at, math.copysign(per_tick, leg.to - at)))
            tick += ticks
            self.arrivals.append(tick)
            at = float(leg.to)
            hold = max(0, round(leg.hold * rate))
            if hold:
                self._segments.append((tick, tick + hold, at, 0.0))
                tick += hold
        self.end = tick
        self.final = at

    def at(self, tick: int) -> float:
        for t0, t1, offset, step in self._segments:
            if tick < t1:
                return offset + step * max(0, tick - t0)
        return self.final


class MovingPart:
    """One part: its boxes, given in the world frame where it stands at offset 0, on a link that
    slides along the unit vector `axis`."""

    STATE = ("offset", "velocity", "travel")   # hub/core/state.py; the joint is the engine's

    def __init__(self, engine, rate: int, centers, half_extents, yaws, axis):
        self.engine = engine
        self.rate = rate
        self.axis = np.asarray(axis, float)
        norm = float(np.linalg.norm(self.axis))
        if not norm > 0.0:
            raise ValueError(f"a moving part's axis must not be zero: {axis!r}")
        self.axis /= norm
        origin = np.asarray(centers[0], float)
        shape = engine.boxes_shape([np.asarray(c, float) - origin for c in centers], half_extents, yaws)
        call = engine.call
        self.body = call(pybullet.createMultiBody, baseMass=0.0, baseCollisionShapeIndex=-1,
                         basePosition=origin.tolist(), linkMasses=[MASS], linkCollisionShapeIndices=[shape],
                         linkVisualShapeIndices=[-1], linkPositions=[[0.0, 0.0, 0.0]],
                         linkOrientations=[[0.0, 0.0, 0.0, 1.0]], linkInertialFramePositions=[[0.0, 0.0, 0.0]],
                         linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]], linkParentIndices=[0],
                         linkJointTypes=[pybullet.JOINT_PRISMATIC], linkJointAxis=[self.axis.tolist()])
        engine.frictionless(self.body, 0)
        call(pybullet.setCollisionFilterGroupMask, self.body, 0, GROUP, MASK)
        engine.set_motor(self.body, 0, 0.0, FORCE)
        engine.sleep(self.body)
        lo, hi = (np.asarray(v, float) for v in engine.aabb(self.body, 0))
        self._centre, self._half = (lo + hi) / 2.0, (hi - lo) / 2.0
        self.offset = 0.0          # m along the axis at the current tick
        self.velocity = 0.0        # m/s along the axis over the coming tick
        self.travel: Travel | None = None

    @property
    def moving(self) -> bool:
        return self.travel is not None

    def move(self, tick: int, legs) -> Travel:
        """Start the legs from this tick on (replacing any move under way); returns the Travel,
        whose `arrivals` and `end` say at which tick each leg and the whole move end."""
        travel = Travel(tick, self.offset, legs, self.rate)
        if self.travel is None:
            self.engine.wake(self.body)
        self.travel = travel
        self._set(tick)
        return travel

    def update(self, tick: int) -> bool:
        """After a tick: the joint at its offset for `tick` and the velocity towards the next one.
        Returns whether the part moved."""
        if self.travel is None:
            return False
        self._set(tick)
        return True

    def _set(self, tick: int) -> None:
        travel = self.travel
        offset = travel.at(tick)
        done = tick >= travel.end
        velocity = 0.0 if done else (travel.at(tick + 1) - offset) * self.rate
        call = self.engine.call
        call(pybullet.resetJointState, self.body, 0, offset, velocity)
        if velocity != self.velocity:
            self.engine.set_motor(self.body, 0, velocity, FORCE)
        self.offset, self.velocity = offset, velocity
        if done:
            self.travel = None
            self.engine.sleep(self.body)

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(centre, half extents) of the part's box for the coming tick, as the wake rule widens it."""
        reach = np.abs(self.axis) * (abs(self.velocity) / self.rate)
        return self._centre + self.axis * self.offset, self._half + (SHAPE_MARGIN + BREAKING) + reach


class MovingParts:
    """The world's moving parts, and the ones under way: waking what they come near, before each tick."""

    STATE = ("parts",)

    def __init__(self, engine, rate: int, changes):
        self.engine = engine
        self.rate = rate
        self.changes = changes           # where the parts under way are announced (changes.py)
        self.parts: list[MovingPart] = []

    @property
    def moving(self) -> bool:
        return any(part.travel is not None for part in self.parts)

    def add(self, centers, half_extents, yaws, axis) -> MovingPart:
        part = MovingPart(self.engine, self.rate, centers, half_extents, yaws, axis)
        self.parts.append(part)
        return part

    def bodies(self) -> set[int]:
        """The parts' bodies."""
        return {part.body for part in self.parts}

    def boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """(centres, half extents) of the parts under way, as the wake rule widens them."""
        boxes = [part.box() for part in self.parts if part.travel is not None]
        return np.array([c for c, _ in boxes]), np.array([e for _, e in boxes])

    def sweep(self) -> None:
        """Before a tick: announce the boxes the parts under way sweep (changes.PartsMoving): what
        rests in them wakes."""
        self.changes.announce(PartsMoving(*self.boxes()))

    def update(self, tick: int) -> None:
        for part in self.parts:
            part.update(tick)
