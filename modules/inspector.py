"""Inspector (fill-level and cap check): a volume trigger that checks each bottle entering it and fires `failed` for one that is not filled or not capped.

What a bottling line has after its capper: a fill-level and cap inspection whose reject signal
fires the ejector (modules/pusher.py) for a bottle that is not as it should be. A bottle passes
when it has every state in `requires` (`filled`, `capped`) in the plant's manifest
(modules/manifest.py), where the stations write them: a station that processes a bottle badly
leaves its state unset (modules/station.py `faults`). The check is made as the bottle enters, so
`failed` can fire a pusher at once; both results are in the event log with the tick the bottle
entered and its id. When several bottles enter in one communication step, `checked` carries the
last; `failed` fires if any of them failed.
"""
from __future__ import annotations

from hub.core.module import Module
from hub.core.slots import Slot
from modules.manifest import cargo
from modules.trigger import VolumeTrigger, add_volume, volume_parameters

STATES = ("filled", "capped")


class Inspection(VolumeTrigger):
    SLOTS = VolumeTrigger.SLOTS + (
        Slot.source("passed", "void", "a bottle that entered in this step passed the check"),
        Slot.source("failed", "void", "a bottle that entered in this step failed it"),
        Slot.source("checked", "string", "id of the bottle checked last; active with passed and failed"),
    )

    STATE = VolumeTrigger.STATE + ("results",)

    def __init__(self, obj, name, world, trigger, requires: tuple[str, ...]):
        super().__init__(obj, name, world, trigger)
        self.requires = requires
        self.results: list[tuple[int, str, str]] = []   # (tick entered, passed/failed, id) at this point

    def sense(self, tick):
        super().sense(tick)
        self.results = []
        for entered, n in self.latch.entered:
            entry = cargo(self.world, n)
            good = all(getattr(entry, state) for state in self.requires)
            self.results.append((entered, "passed" if good else "failed", entry.id))
        for result in ("passed", "failed"):
            if any(r == result for _, r, _ in self.results):
                self.emit(result)
        if self.results:
            self.emit("checked", self.results[-1][2])

    def events(self, tick):
        rows = super().events(tick)
        return [*rows, *self.results] if self.results else rows


class Inspector(Module):
    """A box-shaped inspection volume centred at `position`; `size` is along, across and up the belt."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **volume_parameters([0.005, 0.2, 0.02], "inspection volume"),
            "requires": {"type": "array", "items": {"enum": list(STATES)}, "uniqueItems": True, "minItems": 1,
                         "default": list(STATES), "description": "what a bottle must be to pass: filled, capped"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"trigger": Inspection}

    @classmethod
    def build(cls, name, params, world):
        return {"trigger": Inspection(name, "trigger", world, add_volume(world, params), tuple(params["requires"]))}
