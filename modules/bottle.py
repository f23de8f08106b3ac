"""Bottle: an upright rigid body with friction and restitution 0, at a chosen level of detail.

Body slots are computed only when a flow or the recording reads them: a bottle nobody watches
costs its physics and nothing more. Off stage (taken out by a sink) its pose slots keep the
last values they had on stage and `present` is false: gone, not somewhere below the plant.

Level of detail, per bottle (`model`, `shape`):

| model        | where the belt grips                                  | cost per tick (`make bench`)  |
|--------------|-------------------------------------------------------|-------------------------------|
| `simple`     | centre of mass: no torque, the bottle never rocks     | the reference                 |
| `base_point` | its base point: the force tips it as friction would   | +4–11 % on a belt, +1 % off   |
| `base_body`  | a second body at the base, fixed constraint (paper's) | +47–56 % on a belt, +21–53 % off |

`shape: cylinder` (default) or `hull`: the convex hull of a bottle profile (`profile`, pairs of
height and radius from the base; inertia of the homogeneous cylinder, as in the paper). A
cylinder bottle touches others, gates and rails at its contact ring: `radius` is its widest
ring, at its centre of mass, and its body is 5 % narrower, so a pressed queue pushes through
the centres of mass and stands (hub/physics/world.py; a bottle wider than half its height
stays a plain cylinder).
`tests/bench.py` measures what each costs; `python -m hub report paper` compares the tilt.
"""
from __future__ import annotations

import math

from hub.core.component import Component
from hub.core.module import Module
from hub.core.slots import Slot
from modules.params import POSITION, TRANSPORT, length
from modules.plant import LOOK


class BottleBody(Component):
    """A bottle's body. While it is off stage (a sink took it out, a source still holds it) its
    pose slots keep the last values they had on stage and `present` is false: it is gone, not
    somewhere far below the plant."""

    SLOTS = (
        Slot.source("position", "vec3", "centre of mass, m, every step"),
        Slot.source("orientation", "quat", "orientation (x, y, z, w), every step"),
        Slot.source("velocity", "vec3", "linear velocity, m/s, every step"),
        Slot.source("tilt", "real", "angle between its axis and the plumb line, deg"),
        Slot.source("present", "bool", "on stage (false once a sink took it out)"),
    )

    def __init__(self, obj, name, world, body):
        super().__init__(obj, name)
        self.world = world
        self.body = body

    def sense(self, tick):
        w, b, needed = self.world, self.body, self.needed
        present = not w.is_parked(b)
        if "present" in needed:
            self.emit("present", present)
        if not present:
            return
        if "position" in needed:
            self.emit("position", tuple(w.positions[b].tolist()))
        if "orientation" in needed:
            self.emit("orientation", tuple(w.orientations[b].tolist()))
        if "velocity" in needed:
            self.emit("velocity", tuple(w.velocities[b].tolist()))
        if "tilt" in needed:
            self.emit("tilt", math.degrees(w.tilt(b)))


class Tag(Component):
    SLOTS = (Slot.source("id", "string", "the id an ID reader reads, every step"),)

    def __init__(self, obj, name, ident):
        super().__init__(obj, name)
        self.ident = ident

    def sense(self, tick):
        if self.needed:
            self.emit("id", self.ident)


MODELS = {"simple": "centre", "base_point": "base", "base_body": "base_body"}
HULL_SEGMENTS = 16
# The paper gives no mass for its second body. The share sets how much the base weighs down the
# bottle: the tilt of a 20 g bottle at 1 m/s falls from 4.9° (1 %) to 3.7° (5 %) and 2.6°
# (10 %); as the share goes to 0 the model becomes base_point (5.3°). See the paper report.
BASE_FRACTION = 0.05


def default_profile(radius: float, height: float) -> list[tuple[float, float]]:
    """A plain bottle: straight body to 60 % of its height, shoulder to a neck of 40 % radius at 80 %."""
    neck = 0.4 * radius
    return [(0.0, radius), (0.6 * height, radius), (0.8 * height, neck), (height, neck)]


def hull_points(profile) -> list[tuple[float, float, float]]:
    """The profile turned about the axis: rings of points whose convex hull is the bottle."""
    points = []
    for z, r in profile:
        for i in range(HULL_SEGMENTS):
            a = 2.0 * math.pi * i / HULL_SEGMENTS
            points.append((r * math.cos(a), r * math.sin(a), z))
    return points


class Bottle(Module):
    """An upright bottle standing with the centre of its base at `position`."""

    CONTRIBUTES = (LOOK,)   # its bottles look filled, capped (modules/plant/look.py)

    @classmethod
    def default_hull(cls, radius: float, height: float) -> list[tuple[float, float, float]]:
        """The points of a plain bottle's convex hull (`shape: hull` without a `profile`)."""
        return hull_points(default_profile(radius, height))

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "centre of the bottle's base, m"},
            "id": {"type": "string", "description": "id read by ID readers; default: the object's name"},
            "radius": length(0.03, "m"),
            "height": length(0.1, "m"),
            "mass": length(0.05, "kg"),
            "model": {"enum": list(MODELS), "default": "simple",
                      "description": "where the belt grips: simple (centre of mass), base_point, base_body (the paper's)"},
            **TRANSPORT,
            "base_fraction": {"type": "number", "exclusiveMinimum": 0, "maximum": 0.5,
                              "description": f"model base_body: share of the mass in the second body "
                                             f"(default {BASE_FRACTION:g})"},
            "shape": {"enum": ["cylinder", "hull"], "default": "cylinder",
                      "description": "collision shape: cylinder, or the convex hull of `profile`"},
            "profile": {"type": "array", "minItems": 2,
                        "items": {"type": "array", "items": {"type": "number", "minimum": 0},
                                  "minItems": 2, "maxItems": 2},
                        "description": "[height, radius] pairs from base to top, m (shape: hull); "
                                       "default: a body up to 60 %, a shoulder, a neck of 40 % radius from 80 %"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"body": BottleBody, "tag": Tag}

    @classmethod
    def check(cls, params):
        problems = []
        if "base_fraction" in params and params["model"] != "base_body":
            problems.append((("base_fraction",), "only the base_body model has a second body: "
                                                 "add `model: base_body` or drop base_fraction"))
        profile = params.get("profile")
        if profile is not None:
            if params["shape"] != "hull":
                problems.append((("profile",), "a profile shapes only a hull: add `shape: hull`"))
            heights = [z for z, _ in profile]
            if heights != sorted(heights) or heights[0] != 0 or abs(heights[-1] - params["height"]) > 1e-9:
                problems.append((("profile",), f"heights must rise from 0 to the bottle's height "
                                               f"({params['height']:g} m), got {heights}"))
            if max(r for _, r in profile) > params["radius"] + 1e-9:
                problems.append((("profile",), f"no radius may exceed the bottle's radius ({params['radius']:g} m): "
                                               "sensors and rails assume it"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        ident = params.get("id", name)
        hull = None
        if params["shape"] == "hull":
            hull = hull_points(params.get("profile") or default_profile(params["radius"], params["height"]))
        body = world.add_bottle(params["position"], params["radius"], params["height"], params["mass"], ident,
                                hull=hull, grip_at=MODELS[params["model"]],
                                base_fraction=params.get("base_fraction", BASE_FRACTION),
                                transport=params["transport"], lookahead=params["lookahead"])
        return {"body": BottleBody(name, "body", world, body), "tag": Tag(name, "tag", ident)}
