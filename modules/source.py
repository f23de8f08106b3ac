"""Source (storage): puts bottles with ids and destinations out at one spot, on command or at a rate.

The bottles are either listed (`bottles`: ids and destinations) or made by a rule (`count`
bottles, ids `prefix` + number, destinations drawn with `weights` from the scenario's
run.seed and the object's name, so every run draws the same and two sources draw apart).

Every body is created when the plant is built, never in the loop (pybullet is deterministic
only for an identical sequence of calls, and collision shapes are never freed). Bottles not
yet out are parked off stage (hub/physics/parking.py): asleep, without collision and not
read per tick, so a full store costs next to nothing. A release puts the next bottle, upright
and at rest, on the spot — once nothing stands within a bottle's width of it, so it is never
put into another bottle. One release is pending at most: commands while one waits are merged.
With `interval`, the source also releases by itself every `interval` seconds from `start`.

Each bottle is addressable by its id as an object of its own with a bottle's body slots
(`M001.body.position`, `body.orientation`, `body.velocity`, `body.tilt`, `body.present`) in
`record:`, expectations and flows from it; computed only when one of those reads it, and not on
the data plane (every body's pose is in the bodies message, schemas/scene.schema.json). Before
its release and after a sink took it, `present` is false and its pose holds.
"""
from __future__ import annotations

import re
import zlib

import numpy as np

from hub.core.component import Component
from hub.core.errors import SimulationError
from hub.core.module import Module
from hub.core.slots import Slot
from modules.bottle import BottleBody
from modules.manifest import register
from modules.params import POSITION, TRANSPORT, length
from modules.plant import FIGURES, LOOK

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")   # an object name (schemas/scenario.schema.json)


class Member(BottleBody):
    """A released bottle's body (Module.members): computed only for the slots something reads,
    and not on the data plane (all bodies' poses are in the bodies message)."""

    QUIET_UNLESS_NEEDED = True
    PUBLISHED = False


class Store(Component):
    SLOTS = (
        Slot.target("release", "void", "put the next bottle out (it waits while the spot is occupied)"),
        Slot.source("released", "void", "a bottle was put out"),
        Slot.source("object", "string", "id of the bottle put out; active with released"),
        Slot.source("destination", "string", "its destination; active with released"),
        Slot.source("remaining", "int", "bottles still in store, every step"),
        Slot.source("waiting", "bool", "a release waits for the spot to clear, every step"),
    )

    STATE = ("due", "next", "pending", "out", "blocker")

    def __init__(self, obj, name, world, spot, bodies, destinations, clear, every, first):
        super().__init__(obj, name)
        self.world = world
        self.spot = spot
        self._where = np.asarray(spot[:2])
        self.bodies = bodies              # in release order
        self.destinations = destinations
        self.clear = clear                # minimum horizontal distance of any axis from the spot
        self.every, self.due = every, first   # automatic releases, in ticks (None: on command only)
        self.next = 0
        self.pending = False
        self.out: int | None = None       # index released at the last actuation, reported next sense
        self.blocker: int | None = None   # the body that kept the spot at the last look: asked first

    def sense(self, tick):
        if self.out is not None:
            self.emit("released")
            self.emit("object", self.world.labels[self.bodies[self.out]])
            self.emit("destination", self.destinations[self.out])
            self.out = None
        self.emit("remaining", len(self.bodies) - self.next)
        self.emit("waiting", self.pending and self.next < len(self.bodies))

    def actuate(self):
        tick = self.world.tick
        if self.updated("release"):
            self.pending = True
        if self.due is not None and tick >= self.due:
            self.pending = True
            self.due += self.every
        if self.pending and self.next < len(self.bodies) and self.spot_clear():
            self.world.unpark(self.bodies[self.next], self.spot)
            self.out, self.next, self.pending = self.next, self.next + 1, False

    def spot_clear(self) -> bool:
        w = self.world
        positions, half_heights, level = w.positions, w.half_heights, self.spot[2]
        # A release waits for its spot at nearly every point (bottling plant: 483 of 490 looks
        # found it taken), mostly behind the same bottle: that one asked first answers without
        # numpy over every body. Near only with a margin of 1e-9 of the squared distance, far
        # beyond any rounding of numpy's einsum, so the answer is the one the full look gives.
        n = self.blocker
        if n is not None:
            dx = float(positions[n, 0]) - float(self._where[0])
            dy = float(positions[n, 1]) - float(self._where[1])
            half = float(half_heights[n])
            if (dx * dx + dy * dy < self.clear ** 2 * (1.0 - 1e-9)
                    and abs(float(positions[n, 2]) - (level + half)) < 2 * half):
                return False
        d = positions[:, :2] - self._where
        near = np.flatnonzero(np.einsum("ij,ij->i", d, d) < self.clear ** 2).tolist()
        # Only bodies at the spot's level count: a bottle carried high above it is no obstacle.
        # Only a few bodies are near the spot: judged one by one in floats, the same arithmetic
        # as numpy's, without its cost per call.
        for n in near:
            half = float(half_heights[n])
            if abs(float(positions[n, 2]) - (level + half)) < 2 * half:
                self.blocker = n
                return False
        self.blocker = None
        return True


