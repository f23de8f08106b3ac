"""The volume trigger component shared by every sensing module: a box latched over the physics substeps.

Enter and leave events go to the event log with the exact physics tick and the object's id;
an object that enters and leaves between two communication points gives both events.
"""
from __future__ import annotations

import math

from hub.core.component import Component
from hub.core.slots import Slot
from modules.params import POSITION, YAW


def volume_parameters(size: list[float], what: str) -> dict:
    """Schema properties of a box volume: its centre, yaw and size along, across and up."""
    return {
        "position": {**POSITION, "description": f"centre of the {what}, m"},
        "yaw": YAW,
        "size": {"type": "array", "items": {"type": "number", "exclusiveMinimum": 0},
                 "minItems": 3, "maxItems": 3, "default": size,
                 "description": "extent along, across and up, m"},
    }


def add_volume(world, params) -> int:
    """The world trigger of a box volume given by `volume_parameters`."""
    half = [s / 2 for s in params["size"]]
    return world.add_trigger(params["position"], half, math.radians(params["yaw"]))


class VolumeTrigger(Component):
    """The paper's volume trigger; `latch` keeps what the world saw since the last point."""

    SLOTS = (
        Slot.source("on_enter", "void", "an object entered the volume in this step"),
        Slot.source("on_stay", "void", "an object was inside at some tick of this step"),
        Slot.source("on_leave", "void", "an object left the volume in this step"),
        Slot.source("object", "string", "id of the object that entered last; active with on_enter"),
        Slot.source("occupied", "bool", "whether an object is inside now, every step"),
    )

    EVENTS_WHEN = ("on_enter", "on_leave")   # its rows are the latch's entries and exits

    STATE = ("latch",)

    def __init__(self, obj, name, world, trigger):
        super().__init__(obj, name)
        self.world = world
        self.trigger = trigger
        self.latch = None

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers settled once: every trigger senses at every point (13 in the bottling plant).
        self._at = tuple(index[name] for name in ("on_enter", "on_stay", "on_leave", "object", "occupied"))

    def sense(self, tick):
        latch = self.latch = self.world.take_trigger(self.trigger)
        values, active = self.signals.values, self.signals.active
        on_enter, on_stay, on_leave, obj, occupied = self._at
        if latch.entered:
            active[on_enter] = active[obj] = True
            values[obj] = self.world.labels[latch.entered[-1][1]]
        if latch.stayed:
            active[on_stay] = True
        if latch.left:
            active[on_leave] = True
        values[occupied] = bool(latch.inside)
        active[occupied] = True

    def events(self, tick):
        latch = self.latch
        if not (latch.entered or latch.left):
            return ()
        labels = self.world.labels
        return ([(t, "on_enter", labels[n]) for t, n in latch.entered]
                + [(t, "on_leave", labels[n]) for t, n in latch.left])
