"""Straight conveyor belt: a force-field region over one continuous support surface, with guard rails.

| slot                  | type | dir    | meaning                                                |
|-----------------------|------|--------|--------------------------------------------------------|
| drive.speed           | real | target | target belt speed, m/s (negative runs backwards)       |
| drive.run             | bool | target | true runs the belt, false stops it (speed kept)        |
| drive.running         | bool | source | whether the belt runs, every step                      |
| drive.velocity        | real | source | speed the field drives bottles to now, m/s, every step |
"""
from __future__ import annotations

import math

from hub.component import Component
from hub.module import Module
from hub.slots import Slot

from .params import POSITION, YAW, length

RAIL_THICKNESS = 0.01
SUPPORT_THICKNESS = 0.02


class BeltDrive(Component):
    SLOTS = (
        Slot.target("speed", "real", "target belt speed, m/s"),
        Slot.target("run", "bool", "true runs the belt, false stops it"),
        Slot.source("running", "bool", "whether the belt runs"),
        Slot.source("velocity", "real", "speed the field drives bottles to now, m/s"),
    )

    def __init__(self, obj, name, world, field, speed, running):
        super().__init__(obj, name)
        self.world = world
        self.field = field
        self.speed = speed
        self.running = running

    def sense(self, tick):
        self.emit("running", self.running)
        self.emit("velocity", self.speed if self.running else 0.0)

    def actuate(self):
        if self.updated("speed"):
            self.speed = self.value("speed")
        if self.updated("run"):
            self.running = self.value("run")
        self.world.set_field_speed(self.field, self.speed if self.running else 0.0)


class Conveyor(Module):
    """A straight belt from `position` (start of its centre line, on the belt surface) along `yaw`.

    The belt itself is a box region above the surface in which the paper's force field drives
    each bottle's velocity along the belt towards the belt speed (see hub/physics/fields.py).
    """

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "start of the belt's centre line on its surface, m"},
            "yaw": YAW,
            "length": length(description="belt length, m"),
            "width": length(0.1, "clear width between the guard rails, m"),
            "speed": {"type": "number", "default": 0.5, "description": "belt speed, m/s"},
            "k": {"type": "number", "exclusiveMinimum": 0, "default": 16.0,
                  "description": "force-field rate 1/s: how fast bottles take on the belt speed"},
            "running": {"type": "boolean", "default": True},
            "rail_height": length(0.04, "guard rail height above the surface, m"),
            "field_height": length(0.3, "height of the force-field region above the surface, m"),
        },
        "required": ["position", "length"],
        "additionalProperties": False,
    }
    COMPONENTS = {"drive": BeltDrive}

    @classmethod
    def build(cls, name, params, world):
        x, y, z = params["position"]
        yaw = math.radians(params["yaw"])
        length_, width = params["length"], params["width"]
        d = (math.cos(yaw), math.sin(yaw))
        n = (-d[1], d[0])
        cx, cy = x + d[0] * length_ / 2, y + d[1] * length_ / 2
        half_span = width / 2 + RAIL_THICKNESS
        world.add_static_box((cx, cy, z - SUPPORT_THICKNESS / 2),
                             (length_ / 2, half_span, SUPPORT_THICKNESS / 2), yaw)
        rail_h = params["rail_height"]
        for side in (1, -1):
            offset = side * (width / 2 + RAIL_THICKNESS / 2)
            world.add_static_box((cx + n[0] * offset, cy + n[1] * offset, z + rail_h / 2),
                                 (length_ / 2, RAIL_THICKNESS / 2, rail_h / 2), yaw)
        field_h = params["field_height"]
        field = world.add_force_field((cx, cy, z + field_h / 2), (length_ / 2, width / 2, field_h / 2),
                                      yaw, params["k"], params["speed"] if params["running"] else 0.0)
        return {"drive": BeltDrive(name, "drive", world, field, params["speed"], params["running"])}
