"""Track switch: a T-junction of a straight main belt and a branch belt, with a blade that diverts bottles into the branch.

The blade is the paper's arcuate rigid body of box shapes (Fig. 7): the outer guard rail of a
quarter circle from the main belt's centre line into the branch's, starting tangent to the
main belt's far rail and ending tangent to the branch's downstream rail, its faces a polygon
inscribed in that arc (modules/belt.py `arc_rail`). Base and working position are its
collision switched off and on, as in the paper; the move takes `travel_time`, and the blade
turns solid only when no bottle overlaps it (see modules/gate.py for why and how it waits).
Which position to take for which bottle is the switch's state logic: with `logic: default`
the paper's Fig. 8 net runs as the object's `logic` component (commands on
`logic.MoveToWorkingPos_put` / `logic.MoveToBasePos_put`, its WorkingPos place driving
`blade.working`); without it, flows drive the blade directly.

The switch builds both belts because the main belt's near rail needs an opening where the
branch leaves (a conveyor's rails are unbroken). Their floors, like every belt's, merge with
the floors they touch (hub/physics/supports.py), so conveyors placed at the ends of its main
belt or branch hand bottles over without a seam. (`after:` accepts only conveyors and curves
for now; the main belt's end is registered as the switch's anchor for when it accepts more.)
"""
from __future__ import annotations

import math

from hub.core.logic_spec import LogicSpec
from hub.core.module import Module
from hub.core.slots import Slot
from hub.physics.frames import Arc, Pose, Straight
from modules.belt import COMMON, PLACEMENT, RAIL_THICKNESS, BeltDrive, arc_rail, build_belt, check_placement, start_pose
from modules.gate import Blocker, TwoPositions
from modules.params import length

SIDES = {"left": 1, "right": -1}


class Blade(TwoPositions):
    SLOTS = (
        Slot.target("to_base", "void", "move to base position: bottles run straight on"),
        Slot.target("to_working", "void", "move to working position: bottles turn into the branch"),
        Slot.target("working", "bool", "true moves to working, false to base (a level instead of events)"),
        Slot.source("in_base", "bool", "the blade is in base position, every step"),
        Slot.source("in_working", "bool", "the blade is in working position and guides, every step"),
        Slot.source("on_base", "void", "reached base position"),
        Slot.source("on_working", "void", "reached working position"),
        Slot.source("blocked", "bool", "a move to working waits for a bottle to clear the blade"),
    )
    NAMES = {"to_passable": "to_base", "to_solid": "to_working", "level": "working", "is_solid": "in_working",
             "is_passable": "in_base", "reached_solid": "on_working", "reached_passable": "on_base",
             "blocked": "blocked"}


class Switch(Module):
    """A main belt from `position` along `yaw` with a branch leaving to one `side` at `branch_at`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **PLACEMENT,
            "length": length(description="main belt length, m"),
            "branch_at": length(description="distance along the main belt to the branch's centre line, m"),
            "branch_length": length(description="branch belt length from the main belt's rail, m"),
            "side": {"enum": sorted(SIDES), "default": "right", "description": "side the branch leaves to"},
            **COMMON,
            "branch_speed": {"type": "number", "description": "branch belt speed, m/s (default: `speed`)"},
            "blade_height": length(0.06, "blade height above the surface, m (above a bottle's centre of mass)"),
            "blade_tolerance": length(0.002, "how far the blade's flat faces may stray from the arc, m"),
            "travel_time": {"type": "number", "minimum": 0, "default": 0.2,
                            "description": "time the blade takes to move, s"},
            "working": {"type": "boolean", "default": False, "description": "start in working position"},
        },
        "required": ["length", "branch_at", "branch_length"],
        "additionalProperties": False,
    }
    COMPONENTS = {"blade": Blade, "main": BeltDrive, "branch": BeltDrive}
    # The paper's Fig. 8 net (fmus/nets/track_switch.pnml): commands on logic.MoveToWorkingPos_put
    # and logic.MoveToBasePos_put; the marked WorkingPos place holds the blade in working position.
    LOGIC = LogicSpec(
        model="track_switch",
        events=("MoveToBasePos_put", "MoveToWorkingPos_put", "BasePosStartAnim_got", "WorkingPosStartAnim_got"),
        wiring=(("logic.WorkingPos_marked", "blade.working"),),
    )

    @classmethod
    def slots(cls, params):
        return {"blade": Blade.SLOTS, "main": BeltDrive.SLOTS, "branch": BeltDrive.SLOTS}

    @classmethod
    def check(cls, params):
        problems = check_placement(params)
        half, a, total = params["width"] / 2, params["branch_at"], params["length"]
        turn = half + RAIL_THICKNESS   # the blade's quarter circle starts this far before the branch
        if a - turn < 0:
            problems.append((("branch_at",), f"{a:g} m leaves no room for the blade before the branch: "
                                             f"it needs at least {turn:g} m of main belt"))
        if a + half + RAIL_THICKNESS > total:
            problems.append((("branch_at",), f"{a:g} m puts the branch's opening past the main belt's end "
                                             f"(length {total:g} m): at most {total - half - RAIL_THICKNESS:g} m"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        start = start_pose(name, params, world)
        main = Straight(start, params["length"])
        s, half, a = SIDES[params["side"]], params["width"] / 2, params["branch_at"]
        fork = main.pose_at(a)
        lx, ly = fork.left
        branch_start = Pose(fork.x + s * lx * (half + RAIL_THICKNESS), fork.y + s * ly * (half + RAIL_THICKNESS),
                            fork.z, fork.yaw + s * math.pi / 2)
        branch_params = {**params, "speed": params.get("branch_speed", params["speed"])}
        branch = build_belt(name, "branch", branch_params, world, Straight(branch_start, params["branch_length"]))
        # The main belt's rail on the branch side is open over the branch's width.
        drive = build_belt(name, "main", params, world, main, ((-s, ()), (s, [(a - half, a + half)])))
        world.anchors[name] = main.end
        # The blade: outer rail of a quarter circle of radius half + rail from the main centre
        # line into the branch's, so its ends meet the far rail and the downstream branch rail.
        turn = half + RAIL_THICKNESS
        arc = Arc(main.pose_at(a - turn), turn, math.pi / 2, s)
        centres, halves, yaws = arc_rail(arc, -s, half, params["blade_height"], params["blade_tolerance"])
        blocker = Blocker(world, centres, halves, yaws, params["working"], round(params["travel_time"] * world.rate))
        return {"blade": Blade(name, "blade", blocker), "main": drive, "branch": branch}
