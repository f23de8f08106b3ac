"""Plain numpy statements of what the physics tick's compiled kernels compute (tests/physics/test_kernels.py).

Written from the rules in the kernels' docstrings, not from their loops: no sweep, no first box
around all boxes, no list of nearby boxes, no early exit — every pair, every box, whole arrays. Where a
kernel's number comes from the same operations in the same order, so does the reference's, and the
test asks for the same bits; where the order differs (a rotation written as a matrix, a relaxation
written as v_belt + (v − v_belt)·e^(−k·dt)), the test says by how much they may differ and why.
"""
from __future__ import annotations

import math

import numpy as np

from hub.physics import fields as F
from hub.physics.rest import BREAKING, SHAPE_MARGIN, boxes
from hub.physics.transport_kernels import FALL, FIXED_MARGIN, LIST, SLIDE, SLIDE_INTO, SPIN, STILL, TILT


# --- fields ---------------------------------------------------------------------------------
def field_of(fields, points) -> np.ndarray:
    """The field each point lies in (ForceFields' rule: inside the band, half-open along, between
    its heights; the nearest centre line wins, the first on a tie), from CentreLines.local (numpy)."""
    points = np.atleast_2d(np.asarray(points, float))
    if len(fields) == 0:
        return np.full(len(points), -1)
    along, across = fields.lines.local(points)
    distance = np.abs(across)
    inside = ((along >= 0.0) & (along < fields.lines.length[:, None]) & (distance <= fields.half_widths[:, None])
              & (points[:, 2] >= fields.z_lo[:, None]) & (points[:, 2] <= fields.z_hi[:, None]))
    distance = np.where(inside, distance, np.inf)
    best = np.argmin(distance, axis=0)          # the first of the nearest
    return np.where(inside.any(axis=0), best, -1)


def law(fields, k, p, v, mass, dt) -> np.ndarray:
    """The velocity change of one tick on field `k` (ForceFields' docstring): the relative velocity
    to the surface decays by e^(−rate·dt) (1 − rate·dt explicit) — along the belt only for `along`;
    on an arc in the surface's frame, turned by ω·dt; cut to limit·dt."""
    rate = fields.rates[k] if fields.per_mass[k] else fields.rates[k] / mass
    keep = 1.0 - rate * dt if fields.explicit else math.exp(-rate * dt)
    lines, speed = fields.lines, fields.speeds[k]
    p, v = np.asarray(p[:2], float), np.asarray(v[:2], float)
    if lines.is_arc[k]:
        r = p - lines.origin[k, :2]
        tangent = lines.turn[k] * np.array([-r[1], r[0]]) / max(np.hypot(*r), 1e-12)
    else:
        tangent = np.array([lines.cos[k], lines.sin[k]])
    if not fields.surface[k]:
        along = tangent @ v
        new = v + tangent * (speed + (along - speed) * keep - along)
    elif not lines.is_arc[k]:
        belt = speed * tangent
        new = belt + (v - belt) * keep
    else:
        angle = lines.turn[k] * speed / lines.radius[k] * dt
        turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        w = (turn - np.eye(2)) @ r / dt
        new = w + turn @ (turn @ v - w) * keep
    change = new - v
    size = np.hypot(*change)
    if fields.limits[k] < np.inf and size > fields.limits[k] * dt:
        change = change * (fields.limits[k] * dt / size)
    return change


def spin_torque(fields, k, spin, mass, radius, dt) -> float:
    """The torque taking a spin about the vertical to zero at the field's rate, capped at (2/3)·μ·m·g·r."""
    if not fields.surface[k] or abs(spin) <= F.SPIN_AT_REST:
        return 0.0
    rate = fields.rates[k] if fields.per_mass[k] else fields.rates[k] / mass
    keep = 1.0 - rate * dt if fields.explicit else math.exp(-rate * dt)
    inertia = mass * radius * radius / 2.0
    most = (2.0 / 3.0) * fields.limits[k] * mass * radius
    return float(np.clip(-spin * (1.0 - keep) * inertia / dt, -most, most))


# --- triggers and the watch ----------------------------------------------------------------------
def inside(positions, radii, half_heights, centres, extents, cos, sin) -> np.ndarray:
    """(boxes, bodies): an upright cylinder overlaps a yawed box when, in the box's frame, its axis
    is within its radius of the box's rectangle and the heights overlap."""
    d = positions[None, :, :2] - centres[:, None, :2]
    c, s = cos[:, None], sin[:, None]
    gx = np.maximum(np.abs(c * d[..., 0] + s * d[..., 1]) - extents[:, None, 0], 0.0)
    gy = np.maximum(np.abs(c * d[..., 1] - s * d[..., 0]) - extents[:, None, 1], 0.0)
    return ((gx * gx + gy * gy <= radii[None, :] * radii[None, :])
            & (np.abs(positions[None, :, 2] - centres[:, None, 2]) <= extents[:, None, 2] + half_heights[None, :]))


