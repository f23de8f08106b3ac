"""Connector: AND / OR over the activity of two void signals, each optionally negated.

The output follows the inputs within the same step (zero delay), so connectors chained in a
ring form a zero-delay loop, which the scenario check rejects.
"""
from __future__ import annotations

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot


class Logic(Component):
    SLOTS = (
        Slot.target("in0", "void", "first signal: active when a flow fed it"),
        Slot.target("in1", "void", "second signal"),
        Slot.source("out", "void", "active when `op` over the (negated) inputs holds"),
    )
    FEEDTHROUGH = (("in0", "out"), ("in1", "out"))

    def __init__(self, obj, name, op, negate):
        super().__init__(obj, name)
        self.op = all if op == "and" else any
        self.negate = negate

    def react(self):
        a = self.updated("in0") != self.negate[0]
        b = self.updated("in1") != self.negate[1]
        if self.op((a, b)):
            self.emit("out")


class Connector(Module):
    """A logical data-flow connector (the paper's Fig. 2)."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "op": {"enum": ["and", "or"]},
            "negate": {"type": "array", "items": {"type": "boolean"}, "minItems": 2, "maxItems": 2,
                       "default": [False, False], "description": "negate in0, in1"},
        },
        "required": ["op"],
        "additionalProperties": False,
    }
    COMPONENTS = {"logic": Logic}

    @classmethod
    def build(cls, name, params, world):
        return {"logic": Logic(name, "logic", params["op"], tuple(params["negate"]))}
