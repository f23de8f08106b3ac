"""Straight conveyor belt: a force-field region over a continuous support surface, with guard rails.

Start it at `position`/`yaw`, or `after: NAME` to continue the belt NAME (see modules/belt.py);
`curve` is its curved sibling, with the same slots.
"""
from __future__ import annotations

from hub.core.module import Module
from hub.physics.frames import Straight
from modules.belt import COMMON, PLACEMENT, BeltDrive, build_segment, check_placement, start_pose
from modules.belt import LOGIC as BELT_LOGIC
from modules.params import length

__all__ = ["Conveyor", "BeltDrive"]


class Conveyor(Module):
    """A straight belt from `position` (start of its centre line, on the belt surface) along `yaw`.

    The belt itself is a region above the surface in which the paper's force field drives each
    bottle towards the belt's velocity (see hub/physics/fields.py).
    """

    PARAMETERS = {
        "type": "object",
        "properties": {
            **PLACEMENT,
            "length": length(description="belt length, m"),
            **COMMON,
        },
        "required": ["length"],
        "additionalProperties": False,
    }
    COMPONENTS = {"drive": BeltDrive}
    LOGIC = BELT_LOGIC

    @classmethod
    def check(cls, params):
        return check_placement(params)

    @classmethod
    def build(cls, name, params, world):
        return build_segment(name, params, world, Straight(start_pose(name, params, world), params["length"]))
