"""Stopper: one gate across a belt that holds bottles back until it opens (the paper's stopping element).

| slot           | type | dir    | meaning                                                          |
|----------------|------|--------|------------------------------------------------------------------|
| gate.open      | void | target | open: let bottles pass                                           |
| gate.close     | void | target | close: block the belt (waits until no bottle is in the way)      |
| gate.closed    | bool | target | true closes, false opens                                         |
| gate.is_closed | bool | source | closed and blocking, every step                                  |
| gate.is_open   | bool | source | open, every step (both false while it moves)                     |
| gate.on_closed | void | source | reached closed                                                   |
| gate.on_opened | void | source | reached open                                                     |
| gate.blocked   | bool | source | a close waits for a bottle to clear the gate, every step         |

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
