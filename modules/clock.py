"""Clock: fires a void event at set times — a stand-in for the timers and logic that will drive the actuators.

Times are given as a list (`at`) or as a period (`every`, from `start`, at most `count` times).
Each fires at the first communication point at or after its tick (time × physics rate,
rounded), so a run is the same whatever the communication step divides it into; two times
within one step fire once.
"""
from __future__ import annotations

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot


class Clock(Component):
    SLOTS = (
        Slot.source("fire", "void", "one of the set times was reached in this step"),
        Slot.source("count", "int", "how many times it fired so far, every step"),
    )

    STATE = ("next", "count")

    def __init__(self, obj, name, tick_of, total):
        super().__init__(obj, name)
        self.tick_of = tick_of      # i → tick of the i-th time, computed from i (nothing accumulates)
        self.total = total
        self.next = 0
        self.count = 0

    def sense(self, tick):
        fired = False
        while self.next < self.total and self.tick_of(self.next) <= tick:
            self.next += 1
            fired = True
        if fired:
            self.count += 1
            self.emit("fire")
        self.emit("count", self.count)


class ClockModule(Module):
    """Fires at the times `at`, or every `every` seconds from `start`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "at": {"type": "array", "items": {"type": "number", "minimum": 0}, "minItems": 1,
                   "description": "times to fire, s"},
            "every": {"type": "number", "exclusiveMinimum": 0, "description": "period, s (instead of `at`)"},
            "start": {"type": "number", "minimum": 0, "default": 0.0, "description": "first time with `every`, s"},
            "count": {"type": "integer", "minimum": 1, "description": "at most this many times with `every`"},
        },
        "additionalProperties": False,
    }
    COMPONENTS = {"clock": Clock}

    @classmethod
    def check(cls, params):
        if ("at" in params) == ("every" in params):
            return [((), "give either `at` (a list of times) or `every` (a period), not both or neither")]
        if "at" in params and params["at"] != sorted(params["at"]):
            return [(("at",), "times must be in increasing order")]
        return []

    @classmethod
    def build(cls, name, params, world):
        rate = world.rate
        if "at" in params:
            ticks = [round(t * rate) for t in params["at"]]
            return {"clock": Clock(name, "clock", ticks.__getitem__, len(ticks))}
        start, every = params["start"], params["every"]
        return {"clock": Clock(name, "clock", lambda i: round((start + i * every) * rate),
                               params.get("count", float("inf")))}
