"""Robot arm: the KUKA iiwa moving bottles from a storage pick pose to a belt place pose along preset joint trajectories.

The arm is kinematic, as the paper's skeletal animation: its joints follow straight lines in
joint space with a quintic time law (starting and stopping at rest), evaluated from the
integer tick, between poses solved once by inverse kinematics at build time; the engine never
integrates it (hub/physics/robot.py says what that costs and why). Commands that arrive while
a sequence runs are queued and served in order, so a logic that issues pick, carry, place and
home on its own clock (the robot_arm Petri net) drives it the same as one waiting for
`picked`/`placed`. Sequences advance at communication points.

Gripping (the paper's gripping component): the bottle leaves the dynamics and its pose follows
the tool at every tick (upright, at the offset it had when gripped); released, it collides
again and moves on with the tool's velocity. With `auto_grip` (default) a pick grips at its
lowest point and a place releases at its lowest point; without, only the gripper's targets do.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from hub.core.component import Component
from hub.core.errors import SimulationError
from hub.core.logic_spec import LogicSpec
from hub.core.module import Module
from hub.core.slots import Slot
from hub.physics.robot import JointMotion, reachable
from modules.params import POSITION, YAW, length
from modules.trigger import VolumeTrigger

CLEARANCE = 0.002   # m between a placed bottle's base and the surface when it is let go


class Gripper(VolumeTrigger):
    SLOTS = VolumeTrigger.SLOTS + (
        Slot.target("grip", "void", "grip the bottle in the gripper volume nearest the tool"),
        Slot.target("release", "void", "release the bottle held"),
        Slot.target("hold", "bool", "true grips, false releases (a level, e.g. a Petri net's Holding)"),
        Slot.source("holding", "bool", "a bottle is held, every step"),
        Slot.source("held", "string", 'id of the bottle held ("" when none), every step'),
        Slot.source("on_grip", "void", "a bottle was gripped"),
        Slot.source("on_release", "void", "a bottle was released"),
        Slot.source("position", "vec3", "the tool point, m, every step"),
    )

    STATE = VolumeTrigger.STATE + ("body", "changes", "reported")

    def __init__(self, obj, name, world, trigger, arm):
        super().__init__(obj, name, world, trigger)
        self.arm = arm
        self.body: int | None = None
        self.changes: list[tuple[str, int]] = []   # (event, body) done at the last actuation
        self.reported: list[tuple[str, int]] = []

    def sense(self, tick):
        super().sense(tick)
        self.reported, self.changes = self.changes, []
        for event, _ in self.reported:
            self.emit(event)
        self.emit("holding", self.body is not None)
        self.emit("held", "" if self.body is None else self.world.labels[self.body])
        if "position" in self.needed:
            self.emit("position", tuple(self.arm.tool_position.tolist()))

    def events(self, tick):
        rows = super().events(tick)
        if not self.reported:
            return rows
        return [*rows, *((tick, event, self.world.labels[body]) for event, body in self.reported)]

    def actuate(self):
        if self.updated("hold"):
            self.take() if self.value("hold") else self.let_go()
        if self.updated("grip"):
            self.take()
        if self.updated("release"):
            self.let_go()

    def take(self) -> None:
        """Grip the bottle in the volume whose axis is nearest the tool, if any and none is held."""
        inside = self.latch.inside if self.latch is not None else ()
        if self.body is not None or not inside:
            return
        tool = self.arm.tool_position
        self.body = min(inside, key=lambda n: float(np.hypot(*(self.world.positions[n, :2] - tool[:2]))))
        self.world.grip(self.arm, self.body)
        self.changes.append(("on_grip", self.body))

    def let_go(self) -> None:
        if self.body is None:
            return
        self.world.release(self.arm)
        self.changes.append(("on_release", self.body))
        self.body = None


class Arm(Component):
    SLOTS = (
        Slot.target("pick", "void", "go above the pick pose, down, grip, back up"),
        Slot.target("carry", "void", "go above the place pose"),
        Slot.target("place", "void", "go above the place pose (if not there), down, release, back up"),
        Slot.target("home", "void", "go to the home pose"),
        Slot.source("picked", "void", "a pick sequence ended (see gripper.holding for its outcome)"),
        Slot.source("carried", "void", "a carry ended"),
        Slot.source("placed", "void", "a place sequence ended"),
        Slot.source("homed", "void", "the arm reached home"),
        Slot.source("pose", "string", 'home, above_pick or above_place; "" while moving, every step'),
        Slot.source("busy", "bool", "a sequence runs or waits, every step"),
    )
    COMMANDS = ("pick", "carry", "place", "home")

    # `poses` too: solved by pybullet's inverse kinematics at build, whose answer is not the same
    # in two worlds of one process (measured: a plant built beside another differed), while a
    # resumed run must move the arm as the one that saved it would have.
    STATE = ("queue", "steps", "wait_until", "pose", "finished", "poses")

    def __init__(self, obj, name, world, arm, gripper: Gripper, poses: dict, timing: dict, auto_grip: bool):
        super().__init__(obj, name)
        self.world = world
        self.arm = arm
        self.gripper = gripper
        self.poses = poses            # name → joint positions
        self.timing = timing          # move, approach, grip: ticks
        self.auto_grip = auto_grip
        self.queue: deque[str] = deque()
        self.steps: deque[tuple] = deque()
        self.wait_until = 0
        self.pose = "home"
        self.finished: list[str] = []

    def sense(self, tick):
        for event in self.finished:
            self.emit(event)
        self.finished = []
        self.emit("pose", self.pose)
        self.emit("busy", bool(self.steps or self.queue or self.arm.moving))

    def actuate(self):
        for command in self.COMMANDS:
            if self.updated(command):
                self.queue.append(command)
        tick = self.world.tick
        while not self.arm.moving and tick >= self.wait_until:
            if not self.steps:
                if not self.queue:
                    return
                self.steps.extend(self.sequence(self.queue.popleft()))
            self.run(self.steps.popleft(), tick)

    def sequence(self, command: str) -> list[tuple]:
        t, grip = self.timing, self.auto_grip
        if command == "pick":
            return [("move", "above_pick", t["move"]), ("move", "at_pick", t["approach"]),
                    *([("grip",)] if grip else []), ("wait", t["grip"]),
                    ("move", "above_pick", t["approach"]), ("done", "picked", "above_pick")]
        if command == "carry":
            return [("move", "above_place", t["move"]), ("done", "carried", "above_place")]
        if command == "place":
            return [("move", "above_place", t["move"]), ("move", "at_place", t["approach"]),
                    *([("release",)] if grip else []), ("wait", t["grip"]),
                    ("move", "above_place", t["approach"]), ("done", "placed", "above_place")]
        return [("move", "home", t["move"]), ("done", "homed", "home")]

    def run(self, step: tuple, tick: int) -> None:
        kind = step[0]
        if kind == "move":
            target = self.poses[step[1]]
            if np.max(np.abs(target - self.arm.q)) > 1e-9:   # already there: no time spent
                self.pose = ""
                self.arm.play(JointMotion(self.arm.q, target, tick, step[2], self.world.rate))
        elif kind == "wait":
            self.wait_until = tick + step[1]
        elif kind == "grip":
            self.gripper.take()
        elif kind == "release":
            self.gripper.let_go()
        else:
            self.finished.append(step[1])
            self.pose = step[2]


class RobotArm(Module):
    """A KUKA iiwa on `position`, picking bottles standing at `pick` and setting them down at `place`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "the arm's base, m"},
            "yaw": YAW,
            "pick": {**POSITION, "description": "centre of the base of a bottle to pick (the storage spot), m"},
            "place": {**POSITION, "description": "centre of the base of a placed bottle (on the belt surface), m"},
            "home": {**POSITION, "description": "tool point at home, m (default: the arm's rest pose)"},
            "lift": length(0.15, "height above pick and place from which the arm goes straight down, m"),
            "grip_height": length(0.08, "grip point above the bottle's base, m"),
            "tool_length": length(0.1, "gripper length from the flange to the grip point, m"),
            "gripper_size": {"type": "array", "items": {"type": "number", "exclusiveMinimum": 0},
                             "minItems": 3, "maxItems": 3, "default": [0.02, 0.02, 0.02],
                             "description": "gripper volume around the grip point, m"},
            "move_time": length(1.5, "time of a move between poses, s"),
            "approach_time": length(0.5, "time to go down to or up from pick and place, s"),
            "grip_time": {"type": "number", "minimum": 0, "default": 0.2, "description": "dwell to grip or release, s"},
            "auto_grip": {"type": "boolean", "default": True,
                          "description": "pick grips and place releases by themselves (false: only the gripper's targets)"},
        },
        "required": ["position", "pick", "place"],
        "additionalProperties": False,
    }
    COMPONENTS = {"arm": Arm, "gripper": Gripper}
    # The robot's sequence net (fmus/nets/robot_arm.net.yaml): each token put on
    # logic.Request_put runs one pick → carry → place → return cycle, a phase per place; each
    # phase that begins sends the arm its command (the arm queues a command while it moves).
    LOGIC = LogicSpec(
        model="robot_arm",
        events=("Request_put", "Picking_got", "Carrying_got", "Placing_got", "Returning_got"),
        wiring=(("logic.Picking_got", "arm.pick"), ("logic.Carrying_got", "arm.carry"),
                ("logic.Placing_got", "arm.place"), ("logic.Returning_got", "arm.home")),
    )

    @classmethod
    def tool_points(cls, params) -> dict[str, np.ndarray]:
        up = np.array([0.0, 0.0, params["grip_height"]])
        lift = np.array([0.0, 0.0, params["lift"]])
        pick, place = np.asarray(params["pick"], float) + up, np.asarray(params["place"], float) + up
        place = place + (0.0, 0.0, CLEARANCE)
        points = {"above_pick": pick + lift, "at_pick": pick, "above_place": place + lift, "at_place": place}
        if "home" in params:
            points["home"] = np.asarray(params["home"], float)
        return points

    @classmethod
    def check(cls, params):
        problems = []
        points = cls.tool_points(params)
        for key in ("pick", "place", "home"):
            missed = [pose for pose, point in points.items() if pose.endswith(key)
                      and not reachable(params["position"], point, params["tool_length"])]
            if missed:
                problems.append(((key,), f"{params[key]} is out of reach of the arm standing at {params['position']}: "
                                         f"the tool cannot get to {' and '.join(missed)}"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        arm = world.add_arm(params["position"], math.radians(params["yaw"]), params["tool_length"])
        poses = {"home": arm.q.copy()}
        for pose, point in cls.tool_points(params).items():
            q, miss = arm.solve(point)
            if miss > 1e-3:
                why = "outside its joint limits" if math.isinf(miss) else f"it misses by {miss:.3g} m"
                raise SimulationError(f"object {name!r}: the arm cannot put its tool at {pose} "
                                      f"{np.round(point, 3).tolist()} pointing down ({why})")
            poses[pose] = q
        arm.set(poses["home"], np.zeros(len(poses["home"])))
        half = [s / 2 for s in params["gripper_size"]]
        trigger = world.add_trigger(arm.tool_position, half, 0.0)
        world.follow(trigger, arm, (0.0, 0.0, 0.0))
        rate = world.rate
        timing = {"move": max(1, round(params["move_time"] * rate)),
                  "approach": max(1, round(params["approach_time"] * rate)),
                  "grip": round(params["grip_time"] * rate)}
        gripper = Gripper(name, "gripper", world, trigger, arm)
        return {"arm": Arm(name, "arm", world, arm, gripper, poses, timing, params["auto_grip"]), "gripper": gripper}
