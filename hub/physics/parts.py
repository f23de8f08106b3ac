"""Switchable parts: fixed bodies of boxes (switch blades, gates) whose collision the plant turns on and off, as the paper does."""
from __future__ import annotations

import numpy as np

from hub.physics.changes import PartTurned


class SwitchableParts:
    """The world's switchable parts, numbered in the order they were made."""

    STATE = ("solid",)   # hub/core/state.py; the engine keeps each body's filter (Engine.filters)

    def __init__(self, engine, changes):
        self.engine = engine
        self.changes = changes           # where a part's turn is announced (changes.py)
        self._bodies: list[int] = []
        self._boxes: list[tuple] = []   # each part's bounding box (lo, hi), for waking what rests in it
        self._thinnest: list[tuple] = []   # each part's thinnest box: (its centre, half its thickness), m
        self.solid: list[bool] = []     # each part's collision now (a view draws it so)
        self.boxes: list[tuple] = []    # every box of every part: (centre, half extents, yaw), world frame

    def add(self, centers, half_extents, yaws, solid: bool) -> int:
        """One fixed body of boxes placed in the world frame; returns its number for `set_solid`."""
        body = self.engine.boxes_body(centers, half_extents, yaws)
        self.engine.frictionless(body)
        self._bodies.append(body)
        self.boxes.extend((tuple(c), tuple(h), float(y)) for c, h, y in zip(centers, half_extents, yaws))
        self._boxes.append(self.engine.aabb(body))
        halves = np.asarray(half_extents, float).reshape(-1, 3)[:, :2].min(1)
        thin = int(np.argmin(halves))
        self._thinnest.append((tuple(np.asarray(centers, float).reshape(-1, 3)[thin]), float(halves[thin])))
        self.solid.append(solid)
        self.set_solid(len(self._bodies) - 1, solid)
        return len(self._bodies) - 1

    def jumpable(self, step: float, radius: float) -> list[str]:
        """The parts a bottle of `radius` moving `step` m per tick (the fastest belt's speed × dt)
        may pass through: once its axis gets past a box's middle within one tick, the engine
        resolves the overlap by pushing it out on the far side (2 m/s into a 5 mm gate at 60 Hz,
        33 mm a tick, is just held; 2.5 m/s passes: tests/hard/test_tunnelling.py). Reported at
        load, not fixed."""
        out = []
        for part, (centre, half) in enumerate(self._thinnest):
            if step > radius + half:
                c = ", ".join(f"{x:.3f}" for x in centre)
                out.append(f"gate or blade {part} at ({c}) m is {2000 * half:.1f} mm thick: a bottle of "
                           f"{2000 * radius:.0f} mm moving {1000 * step:.1f} mm per tick (the fastest belt) may "
                           "pass through it between two ticks; make it thicker or the physics rate higher")
        return out

    def bodies(self) -> set[int]:
        """The parts' fixed bodies."""
        return set(self._bodies)

    def set_solid(self, part: int, solid: bool) -> None:
        """Collision on or off through the body's filter group and mask: one call whatever the
        number of bottles (setCollisionFilterPair needs one per bottle), 0.8 µs, in effect from
        the next tick in both directions (measured). On: pybullet's own values for a fixed body.
        A fixed body wakes no sleeping one: the turn is announced (changes.PartTurned), and what
        rests in its box wakes then."""
        lo, hi = (np.asarray(v, float) for v in self._boxes[part])
        self.changes.announce(PartTurned(part, solid, (lo + hi) / 2.0, (hi - lo) / 2.0))
        self.solid[part] = solid
        group, mask = (2, -3) if solid else (0, 0)
        self.engine.set_filter(self._bodies[part], -1, group, mask)
