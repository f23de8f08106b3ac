"""The pybullet material-flow world: static geometry, upright bodies, force fields and triggers."""
from __future__ import annotations

import math
from itertools import chain

import numpy as np

from hub.physics._quiet import quiet_stderr

with quiet_stderr():
    import pybullet

from hub.physics import supports
from hub.physics.fields import ForceFields
from hub.physics.frames import Arc, Pose, Straight, base_points
from hub.physics.rest import Rest, boxes
from hub.physics.robot import KinematicArm
from hub.physics.triggers import Latch, VolumeTriggers

PARKED = (-100.0, 0.0, -100.0)   # off stage: parked bodies wait here, 0.5 m apart along y


class PhysicsWorld:
    """A headless pybullet world stepped in integer ticks of 1/rate seconds.

    Every pybullet call of planthub lives in this class. Each substep reads the state of every
    body in play once, except those at rest (rest.py: asleep in the engine, their state
    stands); force fields and triggers work on those arrays with numpy, which is far cheaper
    than one pybullet query per body and volume. Bodies are created before the
    first step and never reset inside the loop, because pybullet is deterministic only for an
    identical sequence of calls.
    """

    # How the engine is set up; class attributes so that benchmarks can vary them (tests/bench_queue.py).
    #
    # RING: a bottle touches its neighbours, gates and rails at its widest ring, at the height of
    # its centre of mass, with a body RING narrower above and below (a sphere of the bottle's
    # radius there, in one compound with the body cylinder). Bullet resolves the side contact
    # of two cylinders, or of a cylinder and a box, at one point per tick, which jumps between
    # the top and bottom rim: a pressed queue rocks and ratchets into its contacts (12 bottles
    # pressed against a stopper at 150 Hz: the first 22 mm into the gate, neighbours 17 mm into
    # each other, 13 mm into the floor, tilt 12°; as a multibody at 50 iterations 31 mm and 21°).
    # At the ring the push acts where the resultant of a real bottle's line contact acts,
    # through the centre of mass: 0.01 mm, 1.2 mm, 0.1 mm, tilt under 1° (tests/bench_queue.py).
    # 5 %: the narrower base makes a 20 g bottle rock 6° instead of 4° in the paper's tipping
    # test; at 10 % it falls over there.
    # MAXIMAL: bottles are rigid bodies in maximal coordinates (Bullet's btRigidBody), not
    # one-link multibodies: 15-30 % less engine time per bottle, and penetration is recovered
    # without adding velocity (split impulse). The paper's two-body model stays a multibody pair:
    # its fixed constraint leans differently between rigid bodies (tests/test_bottle_models.py).
    # SOLVER_ITERATIONS: a free bottle needs few (the solver stops once it converges); a pressed
    # queue gives by 0.5 mm per contact at 50, 1.2 mm at 20, 2.3 mm at 10 (40 bottles), and
    # costs 1922, 1274 and 1220 µs per tick (README.md, `python -m tests.bench_queue`).
    RING = 0.05
    MAXIMAL = True
    SOLVER_ITERATIONS = 20

    def __init__(self, rate: int, gravity: float = -9.81, solver_iterations: int | None = None,
                 sleep_after: float = 0.05):
        solver_iterations = solver_iterations or self.SOLVER_ITERATIONS
        self.rate = rate
        self.dt = 1.0 / rate
        self.tick = 0
        self.gravity = abs(gravity)
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
        # Plant elements (see park, add_switchable_boxes, add_arm).
        self.seed = 0                           # the scenario's run.seed, for modules that draw at build time
        self._parked: set[int] = set()
        self.rest = Rest(rate, sleep_after)     # bodies the engine leaves asleep (rest.py)
        self.check_rest = False                 # compare resting bodies with the engine at every tick (tests)
        self._full_read = True                  # the next read takes every body (after a park or unpark)
        self._rows_stale = True                 # the sets below need working out again
        self._live_rows = None                  # rows read per tick: in play and awake (None: every body)
        self._live_ids: list[int] = []
        self._play_rows = None                  # rows in play, not parked (None: every body)
        self._under = None                      # the field under each live row at the last read (−1: none)
        self._switchable: list[int] = []
        self._switchable_boxes: list[tuple] = []  # each part's bounding box (lo, hi), for waking what rests in it
        self.arms: list[KinematicArm] = []
        self._held: dict[KinematicArm, int] = {}   # arm → the body it grips (never rests)
        self._following: list[tuple[int, KinematicArm, np.ndarray]] = []   # (trigger, arm, offset)
        self._bodies: list[int] = []
        self.labels: list[str] = []
        self.masses = np.zeros(0)
        self.radii = np.zeros(0)
        self.half_heights = np.zeros(0)
        self.positions = np.zeros((0, 3))
        self.orientations = np.zeros((0, 4))
        self.velocities = np.zeros((0, 3))
        self._started = False
        # Belts, bottle levels of detail (see add_support, add_belt_field, add_bottle).
        self.angular_velocities = np.zeros((0, 3))
        self.anchors: dict[str, Pose] = {}      # named belt ends, where a belt given `after:` starts
        self._supports: list[supports.SupportArea] = []
        self._base_offsets: dict[int, float] = {}   # bottle → COM height above its base (grip at base)
        self._base_bodies: dict[int, int] = {}      # bottle → its second body (the paper's model)
        self._grips = None

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
        self.rest.add(False, radius, height / 2.0)   # a one-link multibody: Bullet's sleeping differs there
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
        """A belt's speed; bodies resting on it wake when it changes."""
        if speed != self.fields.speeds[field] and self.rest.resting.any():
            self._wake(self.rest.on_field(field, self.positions))
        self.fields.set_speed(field, speed)

    def add_trigger(self, center, half_extents, yaw: float = 0.0) -> int:
        return self.triggers.add(center, half_extents, yaw)

    def take_trigger(self, trigger: int) -> Latch:
        return self.triggers.take(trigger)

    # --- belts and bottles (curves, joined belts, levels of detail) -------------------------
    def add_support(self, z: float, rect, thickness: float = 0.02) -> None:
        """Declare a belt's floor (xmin, ymin, xmax, ymax) at height z; touching floors become one
        box at `start` (see supports.py: a seam between boxes tips bottles)."""
        self._supports.append(supports.SupportArea(float(z), tuple(float(v) for v in rect), thickness))

    def add_static_boxes(self, centers, half_extents, yaws) -> None:
        """One fixed body made of boxes (a guard rail along an arc), frictionless like every rail."""
        self._frictionless(self._boxes_body(centers, half_extents, yaws))

    def _boxes_body(self, centers, half_extents, yaws) -> int:
        """A fixed body made of yawed boxes placed in the world frame."""
        shape = self._call(
            pybullet.createCollisionShapeArray,
            shapeTypes=[pybullet.GEOM_BOX] * len(centers),
            halfExtents=[list(h) for h in half_extents],
            collisionFramePositions=[list(c) for c in centers],
            collisionFrameOrientations=[pybullet.getQuaternionFromEuler((0.0, 0.0, y)) for y in yaws],
        )
        return self._call(pybullet.createMultiBody, baseMass=0.0, baseCollisionShapeIndex=shape)

    def add_belt_field(self, line: Straight | Arc, half_width: float, z_lo: float, z_hi: float, k: float,
                       speed: float, grip: str = "surface", per_mass: bool = True,
                       friction: float | None = None) -> int:
        """A belt's force field; `friction` (μ) caps the acceleration it gives at μ·g."""
        limit = math.inf if friction is None else friction * self.gravity
        return self.fields.add_region(line, half_width, z_lo, z_hi, k, speed, grip=grip, per_mass=per_mass,
                                      limit=limit)

    def add_bottle(self, base, radius: float, height: float, mass: float, label: str, *, hull=None,
                   grip_at: str = "centre", base_fraction: float = 0.05) -> int:
        """An upright bottle standing on `base` (the centre of its bottom face).

        Collision shape: the cylinder's body RING narrower than `radius`, with its widest ring
        (the sphere of `radius` about the centre of mass) where it touches others — or a plain
        cylinder for a bottle wider than half its height, where that sphere would reach below
        the base — or the convex hull of `hull` (points relative to `base`); the inertia is the
        homogeneous cylinder's, as in the paper. The belt grips it at
        `grip_at`: `centre` (its centre of mass), `base` (its base point: the force there adds
        the torque of friction at the bottom), or `base_body` (the paper's model: a second body
        of `base_fraction` of the mass at the base, under a fixed constraint, takes the force).
        """
        if self._started:
            raise RuntimeError("bodies must be created before the first step")
        if grip_at not in ("centre", "base", "base_body"):
            raise ValueError(f"grip_at must be centre, base or base_body, not {grip_at!r}")
        half = height / 2.0
        main_mass = mass * (1.0 - base_fraction) if grip_at == "base_body" else mass
        ring = self.RING if hull is None and radius <= half else 0.0
        if hull is not None:
            points = [[float(x), float(y), float(z) - half] for x, y, z in hull]
            shape = self._call(pybullet.createCollisionShape, pybullet.GEOM_MESH, vertices=points)
        elif ring:
            shape = self._call(pybullet.createCollisionShapeArray,
                               shapeTypes=[pybullet.GEOM_CYLINDER, pybullet.GEOM_SPHERE],
                               radii=[radius * (1.0 - ring), radius], lengths=[height, 0.0],
                               collisionFramePositions=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
        else:
            shape = self._call(pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=radius, height=height)
        center = (base[0], base[1], base[2] + half)
        body = self._call(pybullet.createMultiBody, baseMass=main_mass, baseCollisionShapeIndex=shape,
                          basePosition=center, useMaximalCoordinates=self.MAXIMAL and grip_at != "base_body")
        self._frictionless(body)
        across = main_mass * (3 * radius ** 2 + height ** 2) / 12.0
        # The mass again: pybullet zeroes a maximal-coordinate body's mass when only its inertia is set.
        self._call(pybullet.changeDynamics, body, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
                   linearDamping=0.0, angularDamping=0.0, mass=main_mass,
                   localInertiaDiagonal=[across, across, main_mass * radius ** 2 / 2.0])
        index = len(self._bodies)
        if grip_at == "base":
            self._base_offsets[index] = half
        elif grip_at == "base_body":
            m = mass * base_fraction
            second = self._call(pybullet.createMultiBody, baseMass=m, baseCollisionShapeIndex=-1,
                                basePosition=tuple(base))
            self._call(pybullet.changeDynamics, second, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING,
                       linearDamping=0.0, angularDamping=0.0,
                       localInertiaDiagonal=[m * radius ** 2 / 4, m * radius ** 2 / 4, m * radius ** 2 / 2])
            joint = self._call(pybullet.createConstraint, body, -1, second, -1, pybullet.JOINT_FIXED, [0, 0, 0],
                               [0, 0, -half], [0, 0, 0])
            self._call(pybullet.changeConstraint, joint, maxForce=1e4)
            self._base_bodies[index] = second
        self._bodies.append(body)
        self.labels.append(label)
        # Rests only as a plain rigid body whose box rest.boxes knows (no hull, no second body).
        self.rest.add(self.MAXIMAL and hull is None and grip_at != "base_body", radius, half)
        self.masses = np.append(self.masses, mass)
        self.radii = np.append(self.radii, radius)
        self.half_heights = np.append(self.half_heights, half)
        return index

    def _build_supports(self) -> None:
        for area in supports.merge(self._supports):
            center, half = supports.box(area)
            self.add_static_box(center, half)
        self._supports = []

    def _apply_fields(self) -> None:
        """Apply every belt's force for this tick where it grips each bottle on a belt.

        A bottle is on a belt when its centre of mass is over it; only then is its grip point
        worked out (its base, or its second body's state read), so a bottle off every belt
        costs no more at any level of detail.
        """
        if self._rows_stale:
            self._refresh_rows()
        rows = self._live_rows           # parked and resting bodies are not even looked for
        field = self._under if self._under is not None else self._fields_under(rows)
        if rows is None:
            bodies = np.flatnonzero(field >= 0)
            f = field[bodies]
        else:
            on = field >= 0
            bodies, f = rows[on], field[on]
        if len(bodies) == 0:
            return
        if self._grips is None:
            offsets = np.zeros(len(self._bodies))
            for n, offset in self._base_offsets.items():
                offsets[n] = offset
            targets = np.array([self._base_bodies.get(n, b) for n, b in enumerate(self._bodies)], dtype=int)
            self._grips = (offsets, targets)
            self._bodies_array = np.array(self._bodies, dtype=int)
        offsets, targets = self._grips
        points, velocities = self.positions[bodies], self.velocities[bodies]
        if self._base_offsets:
            rows = np.flatnonzero(offsets[bodies] > 0.0)
            if len(rows):
                n = bodies[rows]
                points[rows], velocities[rows] = base_points(
                    self.positions[n], self.orientations[n], self.velocities[n], self.angular_velocities[n], offsets[n])
        client = self._client
        if self._base_bodies:
            for row, n in enumerate(bodies.tolist()):
                second = self._base_bodies.get(n)
                if second is not None:
                    # The paper's model: the field sees the second body's own position and velocity.
                    points[row] = pybullet.getBasePositionAndOrientation(second, client)[0]
                    velocities[row] = pybullet.getBaseVelocity(second, client)[0]
        forces = self.fields.forces_at(f, points, velocities, self.masses[bodies])
        # A world-frame force acts at `at`: the centre of mass adds no torque, the base does.
        # Positional arguments: keywords cost pybullet's argument parser a tenth of the call.
        apply, frame = pybullet.applyExternalForce, pybullet.WORLD_FRAME
        for target, force, at in zip(targets[bodies].tolist(), forces.tolist(), points.tolist()):
            apply(target, -1, force, at, frame, client)
        # The surface also grips the base against spinning; only bottles that spin get a call.
        torques = self.fields.spin_torques(f, self.angular_velocities[bodies, 2], self.masses[bodies],
                                           self.radii[bodies])
        spinning = np.flatnonzero(torques)
        if len(spinning):
            twist = pybullet.applyExternalTorque
            for target, torque in zip(self._bodies_array[bodies[spinning]].tolist(), torques[spinning].tolist()):
                twist(target, -1, (0.0, 0.0, torque), frame, client)

    # --- plant elements: switchable parts, parked bodies, robot arms -----------------------
    def add_switchable_boxes(self, centers, half_extents, yaws, solid: bool) -> int:
        """One fixed body of boxes (a switch blade, a gate) whose collision the plant turns on and
        off, as the paper does; returns its number for `set_solid`."""
        body = self._boxes_body(centers, half_extents, yaws)
        self._frictionless(body)
        self._switchable.append(body)
        self._switchable_boxes.append(self._call(pybullet.getAABB, body))
        self.set_solid(len(self._switchable) - 1, solid)
        return len(self._switchable) - 1

    def set_solid(self, part: int, solid: bool) -> None:
        """Collision on or off through the body's filter group and mask: one call whatever the
        number of bottles (setCollisionFilterPair needs one per bottle), 0.8 µs, in effect from
        the next tick in both directions (measured). On: pybullet's own values for a fixed body.
        A fixed body wakes no sleeping one: bodies resting in its box are woken here."""
        if self.rest.resting.any():
            lo, hi = (np.asarray(v, float) for v in self._switchable_boxes[part])
            self._wake(self.rest.joining([(lo + hi) / 2.0], [(hi - lo) / 2.0], self.positions))
        group, mask = (2, -3) if solid else (0, 0)
        self._call(pybullet.setCollisionFilterGroupMask, self._switchable[part], -1, group, mask)

    def park(self, body: int) -> None:
        """Take a body out of play: off stage, without collision, asleep in the engine and not
        read per tick. Measured: 100 parked bottles take the engine from 37 to 43 µs per tick
        (awake without collision, 99 µs), 1000 add ~0.2 µs each to the engine and ~0.15 µs
        each to the numpy over all rows (`make bench`); reading each would add ~2.5 µs."""
        spot = (PARKED[0], PARKED[1] + 0.5 * body, PARKED[2])
        for b, z in self._parts(body):
            self._call(pybullet.resetBasePositionAndOrientation, b, (spot[0], spot[1], spot[2] + z), (0, 0, 0, 1))
            self._call(pybullet.resetBaseVelocity, b, (0, 0, 0), (0, 0, 0))
            self._call(pybullet.setCollisionFilterGroupMask, b, -1, 0, 0)
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_ENABLE_SLEEPING)
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_SLEEP)
        self._parked.add(body)
        self.rest.forget(body)
        self._moved()

    def unpark(self, body: int, base) -> None:
        """Put a parked body back into play, upright and at rest, standing on `base`."""
        for b, z in self._parts(body):
            center = (base[0], base[1], base[2] + self.half_heights[body] + z)
            self._call(pybullet.resetBasePositionAndOrientation, b, center, (0, 0, 0, 1))
            self._call(pybullet.resetBaseVelocity, b, (0, 0, 0), (0, 0, 0))
            self._call(pybullet.setCollisionFilterGroupMask, b, -1, 1, -1)   # pybullet's default for a dynamic body
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_WAKE_UP)
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING)
        self._parked.discard(body)
        self.rest.forget(body)
        if self.rest.resting.any():
            # The state arrays learn where it stands at the next read; what rests near it wakes now.
            centre = (base[0], base[1], base[2] + self.half_heights[body])
            upright = boxes(np.array([(0.0, 0.0, 0.0, 1.0)]), self.radii[[body]], self.half_heights[[body]])
            self._wake(self.rest.joining([centre], upright, self.positions))
        self._moved()

    def is_parked(self, body: int) -> bool:
        return body in self._parked

    def belts_under(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Read-only, for statistics beside the loop (hub/jams.py): the bodies in play (not
        parked), the force field each one's centre of mass lies in (−1: none) and that field's
        speed now, m/s. From the state read at the last tick; nothing is asked of the engine."""
        rows = self._play_rows
        if rows is None or self._rows_stale:
            rows = np.array([n for n in range(len(self._bodies)) if n not in self._parked], dtype=int)
        field, _, _ = self.fields.locate(self.positions[rows])
        speeds = self.fields.speeds[field] if len(self.fields.speeds) else np.zeros(len(field))   # a scene without belts
        return rows, field, np.where(field >= 0, speeds, 0.0)

    def _parts(self, body: int):
        """The pybullet bodies of one bottle with their height relative to its centre: the body,
        and the paper's second body at its base when it has one."""
        yield self._bodies[body], 0.0
        if body in self._base_bodies:
            yield self._base_bodies[body], -float(self.half_heights[body])

    def add_arm(self, base, yaw: float, tool_length: float) -> KinematicArm:
        arm = KinematicArm(self._client, base, yaw, tool_length)
        self.arms.append(arm)
        return arm

    def follow(self, trigger: int, arm: KinematicArm, offset) -> None:
        """Make a volume trigger move with the arm's tool (the paper's gripper trigger)."""
        self._following.append((trigger, arm, np.asarray(offset, float)))
        self.triggers.move(trigger, arm.tool_position + offset)

    def grip(self, arm: KinematicArm, body: int) -> None:
        """The body leaves the dynamics and follows the tool (the paper's gripping component)."""
        if body in self._base_bodies:
            raise NotImplementedError("gripping a bottle with a second base body")
        if self.rest.resting[body]:
            self._wake(np.array([body]))
        self.rest.forget(body)
        self._held[arm] = body
        arm.hold(self._bodies[body], self.positions[body], self.orientations[body].tolist())

    def release(self, arm: KinematicArm) -> None:
        self._held.pop(arm, None)
        arm.let_go()

    def _move_arms(self) -> None:
        moved = [arm for arm in self.arms if arm.update(self.tick)]
        for trigger, arm, offset in self._following:
            if arm in moved:
                self.triggers.move(trigger, arm.tool_position + offset)

    # --- stepping -------------------------------------------------------------------------
    def start(self) -> None:
        """Freeze the body set and read the initial state (tick 0); idempotent."""
        if not self._started:
            self._started = True
            self._build_supports()
            self._read_state()
            self.triggers.evaluate(self.tick, self.positions, self.radii, self.half_heights)

    def step(self, substeps: int, stop_on_event: bool = False) -> int:
        """Advance up to `substeps` ticks: force fields applied and triggers evaluated at every tick.

        With `stop_on_event`, stop after the first tick at which a trigger saw an object enter
        or leave. Returns the number of ticks advanced.
        """
        self.start()
        step, client, triggers, rest = pybullet.stepSimulation, self._client, self.triggers, self.rest
        for done in range(1, substeps + 1):
            if rest.resting.any():
                self._wake_near()
            self._apply_fields()
            step(client)
            self.tick += 1
            if self.arms:
                self._move_arms()
            full = self._full_read
            self._read_state()
            moved = None if full else self._live_rows
            event = triggers.evaluate(self.tick, self.positions, self.radii, self.half_heights, self._play_rows, moved)
            if self.check_rest:
                self._check_rest()
            if rest.enabled and self.tick % rest.every == 0:
                self._settle()
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
        # One pose and one velocity query per body read: pybullet has no call for many bodies.
        # The arrays are built in one pass over the flattened tuples (half the cost of one
        # np.array per quantity), and positions, orientations and velocities are views of them.
        # Parked and resting bodies are not read (their pose stands); all are after a park or unpark.
        if not self._bodies:
            return
        if self._rows_stale:
            self._refresh_rows()
        rows = None if self._full_read else self._live_rows
        self._full_read = False
        bodies = self._bodies if rows is None else self._live_ids
        if bodies:
            client, n = self._client, len(bodies)
            pose, velocity, flat = pybullet.getBasePositionAndOrientation, pybullet.getBaseVelocity, chain.from_iterable
            # Per body 13 numbers: position, orientation, velocity, spin — one row of `state`.
            read = np.fromiter(flat(flat([pose(b, client) + velocity(b, client) for b in bodies])), float, 13 * n)
            if rows is None:
                self._state = state = read.reshape(n, 13)
                self.positions, self.orientations = state[:, :3], state[:, 3:7]
                self.velocities, self.angular_velocities = state[:, 7:10], state[:, 10:]
            else:
                self._state[rows] = read.reshape(n, 13)
        self._under = self._fields_under(self._live_rows)

    def _refresh_rows(self) -> None:
        """Work out the bodies in play and those read per tick after a park, unpark, rest or wake."""
        play = np.ones(len(self._bodies), bool)
        play[list(self._parked)] = False
        live = play & ~self.rest.resting
        self._play_rows = None if play.all() else np.flatnonzero(play)
        self._live_rows = None if live.all() else np.flatnonzero(live)
        self._live_ids = [] if self._live_rows is None else [self._bodies[n] for n in self._live_rows.tolist()]
        self._rows_stale = False
        self._under = None

    def _moved(self) -> None:
        """A body was put somewhere by the plant (parked, unparked): read every body next tick."""
        self._full_read = True
        self._rows_stale = True
        self._under = None

    def _fields_under(self, rows) -> np.ndarray:
        return self.fields.which(self.positions if rows is None else self.positions[rows])

    # --- bodies at rest (rest.py) ------------------------------------------------------------
    def _awake_rows(self) -> np.ndarray:
        if self._rows_stale:
            self._refresh_rows()
        return np.arange(len(self._bodies)) if self._live_rows is None else self._live_rows

    def _settle(self) -> None:
        """Put to rest the bodies that have been still long enough where nothing drives them."""
        rows = self._awake_rows()
        if len(rows) == 0:
            return
        field = self._under
        undriven = field < 0
        if len(self.fields):
            undriven |= self.fields.speeds[field] == 0.0
        if self._held:
            undriven &= ~np.isin(rows, list(self._held.values()))
        state = self.positions, self.orientations, self.velocities, self.angular_velocities
        candidates = self.rest.candidates(rows, state[2], state[3], undriven)
        if len(candidates):
            candidates = self.rest.settle(candidates, rows, *state)
        if len(candidates):
            for b in (self._bodies[n] for n in candidates.tolist()):
                self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_ENABLE_SLEEPING)
                self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_SLEEP)
            self.rest.put(candidates, self.orientations, field[np.searchsorted(rows, candidates)])
            # What the engine holds for a sleeping body from its next tick on.
            self.velocities[candidates] = 0.0
            self.angular_velocities[candidates] = 0.0
            self._rows_stale = True

    def _wake_near(self) -> None:
        """Before a tick: wake the resting bodies an awake body has come near (the island Bullet wakes)."""
        self._wake(self.rest.woken_by(self._awake_rows(), self.positions, self.orientations, self.velocities,
                                      self.angular_velocities))

    def wake_all(self) -> None:
        """Wake every resting body (they rest again once still for sleep_after)."""
        self._wake(self.rest.rows())

    def _wake(self, rows: np.ndarray) -> None:
        if len(rows) == 0:
            return
        for b in (self._bodies[n] for n in rows.tolist()):
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_WAKE_UP)
            self._call(pybullet.changeDynamics, b, -1, activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING)
        self.rest.wake(rows)
        self._rows_stale = True

    def _check_rest(self) -> None:
        """Every resting body as the engine holds it: where planthub left it, not moving."""
        client = self._client
        for n in self.rest.rows().tolist():
            position, orientation = pybullet.getBasePositionAndOrientation(self._bodies[n], client)
            velocity, spin = pybullet.getBaseVelocity(self._bodies[n], client)
            if (tuple(self.positions[n]) != position or tuple(self.orientations[n]) != orientation
                    or velocity != (0.0, 0.0, 0.0) or spin != (0.0, 0.0, 0.0)):
                raise RuntimeError(
                    f"tick {self.tick}: {self.labels[n]} rests in planthub but the engine moved it: "
                    f"at {position} moving {velocity}, held at {tuple(self.positions[n])}")

    def engine_box(self, body: int) -> tuple[tuple, tuple]:
        """The box (lo, hi) the engine bounds a body by, without its pair-search widening (tests)."""
        return self._call(pybullet.getAABB, self._bodies[body])

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

