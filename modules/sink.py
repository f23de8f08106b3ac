"""Sink: takes every bottle that enters its volume out of the plant and counts them by destination.

| slot              | type   | dir    | meaning                                                     |
|-------------------|--------|--------|-------------------------------------------------------------|
| bin.taken         | void   | source | a bottle was taken out in this step                         |
| bin.object        | string | source | id of the bottle taken last; active with taken              |
| bin.destination   | string | source | its destination; active with taken                          |
| count.total       | int    | source | bottles taken so far, every step                            |
| count.DEST        | int    | source | bottles with destination DEST taken so far (one per name in `destinations`) |
| count.other       | int    | source | bottles with any other destination, every step              |

A bottle is taken out at the first communication point after it entered (it is parked off
stage, see hub/physics/world.py `park`, and costs nothing from then on); all bottles that
entered since the last point are taken, in the order they entered. Destinations come from
the plant's manifest (modules/manifest.py): a source's bottles carry theirs, a `bottle`
object has none and counts as `other`.
"""
from __future__ import annotations

import re

from hub.component import Component
from hub.module import Module
from hub.slots import Slot

from .manifest import cargo
from .trigger import add_volume, volume_parameters

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class Bin(Component):
    SLOTS = (
        Slot.source("taken", "void", "a bottle was taken out"),
        Slot.source("object", "string", "id of the bottle taken last"),
        Slot.source("destination", "string", "its destination"),
    )

    def __init__(self, obj, name, world, trigger, counter):
        super().__init__(obj, name)
        self.world = world
        self.trigger = trigger
        self.counter = counter
        self.taken: list[int] = []

    def sense(self, tick):
        latch = self.world.take_trigger(self.trigger)
        world = self.world
        self.taken = [n for _, n in latch.entered if not world.is_parked(n)]
        for n in self.taken:
            self.counter.add(cargo(world, n).destination)
        if self.taken:
            last = cargo(world, self.taken[-1])
            self.emit("taken")
            self.emit("object", last.id)
            self.emit("destination", last.destination)

    def actuate(self):
        for n in self.taken:
            self.world.park(n)
        self.taken = []

    def events(self, tick):
        for n in self.taken:
            yield tick, "taken", self.world.labels[n]


class Count(Component):
    """Slots `total`, one per listed destination, and `other`; set per instance."""

    def __init__(self, obj, name, destinations):
        super().__init__(obj, name)
        self.SLOTS = Sink.count_slots(destinations)
        self.counts = {slot.name: 0 for slot in self.SLOTS}

    def add(self, destination: str) -> None:
        self.counts["total"] += 1
        key = destination if destination in self.counts and destination not in ("total", "other") else "other"
        self.counts[key] += 1

    def sense(self, tick):
        for name, value in self.counts.items():
            self.emit(name, value)


class Sink(Module):
    """A box volume centred at `position` that takes bottles out; `size` along, across and up."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **volume_parameters([0.05, 0.1, 0.1], "volume"),
            "destinations": {"type": "array", "items": {"type": "string"}, "uniqueItems": True, "default": [],
                             "description": "destinations counted on their own slots count.NAME"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"bin": Bin, "count": Count}

    @staticmethod
    def count_slots(destinations) -> tuple[Slot, ...]:
        return (Slot.source("total", "int", "bottles taken so far"),
                *(Slot.source(d, "int", f"bottles for {d!r} taken so far") for d in destinations),
                Slot.source("other", "int", "bottles for any other destination taken so far"))

    @classmethod
    def slots(cls, params):
        return {"bin": Bin.SLOTS, "count": cls.count_slots(params.get("destinations", []))}

    @classmethod
    def check(cls, params):
        problems = []
        for i, d in enumerate(params["destinations"]):
            if not _NAME.match(d):
                problems.append((("destinations", i), f"{d!r} cannot name a slot: use letters, digits and _ "
                                                       "(not starting with a digit)"))
            elif d in ("total", "other"):
                problems.append((("destinations", i), f"{d!r} is taken by the slot count.{d}"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        counter = Count(name, "count", params["destinations"])
        return {"bin": Bin(name, "bin", world, add_volume(world, params), counter), "count": counter}
