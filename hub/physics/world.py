"""The pybullet material-flow world: static geometry, upright bodies, force fields and triggers."""
from __future__ import annotations

import math

import numpy as np

from ._quiet import quiet_stderr

with quiet_stderr():
    import pybullet

from .fields import ForceFields
from .triggers import Latch, VolumeTriggers


class PhysicsWorld:
    """A headless pybullet world stepped in integer ticks of 1/rate seconds.

    Every pybullet call of planthub lives in this class. Each substep reads the state of all
    dynamic bodies once; force fields and triggers work on those arrays with numpy, which is
    far cheaper than one pybullet query per body and volume. Bodies are created before the
    first step and never reset inside the loop, because pybullet is deterministic only for an
    identical sequence of calls.
    """

    def __init__(self, rate: int, gravity: float = -9.81, solver_iterations: int = 50):
        self.rate = rate
        self.dt = 1.0 / rate
        self.tick = 0
        self._client = pybullet.connect(pybullet.DIRECT)
        self._call(pybullet.setGravity, 0.0, 0.0, gravity)
        self._call(
            pybullet.setPhysicsEngineParameter,
            fixedTimeStep=self.dt,
            numSubSteps=0,
            numSolverIterations=solver_iterations,
            deterministicOverlappingPairs=1,
        )
        self.fields = ForceFields(self.dt)
        self.triggers = VolumeTriggers()
        self._bodies: list[int] = []
        self.labels: list[str] = []
        self.masses = np.zeros(0)
        self.radii = np.zeros(0)
        self.half_heights = np.zeros(0)
        self.positions = np.zeros((0, 3))
        self.orientations = np.zeros((0, 4))
        self.velocities = np.zeros((0, 3))
        self._started = False

    def _call(self, fn, *args, **kwargs):
        return fn(*args, physicsClientId=self._client, **kwargs)

    # --- building -------------------------------------------------------------------------
    def add_static_box(self, center, half_extents, yaw: float = 0.0) -> None:
        """A fixed box (support surface, guard rail) with friction and restitution 0, as in the paper."""
        shape = self._call(pybullet.createCollisionShape, pybullet.GEOM_BOX, halfExtents=list(half_extents))
        body = self._call(
            pybullet.createMultiBody,
            baseMass=0.0,
            baseCollisionShapeIndex=shape,
            basePosition=list(center),
            baseOrientation=pybullet.getQuaternionFromEuler((0.0, 0.0, yaw)),
        )
        self._frictionless(body)

    def add_cylinder(self, base, radius: float, height: float, mass: float, label: str) -> int:
        """An upright dynamic cylinder standing on `base` (the centre of its bottom face)."""
        if self._started:
            raise RuntimeError("bodies must be created before the first step")
        shape = self._call(pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=radius, height=height)
        center = (base[0], base[1], base[2] + height / 2.0)
        body = self._call(
            pybullet.createMultiBody, baseMass=mass, baseCollisionShapeIndex=shape, basePosition=center
        )
        self._frictionless(body)
        self._call(
            pybullet.changeDynamics, body, -1,
            activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
            linearDamping=0.0, angularDamping=0.0,
        )
        self._bodies.append(body)
        self.labels.append(label)
        self.masses = np.append(self.masses, mass)
        self.radii = np.append(self.radii, radius)
        self.half_heights = np.append(self.half_heights, height / 2.0)
        return len(self._bodies) - 1

    def _frictionless(self, body: int) -> None:
        self._call(
            pybullet.changeDynamics, body, -1,
            lateralFriction=0.0, spinningFriction=0.0, rollingFriction=0.0, restitution=0.0,
        )

    def add_force_field(self, center, half_extents, yaw: float, k: float, speed: float) -> int:
        return self.fields.add(center, half_extents, yaw, k, speed)

    def set_field_speed(self, field: int, speed: float) -> None:
        self.fields.set_speed(field, speed)

    def add_trigger(self, center, half_extents, yaw: float = 0.0) -> int:
        return self.triggers.add(center, half_extents, yaw)

    def take_trigger(self, trigger: int) -> Latch:
        return self.triggers.take(trigger)

    # --- stepping -------------------------------------------------------------------------
    def start(self) -> None:
        """Freeze the body set and read the initial state (tick 0); idempotent."""
        if not self._started:
            self._started = True
            self._read_state()
            self.triggers.evaluate(self.tick, self.positions, self.radii, self.half_heights)

    def step(self, substeps: int, stop_on_event: bool = False) -> int:
        """Advance up to `substeps` ticks: force fields applied and triggers evaluated at every tick.

        With `stop_on_event`, stop after the first tick at which a trigger saw an object enter
        or leave. Returns the number of ticks advanced.
        """
        self.start()
        for done in range(1, substeps + 1):
            bodies, forces = self.fields.forces(self.positions, self.velocities, self.masses)
            positions = self.positions[bodies].tolist()
            for n, force, at in zip(bodies.tolist(), forces.tolist(), positions):
                # A world-frame force must be applied at the body's position, or it adds a torque.
                pybullet.applyExternalForce(self._bodies[n], -1, force, at, pybullet.WORLD_FRAME,
                                            physicsClientId=self._client)
            pybullet.stepSimulation(physicsClientId=self._client)
            self.tick += 1
            self._read_state()
            event = self.triggers.evaluate(self.tick, self.positions, self.radii, self.half_heights)
            if event and stop_on_event:
                return done
        return substeps

    def step_engine_only(self, substeps: int) -> None:
        """Only pybullet's own stepping, no state reads, fields or triggers: the floor for benchmarks."""
        self.start()
        for _ in range(substeps):
            self._call(pybullet.stepSimulation)
        self.tick += substeps

    def _read_state(self) -> None:
        # One position and one velocity query per body; per-body calls cannot be batched in
        # pybullet, so keep the Python around them minimal and build the arrays in one go.
        client, bodies = self._client, self._bodies
        if not bodies:
            return
        pose = pybullet.getBasePositionAndOrientation
        velocity = pybullet.getBaseVelocity
        poses = [pose(b, physicsClientId=client) for b in bodies]
        self.positions = np.array([p for p, _ in poses])
        self.orientations = np.array([o for _, o in poses])
        self.velocities = np.array([velocity(b, physicsClientId=client)[0] for b in bodies])

    def tilt(self, body: int) -> float:
        """Angle in radians between the body's axis and the plumb line."""
        x, y, z, w = self.orientations[body]
        # z component of the body's rotated up axis: 1 − 2(x² + y²).
        return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))

    def close(self) -> None:
        if self._client is not None:
            pybullet.disconnect(physicsClientId=self._client)
            self._client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

