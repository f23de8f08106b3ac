"""What every belt segment (straight `conveyor`, `curve`) shares: its drive, its parameters, and how it is placed and built.

Placing: a segment starts at `position` heading `yaw`, or `after: NAME` — where the belt NAME
(declared before it) ends, heading on. Chained segments share their end point exactly, their
force-field regions abut there (a bottle is handed over at one point, see
hub/physics/fields.py), their guard rails meet there, and their floors merge into one box (see
hub/physics/supports.py), so a bottle crosses the seam without a bump.
"""
from __future__ import annotations

import math

from hub.core.component import Component
from hub.core.errors import Problem, ScenarioError
from hub.core.logic_spec import LogicSpec
from hub.core.registry import did_you_mean
from hub.core.slots import Slot
from hub.physics.frames import Arc, Pose, Straight
from modules.params import POSITION, length

RAIL_THICKNESS = 0.01
SUPPORT_THICKNESS = 0.02
K_DEFAULT = 16.0


# The belt's state logic (fmus/nets/belt_run_stop.pnml): `logic.Run_put` and `logic.Stop_put`
# are the run and stop commands; the net's Running place drives the belt. It starts in the
# state the belt's `running` parameter gives.
LOGIC = LogicSpec(
    model="belt_run_stop",
    events=("Run_put", "Stop_put", "Running_got", "Stopped_got"),
    wiring=(("logic.Running_marked", "drive.run"),),
    parameters=lambda params: {"Running_initial": int(params["running"]), "Stopped_initial": int(not params["running"])},
)


class BeltDrive(Component):
    SLOTS = (
        Slot.target("speed", "real", "target belt speed, m/s (negative runs backwards)"),
        Slot.target("run", "bool", "true runs the belt, false stops it (speed kept)"),
        Slot.source("running", "bool", "whether the belt runs, every step"),
        Slot.source("velocity", "real", "speed the field drives bottles to now, m/s, every step"),
    )

    STATE = ("speed", "running", "_applied", "_running", "_velocity")

    def __init__(self, obj, name, world, field, speed, running):
        super().__init__(obj, name)
        self.world = world
        self.field = field
        self.speed = speed
        self.running = running
        self._applied = None   # the speed last given to the world's field

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers settled once: sense and actuate run at every point for every belt (19 in the bottling plant).
        self._running, self._velocity = index["running"], index["velocity"]
        self._speed, self._run = index["speed"], index["run"]

    def sense(self, tick):
        values, active = self.signals.values, self.signals.active
        values[self._running] = self.running
        values[self._velocity] = self.speed if self.running else 0.0
        active[self._running] = active[self._velocity] = True

    def held(self, slot):
        return {"run": self.running, "speed": self.speed}.get(slot)

    def actuate(self):
        updated, values = self.signals.updated, self.signals.values
        if updated[self._speed]:
            self.speed = values[self._speed]
        if updated[self._run]:
            self.running = values[self._run]
        speed = self.speed if self.running else 0.0
        if speed != self._applied:   # the field is this belt's alone: the same speed again changes nothing
            self.world.set_field_speed(self.field, speed)
            self._applied = speed


PLACEMENT = {
    "position": {**POSITION, "description": "start of the belt's centre line on its surface, m (or give `after`)"},
    "yaw": {"type": "number", "description": "heading at the start, degrees (default 0; not with `after`)"},
    "after": {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$", "x-object": ["conveyor", "curve"],
              "description": "start where this belt (declared before) ends, heading on"},
}

COMMON = {
    "width": length(0.1, "clear width between the guard rails, m"),
    "speed": {"type": "number", "default": 0.5, "description": "belt speed on the centre line, m/s"},
    "k": {"type": "number", "exclusiveMinimum": 0,
          "description": f"force-field rate 1/s, force scaled by the bottle's mass (default {K_DEFAULT:g})"},
    "gain": {"type": "number", "exclusiveMinimum": 0,
             "description": "instead of k: the paper's unscaled law F = gain·(v_tar − v), N·s/m"},
    "grip": {"enum": ["surface", "along"], "default": "surface",
             "description": "surface: friction on both horizontal components towards the moving belt "
                            "surface (a curve turns the bottle); along: only along the belt (the paper)"},
    "friction": {"type": "number", "exclusiveMinimum": 0,
                 "description": "friction coefficient μ between belt and bottle: the belt accelerates a bottle "
                                "by at most μ·g and slides under one held back, so a queue is pressed by μ·m·g "
                                "per bottle (default: no limit, the paper's law; a queue of 40 then falls apart)"},
    "running": {"type": "boolean", "default": True},
    "rail_height": length(0.07, "guard rail height above the surface, m (above the bottles' contact ring at "
                                "their centre of mass: over a lower rail a pressed queue leans and tips)"),
    "field_height": length(0.3, "height of the force-field region above the surface, m"),
}


def check_placement(params) -> list[tuple[tuple, str]]:
    """Problems of position/yaw/after and k/gain that the schema cannot express."""
    problems = []
    if "after" in params:
        for key in ("position", "yaw"):
            if key in params:
                problems.append(((key,), f"give either `after` or `{key}`: a belt placed after "
                                         f"{params['after']!r} starts where that belt ends"))
    elif "position" not in params:
        problems.append(((), "needs `position` (start of its centre line) or `after` (the belt it continues)"))
    if "k" in params and "gain" in params:
        problems.append((("gain",), "give `k` (rate 1/s, force scaled by mass) or `gain` "
                                    "(the paper's unscaled law, N·s/m), not both"))
    return problems


