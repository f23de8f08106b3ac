"""Sink: takes every bottle that enters its volume out of the plant, counts them by destination and names the misrouted.

A bottle is taken out at the first communication point after it entered (it is parked off
stage, see hub/physics/parking.py, and costs nothing from then on); all bottles that
entered since the last point are taken, in the order they entered. Destinations come from
the plant's manifest (modules/manifest.py): a source's bottles carry theirs, a `bottle`
object has none and counts as `other`.

`accepts` says which destinations the sink's lane is for: a bottle whose destination is not
among them (a bottle without a destination included) is misrouted — counted on
`count.misrouted`, fired on `bin.misrouted` and logged as `bin.misrouted` with its id and
destination. A sink without `accepts` takes every bottle and judges none (the run summary
then says misroutes were not judged). `destinations` only chooses the counting slots.

A sink with `rejects: true` ends a reject lane (modules/pusher.py): the bottles it takes were
rejected by the line, and the run summary counts them as rejects, on a line of their own, not
as delivered; it judges no destination (a reject is never misrouted), so it takes no `accepts`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot, SlotFamily
from modules.manifest import cargo
from modules.plant import FIGURES, LOOK, ORDERS
from modules.trigger import add_volume, volume_parameters

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_RESERVED = ("total", "other", "misrouted")


@dataclass(frozen=True)
class Delivery:
    """One bottle taken out: at which communication point, which bottle, and whether its lane was wrong."""

    tick: int
    body: int            # the world's body number
    bottle: str          # its id
    destination: str     # "" when it has none
    misrouted: bool      # the sink states `accepts` and the destination is not among them


class Bin(Component):
    SLOTS = (
        Slot.source("taken", "void", "a bottle was taken out in this step"),
        Slot.source("object", "string", "id of the bottle taken last; active with taken"),
        Slot.source("destination", "string", "its destination; active with taken"),
        Slot.source("misrouted", "void", "a bottle for another lane was taken out in this step"),
    )
    EVENTS_WHEN = ("taken",)   # its rows are the bottles taken at this point

    STATE = ("taken", "deliveries")

    def __init__(self, obj, name, world, trigger, counter, accepts: tuple[str, ...] | None, rejects: bool = False):
        super().__init__(obj, name)
        self.world = world
        self.trigger = trigger
        self.counter = counter
        self.accepts = accepts            # None: the sink judges no destination
        self.rejects = rejects            # it ends a reject lane: what it takes is rejected, not delivered
        self.taken: list[Delivery] = []   # taken at this point, parked at actuation
        self.deliveries: list[Delivery] = []   # every bottle taken so far, in order (the run summary reads it)

    def sense(self, tick):
        latch = self.world.take_trigger(self.trigger)
        world, accepts = self.world, self.accepts
        self.taken = []
        for _, n in latch.entered:
            if world.is_parked(n):
                continue
            entry = cargo(world, n)
            wrong = accepts is not None and entry.destination not in accepts
            self.taken.append(Delivery(tick, n, entry.id, entry.destination, wrong))
            self.counter.add(entry.destination, wrong)
        self.deliveries.extend(self.taken)
        if self.taken:
            last = self.taken[-1]
            self.emit("taken")
            self.emit("object", last.bottle)
            self.emit("destination", last.destination)
            if any(d.misrouted for d in self.taken):
                self.emit("misrouted")

    def actuate(self):
        for d in self.taken:
            self.world.park(d.body)
        self.taken = []

    def events(self, tick):
        if not self.taken:
            return ()
        return ([(tick, "taken", d.bottle) for d in self.taken]
                + [(tick, "misrouted", f"{d.bottle} (for {d.destination or 'no destination'})")
                   for d in self.taken if d.misrouted])


class Count(Component):
    """Slots `total`, one per listed destination, `other` and `misrouted`; set per instance."""

    STATE = ("counts",)

    def __init__(self, obj, name, destinations):
        super().__init__(obj, name)
        self.SLOTS = Sink.count_slots(destinations)
        self.counts = {slot.name: 0 for slot in self.SLOTS}

    def add(self, destination: str, misrouted: bool = False) -> None:
        self.counts["total"] += 1
        key = destination if destination in self.counts and destination not in _RESERVED else "other"
        self.counts[key] += 1
        self.counts["misrouted"] += misrouted

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        self._slots = [index[name] for name in self.counts]   # the counts' slot numbers, in their order

    def sense(self, tick):
        # Every count at every point (7 sinks of 9 counts in the bottling plant): one loop, not 63 emits.
        values, active = self.signals.values, self.signals.active
        for i, value in zip(self._slots, self.counts.values()):
            values[i] = value
            active[i] = True


class Sink(Module):
    """A box volume centred at `position` that takes bottles out; `size` along, across and up."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            **volume_parameters([0.05, 0.1, 0.1], "volume"),
            "destinations": {"type": "array", "items": {"type": "string"}, "uniqueItems": True, "default": [],
                             "description": "destinations counted on their own slots count.NAME"},
            "accepts": {"type": "array", "items": {"type": "string", "minLength": 1}, "uniqueItems": True,
                        "minItems": 1,
                        "description": "destinations this sink's lane is for; a bottle for any other is misrouted "
                                       "(default: judge none)"},
            "rejects": {"type": "boolean", "default": False,
                        "description": "the sink ends a reject lane: the bottles it takes count as rejected, "
                                       "not delivered"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"bin": Bin, "count": Count}
    SLOT_FAMILIES = {"count": (SlotFamily.source("DEST", "int", "bottles with destination DEST taken so far (one "
                                                                "per name in `destinations`)"),)}
    PLANT = True
    TAKES_OUT = True
    CONTRIBUTES = (FIGURES, ORDERS, LOOK)

    @staticmethod
    def count_slots(destinations) -> tuple[Slot, ...]:
        return (Slot.source("total", "int", "bottles taken so far, every step"),
                *(Slot.source(d, "int", f"bottles with destination {d} taken so far") for d in destinations),
                Slot.source("other", "int", "bottles with any other destination, every step"),
                Slot.source("misrouted", "int", "bottles taken whose destination is not in `accepts`, every step"))

    @classmethod
    def slots(cls, params):
        return {"bin": Bin.SLOTS, "count": cls.count_slots(params.get("destinations", []))}

    @classmethod
    def check(cls, params):
        problems = []
        if params["rejects"] and "accepts" in params:
            problems.append((("accepts",), "a reject sink (`rejects: true`) takes whatever the line rejected, "
                                           "whatever its destination: it takes no `accepts`"))
        for i, d in enumerate(params["destinations"]):
            if not _NAME.match(d):
                problems.append((("destinations", i), f"{d!r} cannot name a slot: use letters, digits and _ "
                                                       "(not starting with a digit)"))
            elif d in _RESERVED:
                problems.append((("destinations", i), f"{d!r} is taken by the slot count.{d}"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        counter = Count(name, "count", params["destinations"])
        accepts = tuple(params["accepts"]) if "accepts" in params else None
        return {"bin": Bin(name, "bin", world, add_volume(world, params), counter, accepts, params["rejects"]),
                "count": counter}