# --- rest ------------------------------------------------------------------------------------
def turning(r, h, w) -> float:
    return math.sqrt((w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * (2.0 * r * r + h * h))


def bound(r, h, v, w, horizon, margin) -> float:
    return math.sqrt(2.0 * r * r + h * h) + margin + (math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                                                      + turning(r, h, w)) * horizon


def candidates(rows, field, speeds, gripped, velocities, spins, allowed, still, every, ticks, held_ticks, retry,
               speed2, spin2):
    """Rest.candidates' rule over whole arrays: (due rows or none, the still counts after)."""
    still = still.copy()
    v2 = (velocities[rows] ** 2).sum(axis=1)
    w2 = (spins[rows] ** 2).sum(axis=1)
    quiet = ~gripped[rows] & allowed[rows] & (v2 < speed2) & (w2 < spin2)
    still[rows] = np.where(quiet, still[rows] + every, 0)
    undriven = (field < 0) | (speeds[np.maximum(field, 0)] == 0.0)
    need = np.where(undriven, ticks, held_ticks)
    due = still[rows] >= need
    fresh = (due & ((still[rows] - need) % retry < every)).any()
    return (rows[due] if fresh else rows[:0]), still


def reaches(rows, positions, velocities, spins, radii, half_heights, dt, margin) -> np.ndarray:
    return np.array([bound(radii[n], half_heights[n], velocities[n], spins[n], dt, margin) for n in rows])


def within(rows, positions, velocities, spins, radii, half_heights, dt, centres, extents) -> np.ndarray:
    """rest._within: whether each row's bound comes within some box, on every axis (every box)."""
    if len(centres) == 0:
        return np.zeros(len(rows), bool)
    reach = reaches(rows, positions, velocities, spins, radii, half_heights, dt, SHAPE_MARGIN + BREAKING)
    gap = np.abs(positions[rows][:, None, :] - centres[None, :, :]) - extents[None, :, :]
    return (gap < reach[:, None, None]).all(axis=2).any(axis=1)


def seeds(rows, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents):
    """rest._seeds: the resting boxes the rows' boxes (rest.boxes, headed one tick) overlap."""
    rows = np.asarray(rows, int)
    if len(rows) == 0:
        return np.zeros(len(centres), bool)
    mine = boxes(orientations[rows], radii[rows], half_heights[rows], velocities[rows], spins[rows], dt)
    apart = np.abs(positions[rows][:, None, :] - centres[None, :, :])
    return (apart < mine[:, None, :] + extents[None, :, :]).all(axis=2).any(axis=0)


def closure(start, joined) -> np.ndarray:
    """`start` (a mask) grown through the symmetric relation `joined` until it holds every member joined to one."""
    out = start.copy()
    while True:
        grown = out | joined[out].any(axis=0)
        if (grown == out).all():
            return out
        out = grown


def woken(awake, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents):
    near = awake[within(awake, positions, velocities, spins, radii, half_heights, dt, centres, extents)]
    first = seeds(near, positions, orientations, velocities, spins, radii, half_heights, dt, centres, extents)
    joined = (np.abs(centres[:, None, :] - centres[None, :, :]) - extents[:, None, :] - extents[None, :, :] < 0.0)
    return closure(first, joined.all(axis=2))


# --- free transport --------------------------------------------------------------------------
def box_distance(x, y, hx, hy) -> float:
    return float(np.hypot(max(abs(x) - hx, 0.0), max(abs(y) - hy, 0.0)))


def segment_box_distance(a, d, hx, hy) -> float:
    """The distance from the segment a + t·d (t in [0, 1]) to the rectangle |x| ≤ hx, |y| ≤ hy:
    0 where the segment meets it (clipped against both slabs), else the least of its ends'
    distances to the rectangle and the rectangle's corners' to the segment (two disjoint convex
    sets are nearest at a vertex of one of them)."""
    lo, hi = 0.0, 1.0
    for p, q, h in ((a[0], d[0], hx), (a[1], d[1], hy)):
        if q == 0.0:
            if abs(p) > h:
                lo, hi = 1.0, 0.0
        else:
            t0, t1 = sorted(((-h - p) / q, (h - p) / q))
            lo, hi = max(lo, t0), min(hi, t1)
    if lo <= hi:
        return 0.0
    gaps = [box_distance(a[0], a[1], hx, hy), box_distance(a[0] + d[0], a[1] + d[1], hx, hy)]
    length2 = max(d[0] * d[0] + d[1] * d[1], 1e-300)
    for corner in ((hx, hy), (hx, -hy), (-hx, hy), (-hx, -hy)):
        k = np.subtract(corner, a)
        t = min(max((k @ d) / length2, 0.0), 1.0)
        gaps.append(float(np.hypot(*(k - t * np.asarray(d)))))
    return min(gaps)


def slides(a, d, s, hx, hy, r) -> bool:
    """Whether a bottle of radius r at `a` in a box's frame, its way the parallelogram of d and s,
    stays beside one face of the box all the way: every corner of its way within the face's span,
    its centre no further into the box than r − SLIDE_INTO from the face, and coming no nearer the
    face (along its normal, towards the box) than SLIDE."""
    half = (hx, hy)
    corners = [np.asarray(a) + x * np.asarray(d) + y * np.asarray(s) for x in (0, 1) for y in (0, 1)]
    for j in range(2):
        i = 1 - j
        if abs(a[j]) - half[j] < r - SLIDE_INTO:
            continue
        if max(abs(c[i]) for c in corners) > half[i]:
            continue
        side = 1.0 if a[j] > 0.0 else -1.0
        if min(0.0, side * d[j]) + min(0.0, side * s[j]) >= -SLIDE:
            return True
    return False


def listed(n, positions, radii, half_heights, c, h, cos, sin, near_size):
    """_relist: the fixed boxes body n's upright footprint is within LIST of (first `near_size`) and their count."""
    found = []
    for k in range(len(c)):
        if abs(positions[n, 2] - c[k, 2]) > h[k, 2] + half_heights[n] + FIXED_MARGIN + LIST:
            continue
        dx, dy = positions[n, 0] - c[k, 0], positions[n, 1] - c[k, 1]
        if box_distance(cos[k] * dx + sin[k] * dy, cos[k] * dy - sin[k] * dx, h[k, 0], h[k, 1]) - radii[n] < LIST:
            found.append(k)
    return found[:near_size], len(found)


def steady(n, free, orientations, spins) -> bool:
    x, y = orientations[n, 0], orientations[n, 1]
    return bool(free[n] or (1.0 - 2.0 * (x * x + y * y) > math.cos(TILT) and math.sqrt((spins[n] ** 2).sum()) < SPIN))


def on_one_belt(fields, n, m, dt, positions, velocities, pulls) -> int:
    """transport._belt: the straight mass-scaled belt body n stands on and whose band holds the
    four corners of its way over m ticks (velocity and pull), or −1."""
    p = positions[n]
    now = field_of(fields, p)[0]
    if now < 0 or not fields.straight_law[now]:
        return -1
    grow = m * (m + 1.0) / 2.0 * dt
    w = velocities[n, :2] * (m * dt)
    g = pulls[n] * grow
    corners = [p + np.array([x, y, 0.0]) for x, y in (w, g, w + g)]
    return now if (field_of(fields, np.array(corners)) == now).all() else -1


def pair(fields, na, no, times, dt, positions, orientations, velocities, spins, radii, half_heights, ahead, most,
         pulls, farthest, steady_a, steady_o, joined) -> bool:
    """transport._pair's rule for bodies na and no."""
    if steady_a and steady_o:
        n = max(ahead[na], ahead[no]) * times
        span = n * dt
        fall = (abs(velocities[na, 2]) + abs(velocities[no, 2])) * span + 0.5 * FALL * span * span
        if abs(positions[na, 2] - positions[no, 2]) >= half_heights[na] + half_heights[no] + fall:
            return False
        closing = math.hypot(*(velocities[na, :2] - velocities[no, :2]))
        rock = turning(radii[na], half_heights[na], spins[na]) + turning(radii[no], half_heights[no], spins[no])
        way = (closing + rock) * n * dt
        ba = on_one_belt(fields, na, farthest, dt, positions, velocities, pulls)
        bo = on_one_belt(fields, no, farthest, dt, positions, velocities, pulls)
        one = ba >= 0 and ba == bo
        if not one:
            way += (most[na] + most[no]) * n * (n + 1.0) / 2.0 * dt
        if math.hypot(*(positions[na, :2] - positions[no, :2])) - radii[na] - radii[no] - 2.0 * SHAPE_MARGIN >= way:
            return False
        return not (one and way == 0.0 and joined[na] and joined[no])
    ka, ko = ahead[na] * times * dt, ahead[no] * times * dt
    a = boxes(orientations[[na]], radii[[na]], half_heights[[na]], velocities[[na]], spins[[na]], ka)[0]
    o = boxes(orientations[[no]], radii[[no]], half_heights[[no]], velocities[[no]], spins[[no]], ko)[0]
    # rest.boxes adds the breaking threshold, which this rule leaves out.
    return bool((np.abs(positions[na] - positions[no]) < a + o - 2.0 * BREAKING).all())


def touching(fields, rows, play, times, dt, positions, orientations, velocities, spins, radii, half_heights, ahead,
             most, pulls, free, joined, against, part_centres, part_extents) -> np.ndarray:
    """transport._touching over every pair (no sweep): each row against every body of `against`
    in play whose bound (rest.bound) meets its own, and every moving part's box."""
    farthest = max(ahead[play]) * times if len(play) else 0.0
    reach = {n: bound(radii[n], half_heights[n], velocities[n], spins[n], ahead[n] * times * dt, SHAPE_MARGIN)
             for n in play}
    out = np.zeros(len(rows), bool)
    for i, n in enumerate(rows):
        for m in range(len(part_centres)):
            if (np.abs(positions[n] - part_centres[m]) < reach[n] + part_extents[m]).all():
                out[i] = True
        for o in play:
            if o == n or not against[o] or out[i]:
                continue
            if (np.abs(positions[n] - positions[o]) >= reach[n] + reach[o]).any():
                continue
            if pair(fields, n, o, times, dt, positions, orientations, velocities, spins, radii, half_heights, ahead,
                    most, pulls, farthest, steady(n, free, orientations, spins), steady(o, free, orientations, spins),
                    joined):
                out[i] = True
    return out


def still_on(speed, v) -> bool:
    return speed == 0.0 and v[0] * v[0] + v[1] * v[1] < STILL * STILL


def fixed_hit(fields, rows, times, dt, positions, velocities, pulls, ahead, radii, half_heights, c, h, cos, sin):
    """transport._fixed_hit against every fixed box (no list): the way over n = ahead·times ticks
    — the segments along v·n·dt from p, along the pull's part along v from p and from p + v·n·dt,
    the pull's part across widening the radius by FIXED_MARGIN more — comes within the radius of
    a box at its height that the bottle does not slide along (`slides`, on a straight belt)."""
    out = np.zeros(len(rows), bool)
    for i, m in enumerate(rows):
        n = ahead[m] * times
        v = velocities[m, :2]
        s = pulls[m] * (n * (n + 1.0) / 2.0 * dt)
        speed = math.hypot(*v)
        if speed == 0.0:
            along, across = math.hypot(*s), 0.0
            u = s / along if along > 0.0 else np.array([1.0, 0.0])
        else:
            u = v / speed
            along, across = float(s @ u), abs(s[0] * u[1] - s[1] * u[0])
        w, g = v * (n * dt), u * along
        straight = on_one_belt(fields, m, n, dt, positions, velocities, pulls) >= 0
        for k in range(len(c)):
            if abs(positions[m, 2] - c[k, 2]) > h[k, 2] + half_heights[m] + FIXED_MARGIN:
                continue
            turn = np.array([[cos[k], sin[k]], [-sin[k], cos[k]]])     # into the box's frame
            a = turn @ (positions[m, :2] - c[k, :2])
            if straight and slides(a, turn @ w, turn @ s, h[k, 0], h[k, 1], radii[m]):
                continue
            gap = min(segment_box_distance(a, turn @ w, h[k, 0], h[k, 1]),
                      segment_box_distance(a, turn @ g, h[k, 0], h[k, 1]),
                      segment_box_distance(a + turn @ w, turn @ g, h[k, 0], h[k, 1]))
            if gap < radii[m] + across + FIXED_MARGIN:
                out[i] = True
    return out


def grown(extents, growth, ahead, rows, times, dt):
    return extents + growth * (max(ahead[rows]) * times * dt) if len(rows) else extents


def near(fields, rows, times, dt, b, free, against, parts, fixed) -> np.ndarray:
    """transport._near: touching a body or a moving part (its box headed as far as the furthest
    look), or reaching a fixed box."""
    centres, extents, growth = parts
    out = touching(fields, rows, b["play"], times, dt, b["positions"], b["orientations"], b["velocities"],
                   b["spins"], b["radii"], b["half_heights"], b["ahead"], b["most"], b["pulls"], free, free, against,
                   centres, grown(extents, growth, b["ahead"], rows, times, dt))
    if fixed is not None:
        out |= fixed_hit(fields, rows, times, dt, b["positions"], b["velocities"], b["pulls"], b["ahead"], b["radii"],
                         b["half_heights"], *fixed)
    return out


def on_belt(fields, rows, now, times, dt, positions, velocities, pulls, ahead):
    """transport._on_belt: (ok, still, stays) per row."""
    ok, still, stays = (np.zeros(len(rows), bool) for _ in range(3))
    for i, n in enumerate(rows):
        k = now[i]
        if k < 0:
            continue
        m = ahead[n] * times
        there_point = positions[n] + velocities[n] * (m * dt)
        there = field_of(fields, there_point)[0]
        if there < 0 or fields.surfaces[k] != fields.surfaces[there]:
            continue
        grow = m * (m + 1.0) / 2.0 * dt
        stays[i] = there == k and field_of(fields, there_point + np.append(pulls[n] * grow, 0.0))[0] == k
        still[i] = still_on(fields.speeds[k], velocities[n])
        ok[i] = not still[i]
    return ok, still, stays


def leave(fields, rows, dt, b, free, joined, parts, fixed):
    """transport._leave after the pulls: of `rows`, those steady, standing on a belt's surface
    (within SINK), on it 2 × their look-ahead on and touching nothing then: (go, near)."""
    from hub.physics.transport_kernels import RISE, SINK
    p, q, v, w = b["positions"], b["orientations"], b["velocities"], b["spins"]
    riding, field = np.zeros(len(rows), bool), np.full(len(rows), -1)
    for i, n in enumerate(rows):
        upright = (1.0 - 2.0 * (q[n, 0] ** 2 + q[n, 1] ** 2) > math.cos(TILT) and (w[n] ** 2).sum() < SPIN * SPIN
                   and abs(v[n, 2]) < RISE)
        k = field_of(fields, p[n])[0]
        if (free[n] or upright) and k >= 0 and abs(p[n, 2] - b["half_heights"][n] - fields.surfaces[k]) < SINK:
            riding[i], field[i] = True, k
    ok = on_belt(fields, rows[riding], field[riding], 2.0, dt, p, v, b["pulls"], b["ahead"])[0]
    at = np.flatnonzero(riding)[ok]
    these = rows[at]
    centres, extents, growth = parts
    close = touching(fields, these, b["play"], 2.0, dt, p, q, v, w, b["radii"], b["half_heights"], b["ahead"],
                     b["most"], b["pulls"], free, joined, np.ones(len(free), bool), centres,
                     grown(extents, growth, b["ahead"], these, 2.0, dt))
    if fixed is not None:
        close |= fixed_hit(fields, these, 2.0, dt, p, v, b["pulls"], b["ahead"], b["radii"], b["half_heights"], *fixed)
    go, near_ = np.zeros(len(rows), bool), np.zeros(len(rows), bool)
    go[at], near_[at] = ~close, close
    return go, near_


def look(fields, tick, whole, rows, awake, dt, b, clear, free, parts, fixed):
    """transport._look after the pulls: (due, back, ok, still, near, now) and `clear` set."""
    from hub.physics.transport_kernels import LONG
    ahead = b["ahead"]
    due = np.array([whole or clear[n] < tick + ahead[n] for n in rows], bool)
    back = np.zeros(len(rows), bool)
    others = rows[~due]
    if len(others) and len(awake):
        against = np.zeros(len(free), bool)
        against[awake] = True
        centres, extents, growth = parts
        back[~due] = touching(fields, others, b["play"], 1.0, dt, b["positions"], b["orientations"], b["velocities"],
                              b["spins"], b["radii"], b["half_heights"], ahead, b["most"], b["pulls"], free, free,
                              against, centres, grown(extents, growth, ahead, others, 1.0, dt))
    seen = rows[due]
    now = field_of(fields, b["positions"][seen]) if len(seen) else np.zeros(0, int)
    everyone = np.ones(len(free), bool)
    ok, still, stays = on_belt(fields, seen, now, float(LONG), dt, b["positions"], b["velocities"], b["pulls"], ahead)
    near_ = near(fields, seen, float(LONG), dt, b, free, everyone, parts, fixed)
    clear[seen] = tick + LONG * ahead[seen]
    short = ~ok | ~stays | near_
    if short.any():
        these = seen[short]
        ok1, still1, _ = on_belt(fields, these, now[short], 1.0, dt, b["positions"], b["velocities"], b["pulls"], ahead)
        ok[short], still[short] = ok1, still1
        near_[short] = near(fields, these, 1.0, dt, b, free, everyone, parts, fixed)
        clear[these] = tick + ahead[these]
    return due, back, ok, still, near_, now
