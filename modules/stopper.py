"""Stopper: one gate across a belt that holds bottles back until it opens (the paper's stopping element).

See modules/gate.py for the timing and why a gate never closes onto a bottle.
"""
from __future__ import annotations

import math

from hub.core.module import Module
from modules.gate import GATE_PARAMETERS, Gate, gate_across
from modules.params import POSITION, YAW


class Stopper(Module):
    """A gate across the belt at `position` (on its centre line, at its surface), facing along `yaw`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "foot of the gate on the belt's centre line, m"},
            "yaw": {**YAW, "description": "heading of the belt there, degrees"},
            **GATE_PARAMETERS,
            "closed": {"type": "boolean", "default": True, "description": "closed at the start"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"gate": Gate}

    @classmethod
    def build(cls, name, params, world):
        blocker = gate_across(world, params["position"], math.radians(params["yaw"]), params, params["closed"])
        return {"gate": Gate(name, "gate", blocker)}
