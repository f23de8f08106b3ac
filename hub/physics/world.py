"""The pybullet material-flow world: what the modules build in it, and the physics tick that steps it all."""
from __future__ import annotations

import logging
import math

import numpy as np

from hub.core.errors import SimulationError
from hub.physics._quiet import quiet_stderr
from hub.physics.arms import Arms
from hub.physics.bodies import Bodies
from hub.physics.bottles import Bottles
from hub.physics.changes import BeltSpeed, Change, Changes, Gripped, LetGo, Parked, Tipped
from hub.physics.engine import Engine
from hub.physics.fields import ForceFields
from hub.physics.frames import Arc, Pose, Straight
from hub.physics.moving import MovingPart, MovingParts
from hub.physics.parking import PARKED, Parking  # noqa: F401 (PARKED: read here by the plant's figures)
from hub.physics.parts import SwitchableParts
from hub.physics.placement import overlaps
from hub.physics.rest import Rest
from hub.physics.robot import REACH, SHOULDER, URDF, KinematicArm
from hub.physics.scene import SceneLog, SceneState, scene_state
from hub.physics.sleep import Sleep
from hub.physics.transport import LOOKAHEAD, FreeTransport
from hub.physics.triggers import Latch, VolumeTriggers
from hub.physics.watch import Watch

with quiet_stderr():
    import pybullet  # also the name benchmarks time the engine's step by (tests/bench_bottling.py)

_log = logging.getLogger(__name__)