class Source(Module):
    """Bottles appear standing on `position`; listed in `bottles`, or `count` of them by a seeded rule."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "centre of a released bottle's base (on a belt or the store's platform), m"},
            "bottles": {"type": "array", "minItems": 1, "description": "the bottles in release order",
                        "items": {"type": "object", "required": ["id"], "additionalProperties": False,
                                  "properties": {"id": {"type": "string", "minLength": 1},
                                                 "destination": {"type": "string", "default": ""}}},
                        "examples": [[{"id": "P1", "destination": "A"}, {"id": "P2", "destination": "B"}]]},
            "count": {"type": "integer", "minimum": 1, "description": "instead of `bottles`: how many to make"},
            "prefix": {"type": "string", "description": "ids of made bottles: prefix + number (default: the object's name)"},
            "weights": {"type": "object", "additionalProperties": {"type": "number", "minimum": 0},
                        "description": "destination → relative frequency, for made bottles",
                        "examples": [{"A": 2, "B": 1}]},
            "interval": {"type": "number", "exclusiveMinimum": 0, "description": "release by itself every this many s"},
            "start": {"type": "number", "minimum": 0, "default": 0.0, "description": "first release by itself, s"},
            "platform": {"type": "boolean", "default": False,
                         "description": "build a fixed storage platform under the spot (for a robot to pick from)"},
            "radius": length(0.03, "bottle radius, m"),
            "height": length(0.1, "bottle height, m"),
            "mass": length(0.05, "bottle mass, kg"),
            **TRANSPORT,
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"store": Store}
    PLANT = True
    CONTRIBUTES = (FIGURES, LOOK)

    @classmethod
    def check(cls, params):
        problems = []
        if ("bottles" in params) == ("count" in params):
            problems.append(((), "give either `bottles` (a list of ids and destinations) or `count` (made by a rule)"))
        for key in ("prefix", "weights"):
            if key in params and "bottles" in params:
                problems.append(((key,), f"`{key}` makes bottles by the rule: it goes with `count`, not `bottles`"))
        if "weights" in params and not any(w > 0 for w in params["weights"].values()):
            problems.append((("weights",), "at least one destination needs a weight above 0"))
        ids = [b["id"] for b in params.get("bottles", [])]
        duplicates = sorted({i for i in ids if ids.count(i) > 1})
        if duplicates:
            problems.append((("bottles",), f"duplicate ids: {', '.join(duplicates)}"))
        return problems

    @classmethod
    def supply(cls, name: str, params: dict, seed: int) -> int:
        return len(cls.bottles(name, params, seed))

    @classmethod
    def bottles(cls, name: str, params: dict, seed: int) -> list[tuple[str, str]]:
        """(id, destination) of every bottle, in release order."""
        if "bottles" in params:
            return [(b["id"], b.get("destination", "")) for b in params["bottles"]]
        count, prefix = params["count"], params.get("prefix", name)
        width = len(str(count))
        weights = params.get("weights")
        if not weights:
            return [(f"{prefix}{i + 1:0{width}d}", "") for i in range(count)]
        names = sorted(weights)   # the draw must not depend on the order of the YAML mapping
        p = np.array([weights[n] for n in names], float)
        rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
        drawn = rng.choice(len(names), size=count, p=p / p.sum())
        return [(f"{prefix}{i + 1:0{width}d}", names[k]) for i, k in enumerate(drawn.tolist())]

    @classmethod
    def members(cls, name, params):
        """Each bottle, by its id, with the slots of a bottle's body (`B007.body.position`): for
        `record:`, expectations and flows. Their poses are on the bus in the bodies message
        (schemas/scene.schema.json), not as slots. An id that is no object name is not addressable."""
        return {ident: {"body": BottleBody.SLOTS} for ident, _ in cls.bottles(name, params, 0)
                if _NAME.match(ident)}

    @classmethod
    def build(cls, name, params, world):
        spot = tuple(float(v) for v in params["position"])
        r, h = params["radius"], params["height"]
        if params["platform"]:
            world.add_static_box((spot[0], spot[1], spot[2] - 0.01), (2 * r, 2 * r, 0.01))
        bodies, destinations = [], []
        for ident, destination in cls.bottles(name, params, world.seed):
            if ident in world.labels:
                raise SimulationError(f"object {name!r}: bottle id {ident!r} is already used by another bottle")
            body = world.add_bottle(spot, r, h, params["mass"], ident, transport=params["transport"],
                                    lookahead=params["lookahead"])
            world.park(body)
            register(world, body, destination)
            bodies.append(body)
            destinations.append(destination)
        members = {f"{world.labels[b]}.body": Member(world.labels[b], "body", world, b) for b in bodies
                   if _NAME.match(world.labels[b])}
        every = first = None
        if "interval" in params:
            every = max(1, round(params["interval"] * world.rate))
            first = round(params["start"] * world.rate)
        return {"store": Store(name, "store", world, spot, bodies, destinations, 2 * r, every, first), **members}
