"""Pusher: a kinematic ejector beside a belt that, on a command, shoves the bottle in front of it sideways off the belt into a reject lane.

As on a bottling line that rejects unfilled or uncapped bottles: a straight belt (`length`,
placed like a conveyor) with a plate standing in the guard rail on one side at `at`, and a reject
lane — a belt of `lane_width` and `lane_length` — leaving to the other `side` there, at right
angles, like a switch's branch. At rest the plate's face is flush with the rail, so bottles pass
it as they pass a rail. A push drives the plate across the belt at `push_speed` to `stroke`
(default: to the lane's mouth, the belt's width and the far rail), holds it `dwell` s and brings
it back at `return_speed`; the bottle in front of it leaves the plate at about the plate's speed
(a little faster: hub/physics/moving.py) and the lane carries it off. The plate is
`plate_length` along the belt: it must cover how far the bottle rides on while it is pushed
(10 cm in scenarios/pusher.yaml: a 10 cm belt, belt and plate at 0.5 m/s), so the sensor that
commands it stands over the plate's upstream part, and the lane's mouth must take the 3 cm it
drifts on along the belt in the lane.

The stroke is mechanics, not control logic: a pneumatic ejector's cylinder goes out and back
by itself once its valve is fired, so the pusher runs the whole stroke from one command, on the
integer tick clock (hub/physics/moving.py), and reports it; which bottle to push is the plant's
decision, sent by flows (a sensor's event) or by any logic to `push.push`. A push while a
stroke is under way is ignored and reported on `refused`: the plate cannot go out twice at once.

The pusher builds both belts because its belt's rails need openings, where the plate stands and
where the lane leaves (a conveyor's rails are unbroken); their floors merge with the floors they
touch (hub/physics/supports.py), so conveyors placed at the ends hand bottles over without a seam.
`on_extended` and `on_returned` are logged with the tick the plate got there.
"""
from __future__ import annotations

import math

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot
from hub.physics.frames import Pose, Straight
from hub.physics.moving import Leg
from modules.belt import COMMON, PLACEMENT, RAIL_THICKNESS, BeltDrive, build_belt, check_placement, start_pose
from modules.params import length

SIDES = {"left": 1, "right": -1}


class Push(Component):
    SLOTS = (
        Slot.target("push", "void", "push: the plate goes out across the belt and comes back"),
        Slot.source("busy", "bool", "a stroke is under way (command to return), every step"),
        Slot.source("extended", "bool", "the plate stands out at full stroke, every step"),
        Slot.source("on_extended", "void", "the plate reached full stroke"),
        Slot.source("on_returned", "void", "the plate is back at rest: the pusher takes the next command"),
        Slot.source("refused", "void", "a push came while a stroke was under way and was ignored"),
    )

    STATE = ("travel", "seen", "refused_at", "reported")

    def __init__(self, obj, name, world, part, legs, stroke: float):
        super().__init__(obj, name)
        self.world = world
        self.part = part
        self.legs = legs
        self.stroke = stroke
        self.travel = None            # the stroke under way (hub/physics/moving.py Travel)
        self.seen = 0                 # the tick of the last sense
        self.refused_at: int | None = None   # the tick of a push ignored at the last actuation
        self.reported: list[tuple[int, str]] = []   # (tick, event) reported at this point

    def sense(self, tick):
        travel, reported = self.travel, []
        if travel is not None:
            out, back = travel.arrivals[0], travel.end
            if self.seen < out <= tick:
                reported.append((out, "on_extended"))
            if back <= tick:
                reported.append((back, "on_returned"))
                self.travel = None
        if self.refused_at is not None:
            reported.append((self.refused_at, "refused"))
            self.refused_at = None
        self.seen, self.reported = tick, reported
        for _, event in reported:
            self.emit(event)
        self.emit("busy", self.travel is not None)
        self.emit("extended", self.part.offset == self.stroke)

    def actuate(self):
        if self.updated("push"):
            if self.travel is None:
                self.travel = self.part.move(self.world.tick, self.legs)
            else:
                self.refused_at = self.world.tick

    def events(self, tick):
        """The plate's arrivals with the tick it got there, a refusal with the tick it came at."""
        return [(at, event, "") for at, event in self.reported]


