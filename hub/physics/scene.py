"""What the world was built of, as a view draws it: every static box and floor, belt centre line,
switchable and moving part, trigger volume, arm and body, each with the object that made it — and
the state of the moving ones at a tick, from the arrays the world holds already.

The world records an item whenever a module builds one (PhysicsWorld's `add_*` calls), under
the name in `owner`, which the plant sets before it builds each object (hub/run/plant.py). So a
view in another process draws exactly the geometry the engine collides with, without reading
the scenario again or deriving any pose the modules computed. Recording costs nothing per tick;
`state` is read only when a view asks (hub/view/broadcast.py).
"""
from __future__ import annotations

import math

import numpy as np

from hub.physics.frames import Arc, Straight


def _box(center, half_extents, yaw: float) -> dict:
    return {"center": [float(v) for v in center], "half_extents": [float(v) for v in half_extents],
            "yaw": float(yaw)}


def _line(line: Straight | Arc) -> dict:
    if isinstance(line, Arc):
        cx, cy = line.centre
        return {"type": "arc", "center": [cx, cy], "radius": line.radius, "start": line.start_angle,
                "sweep": line.turn * line.sweep}
    end = line.end
    return {"type": "straight", "start": [line.start.x, line.start.y], "end": [end.x, end.y]}


class SceneLog:
    """The items of one world in the order they were built (schemas/scene.schema.json `items`),
    and which object owns each body row."""

    def __init__(self):
        self.owner = ""                   # the object being built now (hub/run/plant.py sets it)
        self.items: list[dict] = []
        self.body_owners: dict[int, str] = {}

    def _add(self, kind: str, **fields) -> None:
        self.items.append({"kind": kind, "object": self.owner, **fields})

    def box(self, center, half_extents, yaw: float) -> None:
        self._add("box", **_box(center, half_extents, yaw))

    def support(self, z: float, rect, thickness: float) -> None:
        self._add("support", z=float(z), rect=[float(v) for v in rect], thickness=float(thickness))

    def belt(self, field: int, line: Straight | Arc, half_width: float, z: float) -> None:
        self._add("belt", field=field, line=_line(line), half_width=float(half_width), z=float(z))

    def field_box(self, field: int, center, half_extents, yaw: float) -> None:
        """A force field given as a box (the paper's belts): drawn as a belt along its x axis."""
        c, s, hx = math.cos(yaw), math.sin(yaw), float(half_extents[0])
        line = {"type": "straight", "start": [center[0] - c * hx, center[1] - s * hx],
                "end": [center[0] + c * hx, center[1] + s * hx]}
        self._add("belt", field=field, line=line, half_width=float(half_extents[1]),
                  z=float(center[2] - half_extents[2]))

    def part(self, part: int, centers, half_extents, yaws) -> None:
        self._add("part", part=part, boxes=[_box(c, h, y) for c, h, y in zip(centers, half_extents, yaws)])

    def moving(self, index: int, centers, half_extents, yaws, axis) -> None:
        a = np.asarray(axis, float)
        a = a / float(np.linalg.norm(a))
        self._add("moving", moving=index, axis=a.tolist(),
                  boxes=[_box(c, h, y) for c, h, y in zip(centers, half_extents, yaws)])

    def trigger(self, trigger: int, center, half_extents, yaw: float) -> None:
        self._add("trigger", trigger=trigger, **_box(center, half_extents, yaw))

    def arm(self, index: int, urdf: str, base, yaw: float, joints: list[str], tool_length: float) -> None:
        self._add("arm", arm=index, urdf=urdf, base=[float(v) for v in base], yaw=float(yaw), joints=joints,
                  tool_length=float(tool_length))

    def body(self, row: int) -> None:
        self.body_owners[row] = self.owner


class SceneState:
    """The moving part of the scene at one tick, as arrays (float32 and uint8, little-endian when
    sent): the bodies in play and their poses, the parts' solidity, the moving parts' offsets,
    the triggers' occupancy and the arms' joint angles."""

    __slots__ = ("tick", "rows", "poses", "parts", "moving", "triggers", "arms")

    def __init__(self, tick, rows, poses, parts, moving, triggers, arms):
        self.tick, self.rows, self.poses = tick, rows, poses
        self.parts, self.moving, self.triggers, self.arms = parts, moving, triggers, arms


def scene_state(world) -> SceneState:
    """The state of `world` now, from what it read at its last tick (no engine call)."""
    b = world.bodies
    rows = b.in_play_rows()
    poses = np.empty((len(rows), 7), np.float32)
    poses[:, :3] = b.positions[rows]
    poses[:, 3:] = b.orientations[rows]
    if b.placed:   # put into play at this point, read at the next tick: upright where they were put
        where = {row: i for i, row in enumerate(rows.tolist())}
        for row, centre in b.placed.items():
            if row in where:
                poses[where[row]] = (*centre, 0.0, 0.0, 0.0, 1.0)
    parts = np.array(world.parts.solid, np.uint8)
    moving = np.array([p.offset for p in world.moving.parts], np.float32)
    triggers = world.triggers.occupied().astype(np.uint8)
    arms = (np.array([arm.q for arm in world.robots.arms], np.float32) if world.robots.arms
            else np.zeros((0, 7), np.float32))
    return SceneState(world.tick, rows.astype(np.uint16), poses, parts, moving, triggers, arms)
