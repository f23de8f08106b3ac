"""Station (filling, capping): changes the state of a bottle that stands still in it for a set time.

The station does not hold the bottle: a `stopper` in front of it does, and the plant's logic
opens it on `done` (see scenarios/station.yaml). A bottle counts as standing while its
horizontal speed is below `still`; it must stand for `time` seconds (counted in ticks at
communication points) to be done. A bottle is processed once: it must leave the volume
before the station takes it again. The bottle's state lives in the plant's manifest
(modules/manifest.py), where ID readers, inspectors and sinks read it.

`faults` is the share of bottles the station processes badly, as a filler's valve under-fills
one now and then: such a bottle is done like any other (its stopper opens) but its state stays
unset — not filled, not capped — and `faulty` fires with `done`, logged with its id, so an
inspector downstream (modules/inspector.py) can have it rejected. Whether a bottle is one of
them is drawn from the run's seed, the station's name and the bottle's id, so every run of a
scenario marks the same bottles, in whatever order they come.
"""
from __future__ import annotations

import math
import zlib

import numpy as np

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot
from modules.manifest import cargo
from modules.plant import LOOK
from modules.trigger import add_volume, volume_parameters

OPERATIONS = {"fill": "filled", "cap": "capped"}


class Process(Component):
    SLOTS = (
        Slot.source("started", "void", "a bottle came to rest in the station: processing began"),
        Slot.source("done", "void", "processing finished: the bottle is filled (or capped)"),
        Slot.source("aborted", "void", "the bottle left before it was done; its state is unchanged"),
        Slot.source("object", "string", "id of the bottle processed; active with started, done, aborted"),
        Slot.source("busy", "bool", "a bottle is being processed, every step"),
        Slot.source("faulty", "void", "the bottle done was processed badly (`faults`); with done"),
    )

    STATE = ("body", "since", "finished")

    def __init__(self, obj, name, world, trigger, field: str, ticks: int, still: float, faults: float = 0.0):
        super().__init__(obj, name)
        self.world = world
        self.trigger = trigger
        self.field = field
        self.ticks = ticks
        self.still = still
        self.body: int | None = None      # the bottle being processed
        self.since = 0
        self.finished: set[int] = set()   # processed and still inside
        self.faults = faults
        self.seed = world.seed

    def sense(self, tick):
        world = self.world
        inside = self.world.take_trigger(self.trigger).inside
        self.finished &= set(inside)
        if self.body is not None and self.body not in inside:
            self.emit("aborted")
            self.emit("object", world.labels[self.body])
            self.body = None
        if self.body is None:
            for n in inside:
                vx, vy, _ = world.velocities[n]
                if n not in self.finished and math.hypot(vx, vy) < self.still:
                    self.body, self.since = n, tick
                    self.emit("started")
                    self.emit("object", world.labels[n])
                    break
        elif tick - self.since >= self.ticks:
            entry = cargo(world, self.body)
            if self.faulty(entry.id):
                self.emit("faulty")
            else:
                setattr(entry, self.field, True)
            self.finished.add(self.body)
            self.emit("done")
            self.emit("object", world.labels[self.body])
            self.body = None
        self.emit("busy", self.body is not None)

    def faulty(self, bottle: str) -> bool:
        """Whether this station processes `bottle` badly: a draw of its own per bottle (see above)."""
        if self.faults <= 0.0:
            return False
        rng = np.random.default_rng([self.seed, zlib.crc32(self.obj.encode()), zlib.crc32(bottle.encode())])
        return bool(rng.random() < self.faults)

    def events(self, tick):
        active, index = self.signals.active, self.index
        return [(tick, slot, self.value("object")) for slot in ("started", "done", "faulty", "aborted")
                if active[index[slot]]]


class Station(Module):
    """A filling or capping station: a box volume centred at `position`; `size` along, across and up."""

    CONTRIBUTES = (LOOK,)   # its bottles look filled, capped (modules/plant/look.py)

    PARAMETERS = {
        "type": "object",
        "properties": {
            **volume_parameters([0.04, 0.1, 0.1], "station's working volume"),
            "operation": {"enum": sorted(OPERATIONS), "description": "fill: the bottle gets filled; cap: it gets capped"},
            "time": {"type": "number", "minimum": 0, "default": 1.0, "description": "how long a bottle must stand, s"},
            "still": {"type": "number", "exclusiveMinimum": 0, "default": 0.02,
                      "description": "a bottle slower than this stands, m/s"},
            "faults": {"type": "number", "minimum": 0, "maximum": 1, "default": 0.0,
                       "description": "share of bottles processed badly (left unfilled or uncapped), drawn per "
                                      "bottle from run.seed"},
        },
        "required": ["position", "operation"],
        "additionalProperties": False,
    }
    COMPONENTS = {"process": Process}

    @classmethod
    def build(cls, name, params, world):
        trigger = add_volume(world, params)
        ticks = round(params["time"] * world.rate)
        return {"process": Process(name, "process", world, trigger, OPERATIONS[params["operation"]],
                                   ticks, params["still"], params["faults"])}