class Pusher(Module):
    """A belt from `position` along `yaw` with a pushing plate at `at` and a reject lane leaving to `side` there."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **PLACEMENT,
            "length": length(description="belt length, m"),
            "at": length(description="distance along the belt to the plate's centre and the lane's centre line, m"),
            "side": {"enum": sorted(SIDES), "default": "right",
                     "description": "side the reject lane leaves to; the plate stands on the other"},
            **COMMON,
            "stroke": length(description="how far the plate's face goes out across the belt, m (default: the "
                                         "belt's width and its far rail, to the lane's mouth)"),
            "push_speed": length(0.5, "plate speed going out, m/s"),
            "return_speed": length(description="plate speed coming back, m/s (default: `push_speed`)"),
            "dwell": {"type": "number", "minimum": 0, "default": 0.0, "description": "time the plate stays out, s"},
            "plate_length": length(0.12, "plate length along the belt, m"),
            "plate_height": length(0.08, "plate height above the surface, m (above a bottle's contact ring at "
                                         "its centre of mass, so the push does not tip it)"),
            "lane_width": length(0.2, "clear width of the reject lane, m (at least `plate_length`)"),
            "lane_length": length(0.5, "reject lane length from the belt's rail, m"),
            "lane_speed": {"type": "number", "description": "reject lane speed, m/s (default: `speed`)"},
        },
        "required": ["length", "at"],
        "additionalProperties": False,
    }
    COMPONENTS = {"push": Push, "main": BeltDrive, "lane": BeltDrive}

    @classmethod
    def check(cls, params):
        problems = check_placement(params)
        at, total, mouth, plate = params["at"], params["length"], params["lane_width"], params["plate_length"]
        if plate > mouth:
            problems.append((("plate_length",), f"{plate:g} m is longer than the lane's mouth (lane_width "
                                                f"{mouth:g} m): a bottle pushed at the plate's ends would hit "
                                                "the lane's rails"))
        half = max(mouth, plate) / 2 + RAIL_THICKNESS
        if at - half < 0 or at + half > total:
            problems.append((("at",), f"{at:g} m puts the lane's mouth and its rails ({2 * half:g} m) past the "
                                      f"belt's ends (length {total:g} m): give {half:g} to {total - half:g} m"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        line = Straight(start_pose(name, params, world), params["length"])
        s, half, at = SIDES[params["side"]], params["width"] / 2, params["at"]
        mouth, plate = params["lane_width"], params["plate_length"]
        # The rail on the lane's side is open over the lane's mouth, the other over the plate.
        main = build_belt(name, "main", params, world, line,
                          ((s, [(at - mouth / 2, at + mouth / 2)]), (-s, [(at - plate / 2, at + plate / 2)])))
        fork = line.pose_at(at)
        lx, ly = fork.left
        lane_start = Pose(fork.x + s * lx * (half + RAIL_THICKNESS), fork.y + s * ly * (half + RAIL_THICKNESS),
                          fork.z, fork.yaw + s * math.pi / 2)
        lane_params = {**params, "width": mouth, "speed": params.get("lane_speed", params["speed"])}
        lane = build_belt(name, "lane", lane_params, world, Straight(lane_start, params["lane_length"]))
        world.anchors[name] = line.end
        # The plate stands in the near rail's opening, its face flush with the rail's inner face,
        # and slides towards the lane.
        across = -s * (half + RAIL_THICKNESS / 2)
        height = params["plate_height"]
        centre = (fork.x + lx * across, fork.y + ly * across, fork.z + height / 2)
        part = world.add_moving_boxes([centre], [(plate / 2, RAIL_THICKNESS / 2, height / 2)], [fork.yaw],
                                      (s * lx, s * ly, 0.0))
        stroke = params.get("stroke", params["width"] + RAIL_THICKNESS)
        out = params["push_speed"]
        legs = (Leg(stroke, out, params["dwell"]), Leg(0.0, params.get("return_speed", out)))
        return {"push": Push(name, "push", world, part, legs, stroke), "main": main, "lane": lane}
