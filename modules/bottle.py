"""Bottle: an upright cylinder with friction and restitution 0, as in the paper.

| slot             | type   | dir    | meaning                                         |
|------------------|--------|--------|-------------------------------------------------|
| body.position    | vec3   | source | centre of mass, m, every step                   |
| body.orientation | quat   | source | orientation (x, y, z, w), every step            |
| body.velocity    | vec3   | source | linear velocity, m/s, every step                |
| body.tilt        | real   | source | angle between its axis and the plumb line, deg  |
| tag.id           | string | source | the id an ID reader reads, every step           |

Body slots are computed only when a flow or the recording reads them: a bottle nobody watches
costs its physics and nothing more.
"""
from __future__ import annotations

import math

from hub.component import Component
from hub.module import Module
from hub.slots import Slot

from .params import POSITION, length


class BottleBody(Component):
    SLOTS = (
        Slot.source("position", "vec3", "centre of mass, m"),
        Slot.source("orientation", "quat", "orientation quaternion (x, y, z, w)"),
        Slot.source("velocity", "vec3", "linear velocity, m/s"),
        Slot.source("tilt", "real", "angle between axis and plumb line, degrees"),
    )

    def __init__(self, obj, name, world, body):
        super().__init__(obj, name)
        self.world = world
        self.body = body

    def sense(self, tick):
        w, b, needed = self.world, self.body, self.needed
        if "position" in needed:
            self.emit("position", tuple(w.positions[b].tolist()))
        if "orientation" in needed:
            self.emit("orientation", tuple(w.orientations[b].tolist()))
        if "velocity" in needed:
            self.emit("velocity", tuple(w.velocities[b].tolist()))
        if "tilt" in needed:
            self.emit("tilt", math.degrees(w.tilt(b)))


class Tag(Component):
    SLOTS = (Slot.source("id", "string", "the id an ID reader reads"),)

    def __init__(self, obj, name, ident):
        super().__init__(obj, name)
        self.ident = ident

    def sense(self, tick):
        if self.needed:
            self.emit("id", self.ident)


class Bottle(Module):
    """An upright bottle standing with the centre of its base at `position`."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "centre of the bottle's base, m"},
            "id": {"type": "string", "description": "id read by ID readers; default: the object's name"},
            "radius": length(0.03, "m"),
            "height": length(0.1, "m"),
            "mass": length(0.05, "kg"),
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"body": BottleBody, "tag": Tag}

    @classmethod
    def build(cls, name, params, world):
        ident = params.get("id", name)
        body = world.add_cylinder(params["position"], params["radius"], params["height"], params["mass"], ident)
        return {"body": BottleBody(name, "body", world, body), "tag": Tag(name, "tag", ident)}
