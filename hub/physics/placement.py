"""Placement at load: a body placed inside static geometry or another body is reported before the first tick."""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr

with quiet_stderr():
    import pybullet

# How deep one shape may reach into another before it is an overlap: bottles stand on floors and
# side by side in queues at distance 0, which the engine's narrow phase gives to ±1e-6 m.
TOLERANCE = 1e-3   # m


def overlaps(engine, bodies) -> list[str]:
    """One sentence per overlap of a body in play with a fixed box or with another body in play.

    Bullet ejects an overlapping body with whatever speed recovers the penetration (a bottle placed
    inside a rail leaves it at metres per second), so the scene is wrong before it runs. Candidates
    come from bounding boxes in numpy; only those are asked of the engine, by getClosestPoints,
    a query that changes nothing in the world (the recordings stay byte-identical)."""
    rows = [n for n in range(len(bodies)) if n not in bodies.parked]
    if not rows:
        return []
    rows = np.array(rows)
    centre = bodies.positions[rows]
    reach = np.stack([bodies.radii[rows], bodies.radii[rows], bodies.half_heights[rows]], 1)
    lo, hi = centre - reach, centre + reach
    found = []
    s_lo, s_hi = engine.static_bounds()
    if len(s_lo):
        near = ((lo[:, None] < s_hi[None] - TOLERANCE) & (hi[:, None] > s_lo[None] + TOLERANCE)).all(2)
        asked = set()
        for i, k in zip(*np.nonzero(near)):
            row, static = int(rows[i]), engine.static[k][0]
            if (row, static) in asked:   # one body of many boxes (a rail along an arc): asked once
                continue
            asked.add((row, static))
            depth, where = _depth(engine, bodies.ids[row], static)
            if depth > TOLERANCE:
                found.append(f"{bodies.labels[row]!r} is placed {depth * 1000:.1f} mm into static geometry "
                             f"(the box centred at ({_xyz(_nearest(engine, static, where))}) m), at ({_xyz(centre[i])}) m")
    near = ((lo[:, None] < hi[None] - TOLERANCE) & (hi[:, None] > lo[None] + TOLERANCE)).all(2)
    for i, j in zip(*np.nonzero(np.triu(near, 1))):
        a, b = int(rows[i]), int(rows[j])
        depth, _ = _depth(engine, bodies.ids[a], bodies.ids[b])
        if depth > TOLERANCE:
            found.append(f"{bodies.labels[a]!r} at ({_xyz(centre[i])}) m and {bodies.labels[b]!r} at "
                         f"({_xyz(centre[j])}) m overlap by {depth * 1000:.1f} mm")
    return found


def _depth(engine, a: int, b: int) -> tuple[float, tuple]:
    """How deep a reaches into b (0: apart or touching), and where on b."""
    points = engine.call(pybullet.getClosestPoints, a, b, 0.0)
    if not points:
        return 0.0, ()
    deepest = min(points, key=lambda p: p[8])
    return max(0.0, -deepest[8]), deepest[6]


def _nearest(engine, static: int, where) -> tuple:
    """The centre of the box of the fixed body `static` nearest to a point on it (a body may be many boxes)."""
    boxes = [c for body, c, _, _ in engine.static if body == static]
    if not where:
        return boxes[0]
    return min(boxes, key=lambda c: sum((x - y) ** 2 for x, y in zip(c, where)))


def _xyz(p) -> str:
    return ", ".join(f"{float(x):.3f}" for x in p)
