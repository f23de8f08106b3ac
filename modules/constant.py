"""Constant: turns an event into a value — emits a fixed value whenever its `set` slot fires.

With `always: true` the value is emitted in every step, as a setpoint that never changes.
`value.out` holds the value from the start, so a flow with `when: target` pulls it any time.
The value follows `set` within the same step, so a sensor event can stop a belt at once.
"""
from __future__ import annotations

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot, SlotFamily, SlotType


class Value(Component):
    FEEDTHROUGH = (("set", "out"),)

    def __init__(self, obj, name, slots, value, always):
        super().__init__(obj, name)
        self.SLOTS = slots
        self.constant = value
        self.always = always

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Hold the value from the start, so a flow that pulls (when: target) reads it at once.
        signals.values[index["out"]] = self.constant

    def react(self):
        if self.always or self.updated("set"):
            self.emit("out", self.constant)


class Constant(Module):
    """A fixed value of any slot type, emitted on an event or in every step."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "type": {"enum": [t.value for t in SlotType if t is not SlotType.VOID],
                     "description": "slot type of the value"},
            "value": {"description": "the value, in the slot type's YAML form (e.g. [0, 0, 1] for vec3)"},
            "always": {"type": "boolean", "default": False, "description": "emit in every step"},
        },
        "required": ["type", "value"],
        "additionalProperties": False,
    }
    COMPONENTS = {"value": Value}
    SLOT_FAMILIES = {"value": (SlotFamily.source("out", "param `type`", "the fixed value; active when `set` fired "
                                                                        "(or always)"),)}

    @classmethod
    def slots(cls, params):
        kind = params.get("type", "real")
        return {"value": (Slot.target("set", "void", "emit the value in this step"),
                          Slot.source("out", kind, cls.SLOT_FAMILIES["value"][0].doc))}

    @classmethod
    def check(cls, params) -> list[tuple[tuple, str]]:
        try:
            SlotType(params["type"]).coerce(params["value"])
        except ValueError as exc:
            return [(("value",), f"not a {params['type']}: {exc}")]
        return []

    @classmethod
    def build(cls, name, params, world):
        kind = SlotType(params["type"])
        slots = cls.slots(params)["value"]
        return {"value": Value(name, "value", slots, kind.coerce(params["value"]), params["always"])}