def start_pose(name: str, params: dict, world) -> Pose:
    if "after" in params:
        previous = params["after"]
        if previous not in world.anchors:
            raise ScenarioError([Problem(f"objects.{name}", None, "after",
                                         f"no belt {previous!r} is declared before {name!r}"
                                         f"{did_you_mean(previous, world.anchors)}")])
        return world.anchors[previous]
    x, y, z = params["position"]
    return Pose(float(x), float(y), float(z), math.radians(params.get("yaw", 0.0)))


def build_segment(name: str, params: dict, world, line: Straight | Arc) -> dict[str, Component]:
    """Floor, guard rails, force field and end anchor of one belt segment along `line`."""
    drive = build_belt(name, "drive", params, world, line)
    world.anchors[name] = line.end
    return {"drive": drive}


#: Both rails of a straight belt, unbroken: (side, its openings), left (+1) first.
UNBROKEN = ((1, ()), (-1, ()))


def build_belt(name: str, component: str, params: dict, world, line: Straight | Arc,
               rails=UNBROKEN) -> BeltDrive:
    """The floor, guard rails and force field of one belt along `line` (its `width`, `rail_height`,
    `field_height`, `speed`, `running`, `k` or `gain`, `grip`, `friction` from `params`), and
    its drive, component `component` of object `name`. A straight belt's `rails` are (side,
    openings) in the order they are built, side +1 left and −1 right of the line and openings
    (from, to) along it where the rail leaves room for a branch, a lane or a pusher's plate; an
    arc's rails are unbroken. The order of the bodies is the order of the engine's calls, which
    its results depend on."""
    z, half = line.start.z, params["width"] / 2.0
    world.add_support(z, line.footprint(half + RAIL_THICKNESS), SUPPORT_THICKNESS)
    height = params["rail_height"]
    if isinstance(line, Straight):
        for centre, half_extents, yaw in straight_rails(line, half, height, rails):
            world.add_static_box(centre, half_extents, yaw)
    else:
        for side in (1, -1):
            world.add_static_boxes(*arc_rail(line, side, half, height, params["rail_tolerance"]))
    if "gain" in params:
        rate, per_mass = params["gain"], False
    else:
        rate, per_mass = params.get("k", K_DEFAULT), True
    speed, running = params["speed"], params["running"]
    # The field reaches a little below the surface: a bottle rides ~2 mm deep in it at 150 Hz,
    # and a bottle gripped at its base must still be found inside.
    field = world.add_belt_field(line, half, z - SUPPORT_THICKNESS, z + params["field_height"], rate,
                                 speed if running else 0.0, params["grip"], per_mass, params.get("friction"))
    return BeltDrive(name, component, world, field, speed, running)


def straight_rails(line: Straight, half_width: float, height: float, rails=UNBROKEN):
    """(centre, half extents, yaw) of the rail boxes, inner faces at ±half_width: per side of
    `rails`, one box for each stretch between its openings."""
    lx, ly = line.start.left
    out = []
    for side, openings in rails:
        offset = side * (half_width + RAIL_THICKNESS / 2)
        ends = [0.0, *(u for opening in openings for u in opening), line.length]
        for u0, u1 in zip(ends[::2], ends[1::2]):
            if u1 - u0 <= 1e-9:
                continue
            mid = line.pose_at((u0 + u1) / 2)
            out.append(((mid.x + lx * offset, mid.y + ly * offset, mid.z + height / 2),
                        ((u1 - u0) / 2, RAIL_THICKNESS / 2, height / 2), line.start.yaw))
    return out


def arc_rail(arc: Arc, side: int, half_width: float, height: float, tolerance: float):
    """(centres, half extents, yaws) of the boxes of one rail along an arc (side +1 left, −1 right).

    The rail's face towards the belt is a polygon inscribed in the circle at ±half_width from the
    centre line, fine enough that it strays at most `tolerance` from that circle; each box lies
    behind its chord, away from the belt. Adjacent faces meet exactly at the polygon's corners,
    and the first and last corner are where the straight rails of the neighbouring belts end,
    so a bottle sliding along a rail meets no protruding edge.
    """
    cx, cy = arc.centre
    face = arc.radius - arc.turn * side * half_width
    outward = 1.0 if face > arc.radius else -1.0
    step_max = 2.0 * math.acos(max(-1.0, 1.0 - tolerance / face))
    count = max(1, math.ceil(arc.sweep / step_max - 1e-9))
    step = arc.sweep / count
    centres, halves, yaws = [], [], []
    for i in range(count):
        mid = arc.start_angle + arc.turn * (i + 0.5) * step
        r = face * math.cos(step / 2) + outward * RAIL_THICKNESS / 2
        centres.append((cx + r * math.cos(mid), cy + r * math.sin(mid), arc.start.z + height / 2))
        halves.append((face * math.sin(step / 2), RAIL_THICKNESS / 2, height / 2))
        yaws.append(mid + math.pi / 2)
    return centres, halves, yaws
