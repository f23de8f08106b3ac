"""The engine's own word on free transport, for tests (PhysicsWorld.check_free): at every tick,
whether a free bottle, at its pose, touches anything but the floor.

Free bottles' poses in the engine are stale (transport.py): each is asked about as a probe
cylinder of its size at the pose the hub moved it to. What this finds is what the rules of
transport_kernels.py must never allow, so a test that sets `check_free` fails at the first tick
they let a bottle go wrong.
"""
from __future__ import annotations

import numpy as np

from hub.physics._quiet import quiet_stderr
from hub.physics.rest import boxes
from hub.physics.transport_kernels import SLIDE_INTO

with quiet_stderr():
    import pybullet

SLIDE_DEPTH = 1e-6    # m: most `check` lets a sliding bottle go deeper into the face over a run (SLIDE a look)


def engine_check(transport, tick: int, floors: set[int], fixed: set[int] = frozenset(), held=()) -> None:
    """Every free bottle at its pose, asked of the engine: a cylinder of its full radius there
    touches no body but a floor or a bottle an arm holds (`held`, rows: out of the collision
    world while held, and looked at whole when let go of) — or a fixed body (`fixed`: rails,
    gates) it slides along (`_slides`): touching it when it went free, no deeper than
    SLIDE_INTO then, and no deeper into it since than SLIDE_DEPTH. Free bottles' engine poses
    are stale: they are compared with each other here, as upright cylinders; two may touch
    only as a train does — they touched when they went free, at one velocity, and are no
    deeper into each other than then."""
    b, client = transport.bodies, transport.engine.client
    index = transport.rows
    rows = index.tolist()
    skip = floors | {b.ids[n] for n in rows} | {b.ids[n] for n in held}
    trains, slides = {}, {}
    p, r, h = b.positions[index], b.radii[index], b.half_heights[index]
    halves = boxes(b.orientations[index], r, h)
    # Every pair (n, m > n) of upright cylinders that overlap, found at once; looked at in turn below.
    apart = p[None, :, :] - p[:, None, :]
    depths = r[None, :] + r[:, None] - np.hypot(apart[:, :, 0], apart[:, :, 1])
    overlap = (index[None, :] > index[:, None]) & (depths > 0.0) & \
        (np.abs(apart[:, :, 2]) < h[None, :] + h[:, None])
    partners = [[] for _ in rows]
    for i, j in zip(*np.nonzero(overlap)):
        partners[i].append(j)
    for i, n in enumerate(rows):
        at, orientation = b.positions[n].tolist(), b.orientations[n].tolist()
        lo, hi = (b.positions[n] - halves[i]).tolist(), (b.positions[n] + halves[i]).tolist()
        for other, _ in pybullet.getOverlappingObjects(lo, hi, physicsClientId=client) or ():
            if other in skip:
                continue
            touch = pybullet.getClosestPoints(-1, other, 0.0, collisionShapeA=_probe(transport, n),
                                              collisionShapePositionA=at, collisionShapeOrientationA=orientation,
                                              physicsClientId=client)
            if not touch:
                continue
            depth = -min(point[8] for point in touch)
            was = transport._slides_seen.get((n, other))
            first = SLIDE_INTO if was is None else was      # as deep as sliding allows, then no deeper
            if other not in fixed or (was is None and n in transport._checked) or depth > first + SLIDE_DEPTH:
                raise RuntimeError(f"tick {tick}: {b.labels[n]} is in free transport but touches body {other} "
                                   f"at {tuple(round(float(c), 4) for c in touch[0][5])}")
            slides[(n, other)] = depth if was is None else was
        for j in partners[i]:
            m, depth = rows[j], float(depths[i, j])
            # Only a train's: at one velocity, bit for bit, touching since both went free, no deeper.
            was = transport._trains_seen.get((n, m))
            one_velocity = (b.velocities[m, :2] == b.velocities[n, :2]).all()
            new = was is None and {n, m} <= transport._checked      # free before, and not touching then
            if not one_velocity or new or depth > (depth if was is None else was) + 1e-9:
                raise RuntimeError(f"tick {tick}: free bottles {b.labels[n]} and {b.labels[m]} touch")
            trains[(n, m)] = depth if was is None else was
    transport._trains_seen, transport._slides_seen, transport._checked = trains, slides, set(rows)


def _probe(transport, n: int) -> int:
    """A collision shape standing for bottle `n` in `check` (made once, outside the world)."""
    shape = transport._probes.get(n)
    if shape is None:
        b = transport.bodies
        shape = transport._probes[n] = transport.engine.call(
            pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=float(b.radii[n]),
            height=2.0 * float(b.half_heights[n]))
    return shape