class PhysicsWorld:
    """A headless pybullet world stepped in integer ticks of 1/rate seconds.

    It is the one object the modules build into and the master steps; each concept is a file
    of its own, and this class puts them together and runs the tick (`step`):

    | part | file | holds |
    |---|---|---|
    | `engine` | engine.py | the pybullet client, its set-up, static boxes and the merged floors |
    | `bodies` | bodies.py | the body table: every bottle's properties and state arrays, the rows read per tick |
    | `bottles` | bottles.py | bottles at their level of detail, and the belts' forces where each is gripped |
    | `fields`, `triggers` | fields.py, triggers.py | belt regions and volume triggers (numpy and compiled loops, no engine call) |
    | `parts` | parts.py | switchable parts (blades, gates) |
    | `moving` | moving.py | moving kinematic parts (a pusher's plate) |
    | `parking` | parking.py | bodies out of play, off stage |
    | `robots` | arms.py, robot.py | robot arms, gripped bodies and the triggers on their tools |
    | `rest`, `sleep` | rest.py, sleep.py | bodies at rest: the rule (numpy and compiled loops) and the engine's side |
    | `transport` | transport.py, transport_kernels.py, transport_check.py | bottles in free transport, moved by their belt's law outside the engine: the state and when it looks, the compiled tests and law, the engine's check (tests) |
    | `watch` | watch.py, placement.py | a run gone wrong: bodies too fast, non-finite or out of the box; overlaps at load |
    | `scene` | scene.py | what was built and by which object, and the moving state, for a view |
    | `changes` | changes.py | what a part changes (a belt's speed, a gate, an arm's grip…), announced once (`announce`) |

    Each tick reads the state of every body in play once, except those at rest (asleep in the
    engine, their state stands) and those in free transport (the hub moves them); force fields,
    triggers, the wake rule and free transport's looks work on those arrays, in compiled loops
    (numba) where they go body by body at every tick: far cheaper than one pybullet query per
    body and volume, and than the dozens of small numpy calls the same tests were. Bodies are created before
    the first step and never reset inside the loop, because pybullet is deterministic only for
    an identical sequence of calls.

    `seed` and `anchors` are the scenario's, not the engine's: modules that draw at build time
    (a source's destinations, a station's faults) read the run's seed here, and a belt given
    `after:` finds where the belt it continues ends (hub/run/plant.py sets the seed).
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
    # costs 1922, 1274 and 1220 µs per tick (`python -m tests.bench_queue`).
    RING = 0.05
    MAXIMAL = True
    SOLVER_ITERATIONS = 20

    #: Everything of the world that changes as it runs (hub/core/state.py): the clock, the engine's
    #: own state, and each part's tables. Sleep and parking keep nothing of their own; the scene
    #: log, the static geometry and the fields' regions are structure.
    STATE = ("tick", "engine", "bodies", "bottles", "fields", "triggers", "rest", "transport", "parts", "moving",
             "robots", "watch", "tables")

    def __init__(self, rate: int, gravity: float = -9.81, solver_iterations: int | None = None,
                 sleep_after: float = 0.05, integrator: str = "exact"):
        self.rate = rate
        self.dt = 1.0 / rate
        self.tick = 0
        self.gravity = abs(gravity)
        self.engine = Engine(self.dt, gravity, solver_iterations or self.SOLVER_ITERATIONS)
        self._client = self.engine.client
        self.fields = ForceFields(self.dt, integrator)
        self.triggers = VolumeTriggers()
        self.seed = 0                           # the scenario's run.seed, for modules that draw at build time
        self.anchors: dict[str, Pose] = {}      # named belt ends, where a belt given `after:` starts
        self.rest = Rest(rate, sleep_after)     # bodies the engine leaves asleep (rest.py)
        self.check_rest = False                 # compare resting bodies with the engine at every tick (tests)
        self.check_free = False                 # ask the engine whether a free bottle touches anything, every tick (tests)
        self.bodies = Bodies(self._client, self.rest)
        self.transport = FreeTransport(self.engine, self.bodies, self.fields, self.rest, self.dt)
        self.bottles = Bottles(self.engine, self.bodies, self.rest, self.transport)
        self.sleep = Sleep(self.engine, self.bodies, self.rest)
        # The levels of detail hear every change a part makes (changes.py), free transport first:
        # it may take resting bodies a belt's start reaches off free before sleep wakes them.
        self.changes = Changes()
        self.changes.listen(self.transport)
        self.changes.listen(self.sleep)
        self.parts = SwitchableParts(self.engine, self.changes)
        self.moving = MovingParts(self.engine, rate, self.changes)
        self.parking = Parking(self.engine, self.bodies, self.bottles)
        self.robots = Arms(self.engine, self.bodies, self.bottles, self.triggers)
        self.watch = Watch(self.gravity)        # off until configured; hub/run/plant.py does, from run.watch
        self.warnings: list[str] = []           # what the checks at the start found doubtful (logged too)
        self.scene = SceneLog()                 # what was built, by whom, as a view draws it (scene.py)
        #: Tables the modules keep per world beside the bodies (the manifest's cargo, by body row):
        #: plain data, saved and put back with the world.
        self.tables: dict[str, dict] = {}

    # --- the body table, as the modules read it ---------------------------------------------
    @property
    def labels(self) -> list[str]:
        return self.bodies.labels

    @property
    def masses(self) -> np.ndarray:
        return self.bodies.masses

    @property
    def radii(self) -> np.ndarray:
        return self.bodies.radii

    @property
    def half_heights(self) -> np.ndarray:
        return self.bodies.half_heights

    @property
    def positions(self) -> np.ndarray:
        return self.bodies.positions

    @property
    def orientations(self) -> np.ndarray:
        return self.bodies.orientations

    @property
    def velocities(self) -> np.ndarray:
        return self.bodies.velocities

    @property
    def angular_velocities(self) -> np.ndarray:
        return self.bodies.angular_velocities

    @property
    def _live_rows(self):
        return self.bodies.live_rows

    @property
    def arms(self) -> list[KinematicArm]:
        return self.robots.arms

    def tilt(self, body: int) -> float:
        """Angle in radians between the body's axis and the plumb line."""
        x, y, z, w = self.bodies.orientations[body]
        # z component of the body's rotated up axis: 1 − 2(x² + y²).
        return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))

    def engine_box(self, body: int) -> tuple[tuple, tuple]:
        """The box (lo, hi) the engine bounds a body by, without its pair-search widening (tests)."""
        return self.engine.aabb(self.bodies.ids[body])

    # --- building: static geometry, belts, bottles, triggers --------------------------------
    def add_static_box(self, center, half_extents, yaw: float = 0.0) -> None:
        self.engine.add_static_box(center, half_extents, yaw)
        self.scene.box(center, half_extents, yaw)

    def add_static_boxes(self, centers, half_extents, yaws) -> None:
        self.engine.add_static_boxes(centers, half_extents, yaws)
        for c, h, y in zip(centers, half_extents, yaws):
            self.scene.box(c, h, y)

    def add_support(self, z: float, rect, thickness: float = 0.02) -> None:
        self.engine.add_support(z, rect, thickness)
        self.scene.support(z, rect, thickness)

    def add_force_field(self, center, half_extents, yaw: float, k: float, speed: float) -> int:
        field = self.fields.add(center, half_extents, yaw, k, speed)
        self.scene.field_box(field, center, half_extents, yaw)
        return field

    def add_belt_field(self, line: Straight | Arc, half_width: float, z_lo: float, z_hi: float, k: float,
                       speed: float, grip: str = "surface", per_mass: bool = True,
                       friction: float | None = None) -> int:
        """A belt's force field; `friction` (μ) caps the acceleration it gives at μ·g."""
        limit = math.inf if friction is None else friction * self.gravity
        field = self.fields.add_region(line, half_width, z_lo, z_hi, k, speed, grip=grip, per_mass=per_mass,
                                       limit=limit)
        self.scene.belt(field, line, half_width, line.start.z)
        return field

    def announce(self, change: Change) -> Change:
        """Tell every level of detail (free transport, rest and sleep, …) of a change a part made
        to the world (changes.py): the one call through which the world's parts and the modules
        report what they change."""
        return self.changes.announce(change)

    def set_field_speed(self, field: int, speed: float) -> None:
        """A belt's speed (announced: `BeltSpeed`); bodies resting on it wake when it changes — those
        that may ride free and nothing can touch ride off free instead (transport.py). The same
        speed again changes nothing and costs nothing (a belt sets its field's speed only when it
        changes, but any caller may): the watch's bound follows the speeds a belt changes to (it
        starts from those at load)."""
        if speed == self.fields.speeds[field]:
            return
        self.watch.belt_speed(speed)
        self.fields.set_speed(field, speed)
        self.announce(BeltSpeed(field, speed))

    def add_cylinder(self, base, radius: float, height: float, mass: float, label: str) -> int:
        row = self.bottles.add_cylinder(base, radius, height, mass, label)
        self.scene.body(row)
        return row

    def add_bottle(self, base, radius: float, height: float, mass: float, label: str, *, hull=None,
                   grip_at: str = "centre", base_fraction: float = 0.05, transport: str = "free",
                   lookahead: int = LOOKAHEAD) -> int:
        """An upright bottle standing on `base` (bottles.py; RING and MAXIMAL above); `transport`
        and `lookahead` (ticks): whether and how it may ride free (transport.py)."""
        row = self.bottles.add(base, radius, height, mass, label, hull=hull, grip_at=grip_at,
                               base_fraction=base_fraction, ring=self.RING, maximal=self.MAXIMAL,
                               transport=transport, lookahead=lookahead)
        self.scene.body(row)
        return row

    def add_trigger(self, center, half_extents, yaw: float = 0.0) -> int:
        trigger = self.triggers.add(center, half_extents, yaw)
        self.scene.trigger(trigger, center, half_extents, yaw)
        return trigger

    def take_trigger(self, trigger: int) -> Latch:
        return self.triggers.take(trigger)

    # --- plant elements: switchable and moving parts, parked bodies, robot arms --------------
    def add_switchable_boxes(self, centers, half_extents, yaws, solid: bool) -> int:
        part = self.parts.add(centers, half_extents, yaws, solid)
        self.scene.part(part, centers, half_extents, yaws)
        return part

    def set_solid(self, part: int, solid: bool) -> None:
        self.parts.set_solid(part, solid)

    def add_moving_boxes(self, centers, half_extents, yaws, axis) -> MovingPart:
        """A part of boxes (world frame, where it stands at offset 0) that slides along `axis`:
        `part.move(world.tick, [Leg(to, speed, hold), …])` (moving.py)."""
        part = self.moving.add(centers, half_extents, yaws, axis)
        self.scene.moving(len(self.moving.parts) - 1, centers, half_extents, yaws, axis)
        return part

    def park(self, body: int) -> None:
        self.announce(Parked(body))
        self.parking.park(body)

    def unpark(self, body: int, base) -> None:
        self.announce(self.parking.unpark(body, base))

    def is_parked(self, body: int) -> bool:
        return body in self.bodies.parked

    def tip(self, body: int, heading: float) -> None:
        """Lay a bottle in play on its side where it stands, its axis along `heading` (rad): a fault."""
        centre, _, extents = self.parking.lying(body, heading)
        self.announce(Tipped(body, centre, extents))
        self.parking.lay(body, heading)

    def add_arm(self, base, yaw: float, tool_length: float) -> KinematicArm:
        arm = self.robots.add(base, yaw, tool_length)
        self.scene.arm(len(self.robots.arms) - 1, URDF, base, yaw, arm.joint_names, tool_length)
        return arm

    def follow(self, trigger: int, arm: KinematicArm, offset) -> None:
        self.robots.follow(trigger, arm, offset)

    def grip(self, arm: KinematicArm, body: int) -> None:
        if body in self.bottles.base_bodies:
            raise NotImplementedError("gripping a bottle with a second base body")
        self.announce(Gripped(body))
        self.robots.grip(arm, body)

    def release(self, arm: KinematicArm) -> None:
        body = self.robots.held.get(arm, -1)
        self.robots.release(arm)
        self.announce(LetGo(body))   # the bottle let go of collides from the next tick on

    def belts_under(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Read-only, for statistics beside the loop (modules/plant/jams.py): the bodies in play
        (not parked), the force field each one's centre of mass lies in (−1: none) and that
        field's speed now, m/s. From the state read at the last tick; nothing is asked of the engine."""
        rows = self.bodies.in_play_rows()
        field = self.fields.which(self.bodies.positions[rows])
        if len(self.fields) == 0:   # a scene without belts (an arm over a table): no speed to look up
            return rows, field, np.zeros(len(rows))
        return rows, field, np.where(field >= 0, self.fields.speeds[field], 0.0)

    def scene_state(self) -> SceneState:
        """The bodies in play and the moving parts now, for a view (scene.py; no engine call)."""
        return scene_state(self)

    # --- stepping -------------------------------------------------------------------------
    def start(self) -> None:
        """Freeze the body set and read the initial state (tick 0); idempotent."""
        b = self.bodies
        if not b.started:
            b.started = True
            self.engine.build_supports()
            if self.transport.enabled:
                self.transport.arm(self._fixed_boxes(), self.moving, self.bottles.base_offsets)
            b.read(self.fields)
            self.check_start()
            self.triggers.evaluate(self.tick, b.positions, b.radii, b.half_heights)

    def _fixed_boxes(self) -> list[tuple]:
        """Every fixed box but the floors, and every box of a gate or blade whether solid or not:
        what a free bottle keeps clear of (transport.py). And the bounding box of every shaped
        link of a body none of the world's parts declared (made by a primitive that tells free
        transport nothing about it): a bottle near it stays in the engine."""
        engine, floors = self.engine, self.engine.floors
        declared = (engine.fixed_bodies() | self.parts.bodies() | self.moving.bodies() | self.robots.arm_bodies()
                    | set(self.bodies.ids))
        unknown = [box for body in engine.bodies() if body not in declared for box in engine.shaped_boxes(body)]
        return [(c, h, y) for body, c, h, y in engine.static if body not in floors] + self.parts.boxes + unknown

    def _arm_spheres(self) -> list[tuple]:
        """Where each robot arm can reach (centre, radius): where it may put a bottle down."""
        return [(arm.base + SHOULDER, REACH + arm.tool_length) for arm in self.robots.arms]

    def check_start(self) -> None:
        """Before the first tick: bodies placed overlapping are an error (the engine would eject
        them); the watch's box and bound are fixed; a trigger or a gate a bottle could jump is a warning."""
        b = self.bodies
        if not self.watch.enabled:
            return
        found = overlaps(self.engine, b)
        if found:
            raise SimulationError(f"tick {self.tick} (t = {self.tick * self.dt:.4f} s), at load: "
                                  + "; ".join(found) + " — the engine would eject them: move them apart")
        fastest = float(np.abs(self.fields.speeds).max()) if len(self.fields.speeds) else 0.0
        lo, hi = self.engine.static_bounds()
        # An arm carries a bottle anywhere within its reach, and may let go of it there.
        reach = self._arm_spheres()
        lo = np.vstack([lo] + [c - r for c, r in reach])
        hi = np.vstack([hi] + [c + r for c, r in reach])
        play = b.in_play_rows()
        self.watch.arm(lo.min(0) if len(lo) else np.full(3, np.inf), hi.max(0) if len(hi) else np.full(3, -np.inf),
                       b.positions[play], fastest)
        jumps = self.triggers.jumpable(fastest * self.dt, b.radii[play])
        if len(b.radii[play]):
            jumps += self.parts.jumpable(fastest * self.dt, float(np.min(b.radii[play])))
        for message in jumps:
            self.warnings.append(message)
            _log.warning("%s", message)

    def step(self, substeps: int, stop_on_event: bool = False) -> int:
        """Advance up to `substeps` ticks: force fields applied and triggers evaluated at every tick.

        One tick: bring back into the engine the free bottles something could touch, wake what
        awake bodies and moving parts come near (rest.py's rule), apply the belts' forces, let the
        engine step, move the free bottles (transport.py), put arms and moving parts where they
        are at the new tick, read the bodies' state, evaluate the triggers, let still bodies
        rest and steady ones on a belt ride free. With
        `stop_on_event`, stop after the first tick at which a trigger saw an object enter or
        leave. Returns the number of ticks advanced.
        """
        self.start()
        step, client, triggers, rest = pybullet.stepSimulation, self._client, self.triggers, self.rest
        b, sleep, moving, arms, watch = self.bodies, self.sleep, self.moving, self.robots, self.watch
        transport = self.transport
        free = transport.enabled
        for done in range(1, substeps + 1):
            if free and len(transport.rows):
                transport.release_near(self.tick, b.placed, moving.moving, b.awake_rows())
            if rest.resting.any():
                sleep.wake_near()
            if moving.moving:
                moving.sweep()
            self.bottles.drive(self.fields)
            step(client)
            self.tick += 1
            if free:
                transport.advance()
            if arms.arms:
                arms.move(self.tick)
            if moving.parts:
                moving.update(self.tick)
            full = b.full_read
            b.read(self.fields)
            if watch.enabled:
                bad = watch.check(b.fresh, b.fresh_rows)
                if bad is not None:
                    self._violation(bad)
            moved = None if full or b.full_read else b.moved_rows   # full_read again: the watch took a body out
            event = triggers.evaluate(self.tick, b.positions, b.radii, b.half_heights, b.play_rows, moved)
            if self.check_rest:
                sleep.check(self.tick, self.parts.bodies())
            if self.check_free:
                transport.check(self.tick, self.engine.floors, self.engine.fixed_bodies() | self.parts.bodies(),
                                arms.held_rows())
            if self.tick % rest.every == 0 and rest.enabled:
                sleep.settle(self.fields, arms.held_rows(), moving)
            if free and self.tick % transport.every == 0:
                transport.take_free(self.tick, b.awake_rows(), arms.held_rows())
            if event and stop_on_event:
                return done
        return substeps

    def _violation(self, rows: np.ndarray) -> None:
        """Bodies the watch caught at this tick: stop the run naming the first, or (policy
        `remove`) park each and log it. A body an arm holds follows the tool, not the engine: exempt."""
        held = set(self.robots.held_rows())
        b, when = self.bodies, f"tick {self.tick} (t = {self.tick * self.dt:.4f} s)"
        for row in (int(r) for r in rows):
            if row in held:
                continue
            cause = self.watch.cause(b.positions[row], b.velocities[row],
                                     np.concatenate([b.orientations[row], b.angular_velocities[row]]))
            message = f"bottle {b.labels[row]!r}, {when}: {cause}"
            if self.watch.policy == "stop":
                raise SimulationError(message + " — run.watch.on_violation: remove takes such a body out instead")
            self.watch.removed.append((self.tick, row, cause))
            _log.warning("%s; taken out of the run (run.watch.on_violation: remove)", message)
            self.park(row)
        b.refresh()   # the triggers at this tick see the bodies in play without it

    def step_engine_only(self, substeps: int) -> None:
        """Only pybullet's own stepping, no state reads, fields or triggers: the floor for benchmarks."""
        self.start()
        for _ in range(substeps):
            self.engine.call(pybullet.stepSimulation)
        self.tick += substeps

    def wake_all(self) -> None:
        """Wake every resting body (they rest again once still for sleep_after)."""
        self.sleep.wake_all()

    def close(self) -> None:
        self.engine.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
