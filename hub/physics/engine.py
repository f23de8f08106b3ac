"""The engine: one headless pybullet client, how it is set up, and the static geometry (floors, rails) in it."""
from __future__ import annotations

import os
import tempfile

import numpy as np

from hub.core.errors import CheckpointError
from hub.physics import supports
from hub.physics._quiet import quiet_stderr

with quiet_stderr():
    import pybullet


#: pybullet's collision filter group and mask of a dynamic body, as it makes one.
DYNAMIC = (1, -1)


class Engine:
    """A pybullet client in DIRECT mode stepped at a fixed step of `dt`, and the calls every part
    of the world makes on it: static boxes, friction off, bodies put to sleep and woken.

    pybullet is deterministic only for an identical sequence of calls, so every part creates
    its bodies before the first step and goes through the same few calls here in a fixed order.
    """

    def __init__(self, dt: float, gravity: float, solver_iterations: int):
        self.client = pybullet.connect(pybullet.DIRECT)
        self.call(pybullet.setGravity, 0.0, 0.0, gravity)
        self.call(
            pybullet.setPhysicsEngineParameter,
            fixedTimeStep=dt,
            numSubSteps=0,
            numSolverIterations=solver_iterations,
            deterministicOverlappingPairs=1,
        )
        self._supports: list[supports.SupportArea] = []
        # Every fixed box made here, (body, centre, half extents, yaw) in the world frame: the
        # world's box and the placement check at load read them (watch.py, placement.py).
        self.static: list[tuple[int, tuple, tuple, float]] = []
        self.floors: set[int] = set()   # the bodies of the merged floors among them
        # What the hub set on bodies that the engine's own saved state does not hold
        # (save_state): each (body, link)'s collision filter, whether a body was put to sleep
        # or woken last, each joint motor's target velocity and force.
        self.filters: dict[tuple[int, int], tuple[int, int]] = {}
        self.asleep: dict[int, bool] = {}
        self.motors: dict[tuple[int, int], tuple[float, float]] = {}
        # Bullet numbers every collision object's broadphase entry as it makes it (a counter
        # that only goes up), and a filter change makes the entry again: `refreshes` counts
        # those remakings and `refreshed` says when each (body, link) was last remade. The
        # numbers order the contact pairs and the solver's rows, and restoreState finds bodies
        # and contact points by them (restore_state makes them again in the same order).
        self.refreshes = 0
        self.refreshed: dict[tuple[int, int], int] = {}

    @property
    def solver_iterations(self) -> int:
        """The constraint solver's iterations per tick, as the engine has them."""
        return int(self.call(pybullet.getPhysicsEngineParameters)["numSolverIterations"])

    def call(self, fn, *args, **kwargs):
        return fn(*args, physicsClientId=self.client, **kwargs)

    def step(self) -> None:
        pybullet.stepSimulation(self.client)

    # --- static geometry ------------------------------------------------------------------
    def add_static_box(self, center, half_extents, yaw: float = 0.0) -> None:
        """A fixed box (support surface, guard rail) with friction and restitution 0, as in the paper."""
        shape = self.call(pybullet.createCollisionShape, pybullet.GEOM_BOX, halfExtents=list(half_extents))
        body = self.call(
            pybullet.createMultiBody,
            baseMass=0.0,
            baseCollisionShapeIndex=shape,
            basePosition=list(center),
            baseOrientation=pybullet.getQuaternionFromEuler((0.0, 0.0, yaw)),
        )
        self.frictionless(body)
        self.static.append((body, tuple(center), tuple(half_extents), float(yaw)))

    def add_static_boxes(self, centers, half_extents, yaws) -> None:
        """One fixed body made of boxes (a guard rail along an arc), frictionless like every rail."""
        body = self.boxes_body(centers, half_extents, yaws)
        self.frictionless(body)
        self.static.extend((body, tuple(c), tuple(h), float(y)) for c, h, y in zip(centers, half_extents, yaws))

    def boxes_body(self, centers, half_extents, yaws) -> int:
        """A fixed body made of yawed boxes placed in the world frame."""
        shape = self.boxes_shape(centers, half_extents, yaws)
        return self.call(pybullet.createMultiBody, baseMass=0.0, baseCollisionShapeIndex=shape)

    def boxes_shape(self, centers, half_extents, yaws) -> int:
        """One collision shape of yawed boxes, placed relative to the frame of the body that takes it."""
        return self.call(
            pybullet.createCollisionShapeArray,
            shapeTypes=[pybullet.GEOM_BOX] * len(centers),
            halfExtents=[list(h) for h in half_extents],
            collisionFramePositions=[list(c) for c in centers],
            collisionFrameOrientations=[pybullet.getQuaternionFromEuler((0.0, 0.0, y)) for y in yaws],
        )

    def add_support(self, z: float, rect, thickness: float = 0.02) -> None:
        """Declare a belt's floor (xmin, ymin, xmax, ymax) at height z; touching floors become one
        box when the world starts (see supports.py: a seam between boxes tips bottles)."""
        self._supports.append(supports.SupportArea(float(z), tuple(float(v) for v in rect), thickness))

    def build_supports(self) -> None:
        for area in supports.merge(self._supports):
            center, half = supports.box(area)
            self.add_static_box(center, half)
            self.floors.add(self.static[-1][0])
        self._supports = []

    def static_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per fixed box its bounding box (lo, hi), rows in `static` order, worked out from its
        extents without asking the engine."""
        if not self.static:
            return np.zeros((0, 3)), np.zeros((0, 3))
        centre = np.array([c for _, c, _, _ in self.static], float)
        half = np.array([h for _, _, h, _ in self.static], float)
        yaw = np.array([y for _, _, _, y in self.static], float)
        c, s = np.abs(np.cos(yaw)), np.abs(np.sin(yaw))
        reach = np.stack([c * half[:, 0] + s * half[:, 1], s * half[:, 0] + c * half[:, 1], half[:, 2]], 1)
        return centre - reach, centre + reach

    # --- per body -------------------------------------------------------------------------
    def frictionless(self, body: int, link: int = -1) -> None:
        self.call(
            pybullet.changeDynamics, body, link,
            lateralFriction=0.0, spinningFriction=0.0, rollingFriction=0.0, restitution=0.0,
        )

    def set_filter(self, body: int, link: int, group: int, mask: int) -> None:
        """A body's (or link's) collision filter group and mask: (0, 0) takes it out of every pair."""
        self.call(pybullet.setCollisionFilterGroupMask, body, link, group, mask)
        self.filters[body, link] = (group, mask)
        self.refreshed[body, link] = self.refreshes
        self.refreshes += 1

    def set_motor(self, body: int, joint: int, velocity: float, force: float) -> None:
        """A joint's velocity motor: its target velocity and the most force it may use."""
        self.call(pybullet.setJointMotorControl2, body, joint, pybullet.VELOCITY_CONTROL, targetVelocity=velocity,
                  force=force)
        self.motors[body, joint] = (velocity, force)

    def sleep(self, body: int) -> None:
        """Leave a body asleep: the engine stops integrating it until something awake joins its island."""
        self.asleep[body] = True
        self.call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_ENABLE_SLEEPING)
        self.call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_SLEEP)

    def wake(self, body: int) -> None:
        """Wake a body and keep Bullet's own sleeping rule off it (it would stop a bottle riding a belt)."""
        self.asleep[body] = False
        self.call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_WAKE_UP)
        self.call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING)

    def fixed_bodies(self) -> set[int]:
        """The fixed bodies made here (floors, rails)."""
        return {body for body, _, _, _ in self.static}

    def leave(self, body: int) -> None:
        """Take a dynamic body out of the collision world and put it to sleep: the engine keeps
        no pair, contact or island for it (a resting, parked or free bottle). With the
        ~50 resting bottles of the bottling plant's busiest window out, the engine's part of the
        hub's tick fell from 1662 to 1150 µs (`python -m tests.bench_bottling`)."""
        self.set_filter(body, -1, 0, 0)
        self.sleep(body)

    def rejoin(self, body: int) -> None:
        """Put a body that left back into the collision world, awake (pybullet's group and mask for a dynamic body)."""
        self.set_filter(body, -1, *DYNAMIC)
        self.wake(body)

    def bodies(self) -> list[int]:
        """Every body in the engine, whoever made it."""
        return [self.call(pybullet.getBodyUniqueId, i) for i in range(self.call(pybullet.getNumBodies))]

    def shaped_boxes(self, body: int) -> list[tuple]:
        """(centre, half extents, yaw 0) of the box the engine bounds each of a body's links by
        that has a collision shape, as it stands now."""
        found = []
        for link in range(-1, self.call(pybullet.getNumJoints, body)):
            if self.call(pybullet.getCollisionShapeData, body, link):
                lo, hi = (np.asarray(v, float) for v in self.aabb(body, link))
                found.append((tuple((lo + hi) / 2), tuple((hi - lo) / 2), 0.0))
        return found

    def aabb(self, body: int, link: int = -1) -> tuple[tuple, tuple]:
        """The box (lo, hi) the engine bounds a body (or one of its links) by, without its pair-search widening."""
        return self.call(pybullet.getAABB, body, link)

    # --- state (hub/core/state.py) ----------------------------------------------------------
    STATE = ("filters", "asleep", "motors", "refreshes", "refreshed")

    def save_state(self) -> dict:
        """The engine's whole dynamic state: its own (bodies' poses and velocities, joint states,
        contact points with their cached impulses, as pybullet's saveBullet writes them) and what
        the hub set that it does not hold (filters, sleep, motors, the broadphase's numbering)."""
        return {"bullet": self._bullet(), "filters": dict(self.filters), "asleep": dict(self.asleep),
                "motors": dict(self.motors), "refreshes": self.refreshes, "refreshed": dict(self.refreshed)}

    def restore_state(self, saved: dict) -> None:
        """Put back an engine state saved from a world of the same build, into a world freshly
        built (one that has not run past the save): the filters first, remade in the saved order
        so that every collision object gets the broadphase number it had (pybullet's restoreState
        finds bodies and contact points by that number, and the solver orders its rows by it);
        then sleep and motors, then the engine's own state. A freshly built world then continues
        exactly as the saved one did (tests/test_checkpoint.py)."""
        self._renumber(saved["refreshes"], saved["refreshed"], saved["filters"])
        for body in sorted(set(self.asleep) | set(saved["asleep"])):
            want = saved["asleep"].get(body, False)
            if self.asleep.get(body) != want:
                (self.sleep if want else self.wake)(body)
        for key, (velocity, force) in sorted(saved["motors"].items()):
            if self.motors.get(key) != (velocity, force):
                self.set_motor(*key, velocity, force)
        self.asleep, self.motors = dict(saved["asleep"]), dict(saved["motors"])
        fd, path = tempfile.mkstemp(suffix=".bullet", dir=_SCRATCH)
        try:
            with os.fdopen(fd, "wb") as out:
                out.write(saved["bullet"])
            self.call(pybullet.restoreState, fileName=path)
        except pybullet.error as exc:
            raise CheckpointError(f"the engine's saved state does not fit this world: {exc}") from None
        finally:
            os.unlink(path)

    def _renumber(self, refreshes: int, refreshed: dict, filters: dict) -> None:
        """Remake collision objects' broadphase entries until each has the number it had when
        saved: those last remade after this world's own remakings, in their saved order, each
        remade as often as the counter needs to reach its number (a remaking only counts up, and
        every remaking between two last ones was of an object remade again later)."""
        if refreshes < self.refreshes or any(refreshed.get(key, -1) < at for key, at in self.refreshed.items()):
            raise CheckpointError("the engine's saved state is of an earlier point than this world's: "
                                  "a checkpoint is put back into a freshly built world")
        for at, key in sorted((at, key) for key, at in refreshed.items() if at >= self.refreshes
                              and self.refreshed.get(key) != at):
            while self.refreshes <= at:
                self.set_filter(*key, *filters[key])
        if self.refreshes != refreshes:
            raise CheckpointError(f"the engine's saved numbering is inconsistent: {refreshes} remakings saved, "
                                  f"{self.refreshes} made again")

    def _bullet(self) -> bytes:
        """pybullet's saveBullet, which writes only to a file: a scratch file in memory where there is one."""
        fd, path = tempfile.mkstemp(suffix=".bullet", dir=_SCRATCH)
        os.close(fd)
        try:
            self.call(pybullet.saveBullet, path)
            with open(path, "rb") as saved:
                return saved.read()
        finally:
            os.unlink(path)

    def close(self) -> None:
        if self.client is not None:
            pybullet.disconnect(physicsClientId=self.client)
            self.client = None


#: Where the engine's state passes through a file: memory-backed where the system has it.
_SCRATCH = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
