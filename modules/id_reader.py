"""ID reader (bar code scanner): a volume trigger that reads the id of each bottle entering and leaving.

A plant-management system routes by the id read on entry (the paper's switches ask for the
destination of the incoming bottle) and tracks where each bottle is by the id that left; both
are in the event log with their exact tick. The destination, fill and cap state come from the
plant's manifest (modules/manifest.py), as a management system would look the id up. When
several bottles enter in one communication step the slots carry the last; the event log has
every one.
"""
from __future__ import annotations

from hub.core.module import Module
from hub.core.slots import Slot
from modules.manifest import cargo
from modules.trigger import VolumeTrigger, add_volume, volume_parameters


class IdTrigger(VolumeTrigger):
    SLOTS = VolumeTrigger.SLOTS + (
        Slot.source("left", "string", "id of the bottle that left last; active with on_leave"),
        Slot.source("destination", "string", "destination of the bottle that entered last; with on_enter"),
        Slot.source("filled", "bool", "whether that bottle is filled; with on_enter"),
        Slot.source("capped", "bool", "whether that bottle is capped; with on_enter"),
    )

    def sense(self, tick):
        super().sense(tick)
        latch = self.latch
        if latch.entered:
            entry = cargo(self.world, latch.entered[-1][1])
            self.emit("destination", entry.destination)
            self.emit("filled", entry.filled)
            self.emit("capped", entry.capped)
        if latch.left:
            self.emit("left", self.world.labels[latch.left[-1][1]])


class IdReader(Module):
    """A box-shaped reading volume centred at `position`; `size` is along, across and up the belt."""

    PARAMETERS = {
        "type": "object",
        "properties": volume_parameters([0.005, 0.2, 0.02], "reading volume"),
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"trigger": IdTrigger}

    @classmethod
    def build(cls, name, params, world):
        return {"trigger": IdTrigger(name, "trigger", world, add_volume(world, params))}
