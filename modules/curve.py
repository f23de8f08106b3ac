"""Curved conveyor belt: a force-field region on an annular sector, guard rails of boxes along the arc.

The belt turns `left` or `right` by `angle` degrees on a centre line of `radius`. It moves as a
rotating surface (ω = speed/radius about the curve's centre): with `grip: surface` (default)
friction acts on both horizontal components towards ω×r, so a bottle turns with the belt at
its own radius and never leans on a rail; with `grip: along` (the paper's law) only the
tangential component is driven and the outer rail turns the bottle. Start it at
`position`/`yaw` or `after: NAME` (see modules/belt.py).
"""
from __future__ import annotations

import math

from hub.core.module import Module
from hub.physics.frames import Arc
from modules.belt import COMMON, PLACEMENT, RAIL_THICKNESS, BeltDrive, build_segment, check_placement, start_pose
from modules.belt import LOGIC as BELT_LOGIC
from modules.params import length


class Curve(Module):
    """A curved belt turning left or right by `angle` degrees on a centre line of `radius`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **PLACEMENT,
            "turn": {"enum": ["left", "right"], "description": "direction of the turn seen in the direction of travel"},
            "angle": {"type": "number", "exclusiveMinimum": 0, "maximum": 360, "default": 90.0,
                      "description": "angle turned, degrees"},
            "radius": length(0.5, "radius of the centre line, m"),
            **COMMON,
            "rail_tolerance": length(0.0005, "largest gap between the boxed rails and the true arc, m"),
        },
        "required": ["turn"],
        "additionalProperties": False,
    }
    COMPONENTS = {"drive": BeltDrive}
    LOGIC = BELT_LOGIC

    @classmethod
    def check(cls, params):
        problems = check_placement(params)
        least = params["width"] / 2 + RAIL_THICKNESS
        if params["radius"] <= least:
            problems.append((("radius",), f"{params['radius']:g} m is too tight for a belt {params['width']:g} m "
                                          f"wide: the centre line's radius must exceed half the width plus "
                                          f"the rail ({least:g} m)"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        turn = 1 if params["turn"] == "left" else -1
        arc = Arc(start_pose(name, params, world), params["radius"], math.radians(params["angle"]), turn)
        return build_segment(name, params, world, arc)
