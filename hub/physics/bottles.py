"""Bottles at their level of detail: how each is made in the engine, and where and how a belt drives it."""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.frames import base_points
from hub.physics.transport import LOOKAHEAD

with quiet_stderr():
    import pybullet

GRIPS = ("centre", "base", "base_body")
TRANSPORTS = ("free", "engine")


class Bottles:
    """Makes the world's bottles (upright dynamic bodies) into its body table and applies the
    belts' forces to them where each is gripped: at its centre of mass, at its base point, or
    on the paper's second body at its base (`grip_at`)."""

    STATE = ("_grips",)   # hub/core/state.py: the grip table, made at the first drive

    def __init__(self, engine, bodies, rest, transport):
        self.engine = engine
        self.bodies = bodies
        self.rest = rest
        self.transport = transport
        self.base_offsets: dict[int, float] = {}   # bottle → COM height above its base (grip at base)
        self.base_bodies: dict[int, int] = {}      # bottle → its second body (the paper's model)
        self._grips = None

    def add_cylinder(self, base, radius: float, height: float, mass: float, label: str) -> int:
        """An upright dynamic cylinder standing on `base` (the centre of its bottom face)."""
        self.bodies.check_open()
        call = self.engine.call
        shape = call(pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=radius, height=height)
        center = (base[0], base[1], base[2] + height / 2.0)
        body = call(pybullet.createMultiBody, baseMass=mass, baseCollisionShapeIndex=shape, basePosition=center)
        self.engine.frictionless(body)
        call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
             linearDamping=0.0, angularDamping=0.0)
        index = self.bodies.add(body, label, mass, radius, height / 2.0)
        self.rest.add(False, radius, height / 2.0)   # a one-link multibody: Bullet's sleeping differs there
        self.transport.add(False)
        return index

    def add(self, base, radius: float, height: float, mass: float, label: str, *, hull=None,
            grip_at: str = "centre", base_fraction: float = 0.05, ring: float, maximal: bool,
            transport: str = "free", lookahead: int = LOOKAHEAD) -> int:
        """An upright bottle standing on `base` (the centre of its bottom face).

        Collision shape: the cylinder's body `ring` narrower than `radius`, with its widest ring
        (the sphere of `radius` about the centre of mass) where it touches others — or a plain
        cylinder for a bottle wider than half its height, where that sphere would reach below
        the base — or the convex hull of `hull` (points relative to `base`); the inertia is the
        homogeneous cylinder's, as in the paper. The belt grips it at `grip_at`: `centre` (its
        centre of mass), `base` (its base point: the force there adds the torque of friction at
        the bottom), or `base_body` (the paper's model: a second body of `base_fraction` of the
        mass at the base, under a fixed constraint, takes the force). `maximal`: a rigid body in
        maximal coordinates rather than a one-link multibody (PhysicsWorld says why).
        `transport`: `free` (the default) lets a plain rigid bottle (no hull, no second body: those
        stay in the engine) leave the engine while it rides a belt on which nothing can touch it,
        looking `lookahead` ticks forward (transport.py); `engine` keeps it in the engine throughout.
        """
        if transport not in TRANSPORTS:
            raise ValueError(f"transport must be free or engine, not {transport!r}")
        self.bodies.check_open()
        if grip_at not in GRIPS:
            raise ValueError(f"grip_at must be centre, base or base_body, not {grip_at!r}")
        call = self.engine.call
        half = height / 2.0
        main_mass = mass * (1.0 - base_fraction) if grip_at == "base_body" else mass
        ring = ring if hull is None and radius <= half else 0.0
        if hull is not None:
            points = [[float(x), float(y), float(z) - half] for x, y, z in hull]
            shape = call(pybullet.createCollisionShape, pybullet.GEOM_MESH, vertices=points)
        elif ring:
            shape = call(pybullet.createCollisionShapeArray,
                         shapeTypes=[pybullet.GEOM_CYLINDER, pybullet.GEOM_SPHERE],
                         radii=[radius * (1.0 - ring), radius], lengths=[height, 0.0],
                         collisionFramePositions=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
        else:
            shape = call(pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=radius, height=height)
        center = (base[0], base[1], base[2] + half)
        body = call(pybullet.createMultiBody, baseMass=main_mass, baseCollisionShapeIndex=shape,
                    basePosition=center, useMaximalCoordinates=maximal and grip_at != "base_body")
        self.engine.frictionless(body)
        across = main_mass * (3 * radius ** 2 + height ** 2) / 12.0
        # The mass again: pybullet zeroes a maximal-coordinate body's mass when only its inertia is set.
        call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
             linearDamping=0.0, angularDamping=0.0, mass=main_mass,
             localInertiaDiagonal=[across, across, main_mass * radius ** 2 / 2.0])
        index = len(self.bodies)
        if grip_at == "base":
            self.base_offsets[index] = half
        elif grip_at == "base_body":
            m = mass * base_fraction
            second = call(pybullet.createMultiBody, baseMass=m, baseCollisionShapeIndex=-1, basePosition=tuple(base))
            call(pybullet.changeDynamics, second, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
                 linearDamping=0.0, angularDamping=0.0,
                 localInertiaDiagonal=[m * radius ** 2 / 4, m * radius ** 2 / 4, m * radius ** 2 / 2])
            joint = call(pybullet.createConstraint, body, -1, second, -1, pybullet.JOINT_FIXED, [0, 0, 0],
                         [0, 0, -half], [0, 0, 0])
            call(pybullet.changeConstraint, joint, maxForce=1e4)
            self.base_bodies[index] = second
        self.bodies.add(body, label, mass, radius, half)
        # Rests, and rides free, only as a plain rigid body whose box rest.boxes knows (no hull, no second body).
        plain = maximal and hull is None and grip_at != "base_body"
        self.rest.add(plain, radius, half)
        self.transport.add(plain and transport == "free", lookahead)
        return index

    def parts(self, body: int):
        """The pybullet bodies of one bottle with their height relative to its centre: the body,
        and the paper's second body at its base when it has one."""
        yield self.bodies.ids[body], 0.0
        if body in self.base_bodies:
            yield self.base_bodies[body], -float(self.bodies.half_heights[body])

    def drive(self, fields) -> None:
        """Apply every belt's force for this tick where it grips each bottle on a belt in the
        engine (free transport moves its bottles by the same law itself: transport.py).

        A bottle is on a belt when its centre of mass is over it; only then is its grip point
        worked out (its base, or its second body's state read), so a bottle off every belt
        costs no more at any level of detail.
        """
        b = self.bodies
        if b.stale:
            b.refresh()
        rows = b.live_rows           # parked, resting and free bodies are not even looked for
        field = b.under if b.under is not None else b.fields_under(fields, rows)
        if rows is None:
            rows = np.arange(len(field))
        if self._grips is None:
            offsets = np.zeros(len(b.ids))
            for n, offset in self.base_offsets.items():
                offsets[n] = offset
            targets = np.array([self.base_bodies.get(n, i) for n, i in enumerate(b.ids)], dtype=int)
            self._grips = (offsets, targets, np.array(b.ids, dtype=int))
        offsets, targets, ids = self._grips
        client = self.engine.client
        if not (self.base_offsets or self.base_bodies):
            # Every bottle gripped at its centre (a plant's): which bodies are on a belt, and their
            # forces and torques, in one compiled call.
            bodies, points, fx, fy, torques = fields.drive_rows(rows, field, b.positions, b.velocities, b.masses,
                                                                b.radii, b.angular_velocities)
            if len(bodies) == 0:
                return
        else:
            on = field >= 0
            bodies, f = rows[on], field[on]
            if len(bodies) == 0:
                return
            points, velocities = b.positions[bodies], b.velocities[bodies]
            if self.base_offsets:
                rows = np.flatnonzero(offsets[bodies] > 0.0)
                if len(rows):
                    n = bodies[rows]
                    points[rows], velocities[rows] = base_points(
                        b.positions[n], b.orientations[n], b.velocities[n], b.angular_velocities[n], offsets[n])
            if self.base_bodies:
                for row, n in enumerate(bodies.tolist()):
                    second = self.base_bodies.get(n)
                    if second is not None:
                        # The paper's model: the field sees the second body's own position and velocity.
                        points[row] = pybullet.getBasePositionAndOrientation(second, client)[0]
                        velocities[row] = pybullet.getBaseVelocity(second, client)[0]
            fx, fy, torques = fields.drive(f, points, velocities, b.masses[bodies], b.radii[bodies],
                                           b.angular_velocities[bodies, 2])
        # A world-frame force acts at `at`: the centre of mass adds no torque, the base does.
        # Positional arguments: keywords cost pybullet's argument parser a tenth of the call.
        apply, frame = pybullet.applyExternalForce, pybullet.WORLD_FRAME
        for target, x, y, at in zip(targets[bodies].tolist(), fx.tolist(), fy.tolist(), points.tolist()):
            apply(target, -1, (x, y, 0.0), at, frame, client)
        # The surface also grips the base against spinning; only bottles that spin get a call (a
        # handful of bodies: plain lists cost less than numpy's selection).
        twist = pybullet.applyExternalTorque
        for target, torque in zip(ids[bodies].tolist(), torques.tolist()):
            if torque:
                twist(target, -1, (0.0, 0.0, torque), frame, client)
