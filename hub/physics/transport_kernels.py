"""The compiled loops of free transport: the tests that let a bottle leave the engine or bring it
back, and the belt's law it follows while free (transport.py says what they decide and when).

Each is plain Python that numba compiles (`cache=True`: make warm compiles them once); each takes
a few packed tables — the bodies' state (Body), each body's look (Way), the fixed boxes with each
body's list of them (Fixed), the belts' regions (ForceFields.regions) — named tuples of the arrays
as they are, never a Python object; tests/physics/test_kernels.py holds each to a plain numpy
reference on random scenes, and runs the physics tests once more with the JIT off. The laws and
limits below are what the tests decide by.
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from hub.physics.fields import ARC, HEIGHT, SPEED, STRAIGHT, Regions, field_at, law_at
from hub.physics.grid import grid_of, in_cells
from hub.physics.rest import SHAPE_MARGIN, bound, extent, turning

TILT = 0.0175         # rad (1°): most tilt a bottle may leave the engine with
SPIN = 2.5            # rad/s: most spin (a rocking bottle on a belt: up to 1.7)
RISE = 0.02           # m/s: most vertical speed
SINK = 0.005          # m: most distance between its base and the belt's surface
STILL = 0.005         # m/s: on a still belt a bottle slower than this re-enters, to rest
FIXED_MARGIN = SHAPE_MARGIN + 0.001   # m a free bottle keeps from fixed geometry beyond its travel
SLIDE = 1e-9          # m: most a bottle sliding along a box's face may come nearer it over a look
SLIDE_INTO = SHAPE_MARGIN   # m: a bottle reaching further than this into a box does not slide along it
FALL = 9.81           # m/s²: what two steady bodies' heights may close at, beyond their vertical speeds
LONG = 4              # a whole look goes this many look-aheads forward where it can
LIST = 0.1            # m: the fixed boxes within this of a free bottle are the ones it is tested against
NEAR = 32             # boxes a bottle's list holds; one with more within LIST stays in the engine

#: every body's state, a row each (hub/physics/bodies.py's arrays; spins: angular velocities)
Body = namedtuple("Body", "positions orientations velocities spins masses radii half_heights")
#: every body's look: its look-ahead in ticks, the most it may be pulled over a look, its pull now
#: (FreeTransport's ahead, most, pulls; `_pulls` writes the last two)
Way = namedtuple("Way", "ahead most pulls")
#: the fixed boxes as `with_grid` makes them (their table and grid) and each body's list of those
#: near it: where it was listed, the first NEAR of them and how many (`_relist` writes these)
Fixed = namedtuple("Fixed", "boxes grid listed_at near near_count")


@njit(cache=True)
def _fixed_hit(rows, times, dt, body, way, regions, fixed):
    """(len(rows),): whether each of `rows`, headed on for `times` × its look-ahead (n ticks),
    could reach a fixed box (`fixed`: the table of centre, half extents, cos and sin of the yaw,
    one a row, its grid (`with_grid`) and the bodies' lists of them).

    Its way: n ticks at its velocity v, plus what the belt's pull adds — a pull that does
    not grow (the relaxing law, or friction's constant cap; a belt's speed change looks
    again at once, with the pull at the new speed) moves it at most n(n+1)/2·|Δv|·dt
    further, along the last change Δv. So at every one of the n ticks it is at
    p + a·v·T + b·S·Δv for some a, b in [0, 1] (T = n·dt, S = n(n+1)/2·dt). The part of
    S·Δv along v keeps it on v's line: within the three segments from p along v·T, from p
    along that part, and from p + v·T along it; the part across v widens its radius, with
    FIXED_MARGIN. A bottle setting off from rest on a belt between rails is pulled along
    them, not into them. Each segment's distance from each box it may reach (listed
    within LIST) against the radius so widened: its ends and the box's corners give the
    distance whenever the segment is shorter than the bottle is wide. Each bottle's boxes are
    listed afresh once it has moved LIST/2 from where they were last, across or up (the only
    boxes it can reach before then are within LIST of it there, both ways); one with more
    than NEAR of them counts as reaching one.

    A bottle that rides a straight belt along a box's face instead — beside that face all the
    way, no further into it than the engine's contact leaves one (SLIDE_INTO), and coming no
    nearer it than SLIDE — slides along it as a bottle in the engine slides along a
    frictionless rail, untouched: however near it is, even touching (a queue's bottles ride
    on pressed against a guard rail, at one velocity along it), that box cannot stop it
    (`_slides`).

    Row by row and, for each, box by box of its list (listed again first where it is stale), or
    of the grid's cells its way can reach."""
    positions, velocities, radii, half_heights = body.positions, body.velocities, body.radii, body.half_heights
    ahead, pulls = way.ahead, way.pulls
    boxes, grid, listed_at, near, near_count = fixed
    c, h, cos, sin = boxes[:, 0:3], boxes[:, 3:6], boxes[:, 6], boxes[:, 7]
    found = np.empty(c.shape[0], np.int64)
    hit = np.zeros(rows.shape[0], np.bool_)
    for i in range(rows.shape[0]):
        n_ = rows[i]
        if (math.hypot(positions[n_, 0] - listed_at[n_, 0], positions[n_, 1] - listed_at[n_, 1]) > LIST / 2.0
                or abs(positions[n_, 2] - listed_at[n_, 2]) > LIST / 2.0):
            _relist(n_, body, fixed)
        if near_count[n_] > near.shape[1]:
            hit[i] = True
            continue
        # Its way at its velocity (wx, wy), the pull's way along it (gx, gy) and the widening across.
        n = ahead[n_] * times
        vx, vy = velocities[n_, 0], velocities[n_, 1]
        grow = n * (n + 1.0) / 2.0 * dt
        sx, sy = pulls[n_, 0] * grow, pulls[n_, 1] * grow
        speed = math.hypot(vx, vy)
        if speed == 0.0:
            along, across = math.hypot(sx, sy), 0.0
            ux, uy = (sx / along, sy / along) if along > 0.0 else (1.0, 0.0)
        else:
            ux, uy = vx / speed, vy / speed
            along, across = sx * ux + sy * uy, abs(sx * uy - sy * ux)
        wx, wy = vx * n * dt, vy * n * dt
        gx, gy = ux * along, uy * along
        widen = across + FIXED_MARGIN
        px, py = positions[n_, 0], positions[n_, 1]
        straight = _belt(n_, n, dt, body, way, regions) >= 0
        # The list holds every box its way can reach only while the way, widened, stays within
        # LIST/2 of where it is (it is within LIST/2 of where it was listed): a longer way (a fast
        # bottle over a long look) is tested against every box of the grid's cells it can reach,
        # those out of its reach skipped.
        far = math.hypot(wx, wy) + math.hypot(gx, gy) + widen
        every = far > LIST / 2.0
        count = 0
        if every:
            reach = radii[n_] + far
            count = in_cells(grid, px - reach, px + reach, py - reach, py + reach, found)
        for j in range(count if every else near_count[n_]):
            k = found[j] if every else near[n_, j]
            if abs(positions[n_, 2] - c[k, 2]) > h[k, 2] + half_heights[n_] + FIXED_MARGIN:
                continue
            if every and math.hypot(px - c[k, 0], py - c[k, 1]) - math.hypot(h[k, 0], h[k, 1]) > radii[n_] + far:
                continue
            ax, ay = px - c[k, 0], py - c[k, 1]
            a0, a1 = cos[k] * ax + sin[k] * ay, cos[k] * ay - sin[k] * ax
            d0, d1 = cos[k] * wx + sin[k] * wy, cos[k] * wy - sin[k] * wx
            if straight and _slides(a0, a1, d0, d1, cos[k] * sx + sin[k] * sy, cos[k] * sy - sin[k] * sx, h[k, 0],
                                    h[k, 1], radii[n_]):
                continue
            e0, e1 = cos[k] * gx + sin[k] * gy, cos[k] * gy - sin[k] * gx
            gap = min(_segment_gap(a0, a1, d0, d1, h[k, 0], h[k, 1]), _segment_gap(a0, a1, e0, e1, h[k, 0], h[k, 1]),
                      _segment_gap(a0 + d0, a1 + d1, e0, e1, h[k, 0], h[k, 1]))
            if gap < radii[n_] + widen:
                hit[i] = True
                break
    return hit


@njit(cache=True)
def _on_belt(rows, now, times, dt, body, way, regions):
    """(ok, still, stays), each (len(rows),): riding a belt now (`now`: the field under each)
    and, `times` × its look-ahead on, one at the same height, not coming to a stop on a still
    belt (ok); on a belt, coming to a stop on a still one (still); on the same belt all the
    way, at its velocity and with the belt's pull (stays: its law, and so its pull, does not
    change on the way — one crossing onto a slower belt is pulled harder there)."""
    table = regions.table
    positions, velocities, ahead, pulls = body.positions, body.velocities, way.ahead, way.pulls
    count = rows.shape[0]
    ok, still, stays = np.zeros(count, np.bool_), np.zeros(count, np.bool_), np.zeros(count, np.bool_)
    for i in range(count):
        n, k = rows[i], now[i]
        if k < 0:
            continue
        m = ahead[n] * times
        x = positions[n, 0] + velocities[n, 0] * (m * dt)
        y = positions[n, 1] + velocities[n, 1] * (m * dt)
        z = positions[n, 2] + velocities[n, 2] * (m * dt)
        there = field_at(x, y, z, regions)
        if there < 0 or table[k, HEIGHT] != table[there, HEIGHT]:
            continue
        grow = m * (m + 1.0) / 2.0 * dt
        stays[i] = there == k and field_at(x + pulls[n, 0] * grow, y + pulls[n, 1] * grow, z, regions) == k
        vx, vy = velocities[n, 0], velocities[n, 1]
        still[i] = table[k, SPEED] == 0.0 and vx * vx + vy * vy < STILL * STILL
        ok[i] = not still[i]
    return ok, still, stays


@njit(cache=True)
def _pulls(rows, dt, explicit, body, way, regions):
    """The pull each moving body of `rows` gets from the belt under it at its velocity now
    (`pulls`: what the next tick applies), in place of the last tick's, which is stale once a
    bottle crossed onto another belt; and `most`, the most it may be pulled over a look (one,
    two or LONG look-aheads forward): the larger of now and the law where its way ends, which
    may be another belt's. Bodies not in `rows` (resting, parked) are not pulled: the caller
    (`_look`, `_leave`) zeroes `most` first."""
    table = regions.table
    positions, velocities, masses = body.positions, body.velocities, body.masses
    ahead, most, pulls = way
    for n in rows:
        x, y, z = positions[n, 0], positions[n, 1], positions[n, 2]
        vx, vy = velocities[n, 0], velocities[n, 1]
        largest, here = 0.0, -1
        for times in (0.0, 1.0, 2.0, float(LONG)):
            h = ahead[n] * times * dt
            k = field_at(x + vx * h, y + vy * h, z + velocities[n, 2] * h, regions)
            if times > 0.0 and k == here and (k < 0 or not table[k, ARC]):
                continue        # the same straight belt: the same law at the same velocity
            dvx = dvy = 0.0
            if k >= 0:
                dvx, dvy = law_at(k, x + vx * h, y + vy * h, vx, vy, masses[n], dt, explicit, table)
            size = math.hypot(dvx, dvy)
            if times == 0.0:
                pulls[n, 0], pulls[n, 1], here = dvx, dvy, k
            largest = max(largest, size)
        most[n] = largest


@njit(cache=True)
def _advance(rows, positions, orientations, velocities, masses, offsets, dt, explicit, table, grid):
    """FreeTransport.advance, row by row: the field under its centre (`field_at`), the law's
    change at its grip point (`law_at`: its base is frames.base_points' with no spin), then
    x ← x + v·dt."""
    regions = Regions(table, grid)   # made here: a named tuple given costs a call per tick its typing
    for n in rows:
        k = field_at(positions[n, 0], positions[n, 1], positions[n, 2], regions)
        if k >= 0:
            px, py = positions[n, 0], positions[n, 1]
            if offsets[n] > 0.0:
                x, y, z, w = orientations[n, 0], orientations[n, 1], orientations[n, 2], orientations[n, 3]
                px += -offsets[n] * (2.0 * (x * z + w * y))
                py += -offsets[n] * (2.0 * (y * z - w * x))
            dvx, dvy = law_at(k, px, py, velocities[n, 0], velocities[n, 1], masses[n], dt, explicit, table)
            velocities[n, 0] += dvx
            velocities[n, 1] += dvy
        positions[n, 0] += velocities[n, 0] * dt
        positions[n, 1] += velocities[n, 1] * dt


@njit(cache=True)
def _relist(n, body, fixed):
    """Body `n`'s list: the fixed boxes (`_fixed_hit`) its upright footprint is within LIST of,
    horizontally and in height, the first NEAR of them, and how many there are: of the boxes in
    the grid's cells within LIST of its footprint."""
    positions, radii, half_heights = body.positions, body.radii, body.half_heights
    boxes, grid, listed_at, near, near_count = fixed
    c, h, cos, sin = boxes[:, 0:3], boxes[:, 3:6], boxes[:, 6], boxes[:, 7]
    reach = radii[n] + LIST
    px, py = positions[n, 0], positions[n, 1]
    found = np.empty(c.shape[0], np.int64)
    count = 0
    for j in range(in_cells(grid, px - reach, px + reach, py - reach, py + reach, found)):
        k = found[j]
        if abs(positions[n, 2] - c[k, 2]) > h[k, 2] + half_heights[n] + FIXED_MARGIN + LIST:
            continue
        dx, dy = positions[n, 0] - c[k, 0], positions[n, 1] - c[k, 1]
        if _box_distance(cos[k] * dx + sin[k] * dy, cos[k] * dy - sin[k] * dx, h[k, 0], h[k, 1]) - radii[n] < LIST:
            if count < near.shape[1]:
                near[n, count] = k
            count += 1
    near_count[n] = count
    listed_at[n, 0], listed_at[n, 1], listed_at[n, 2] = positions[n, 0], positions[n, 1], positions[n, 2]


@njit(cache=True)
def _slides(a0, a1, d0, d1, s0, s1, hx, hy, r):
    """Whether a bottle of radius r at (a0, a1) in a box's frame (half extents hx, hy), its way
    the parallelogram of (d0, d1) and (s0, s1), stays beside one face of the box — its centre
    within the face's span all the way, where the box's nearest point to it is on that face —
    reaches no further into it than SLIDE_INTO (what the engine's contact leaves, within the
    shapes' margins: one deeper is in a box that is not solid, which may turn solid) and comes no
    nearer the face than SLIDE."""
    for j in range(2):
        aj, dj, sj, hj = (a1, d1, s1, hy) if j == 1 else (a0, d0, s0, hx)
        ai, di, si, hi = (a0, d0, s0, hx) if j == 1 else (a1, d1, s1, hy)
        if (abs(aj) - hj < r - SLIDE_INTO
                or max(abs(ai), abs(ai + di), abs(ai + si), abs(ai + di + si)) > hi):
            continue
        side = 1.0 if aj > 0.0 else -1.0
        if min(0.0, side * dj) + min(0.0, side * sj) >= -SLIDE:
            return True
    return False


@njit(cache=True)
def _segment_gap(a0, a1, d0, d1, hx, hy):
    """Distance from the segment from (a0, a1) along (d0, d1), in a box's frame, to the box of
    half extents (hx, hy): 0 where it crosses the box (clipped against both slabs), else its ends',
    and the box corners' from it (two disjoint convex shapes are nearest at a corner of one). Without
    the crossing a way longer than the bottle is wide passed through a thin gate across its belt
    unseen (tests/physics/test_kernels.py, test_transport.py)."""
    lo, hi = 0.0, 1.0
    for p, q, half in ((a0, d0, hx), (a1, d1, hy)):
        if q == 0.0:
            if abs(p) > half:
                hi = -1.0
        else:
            t0, t1 = (-half - p) / q, (half - p) / q
            lo, hi = max(lo, min(t0, t1)), min(hi, max(t0, t1))
    if lo <= hi:
        return 0.0
    gap = min(_box_distance(a0, a1, hx, hy), _box_distance(a0 + d0, a1 + d1, hx, hy))
    length2 = max(d0 * d0 + d1 * d1, 1e-300)
    for sx in (1.0, -1.0):
        for sy in (1.0, -1.0):
            kx, ky = sx * hx - a0, sy * hy - a1
            t = min(max((kx * d0 + ky * d1) / length2, 0.0), 1.0)
            gap = min(gap, math.hypot(kx - t * d0, ky - t * d1))
    return gap


@njit(cache=True)
def _box_distance(x, y, hx, hy):
    """Distance from the point (x, y), in a box's frame, to the box of half extents (hx, hy) (0 inside)."""
    return math.hypot(max(abs(x) - hx, 0.0), max(abs(y) - hy, 0.0))


@njit(cache=True)
def _touching(rows, play, times, dt, body, way, free, joined, against, regions, part_centres, part_extents):
    """(len(rows),): whether each of `rows` could touch another body in play (or of `among`)
    or a moving part within `times` × its look-ahead. Their bounds first (rest.bound; pairs
    found by a sweep along the plant's longer axis when there are many), then for each pair
    whose bounds meet: two steady bottles (free, or upright and steady in the engine) by their
    footprints and their relative motion — the difference of their velocities, of the belt's
    pull and their rocking brings them together, nothing else; any other pair by the wake
    rule's boxes, each body headed as far.

    Two steady bottles on one straight belt whose law scales with the mass, both staying
    on it as far as the look goes (`belt`), follow the same law, which never lets two
    velocities part — on u = v_belt − v it is u ↦ k·u, or with friction's cap
    u ↦ u − (1 − k)·P(u), P the projection onto a ball: both non-expansive — so their gap
    changes by at most n·|v_a − v_b|·dt, however hard the belt pulls: a line of bottles
    setting off from rest together stays a line. Two such bottles both `joined` (by default:
    free) at the same velocity, bit for bit, and not turning are a train: the law gives both
    the same velocity change at every tick and the engine's position step moves both alike,
    so their gap stays what it is, to rounding, even when they touch (a magazine's queue
    stood at rest in pairs, and rides off together). Free bottles nearer each other than
    2·SHAPE_MARGIN are a train's, and when one of them comes back into the engine the other
    comes too (`FreeTransport._trains`).

    `play`: the bodies in play (sorted, holds `rows`); `against`: a mask of the bodies they are
    looked at against; `joined`: the bodies that may form a train; `regions`: ForceFields.regions
    (its STRAIGHT column: straight with its law scaled by the mass); the moving parts'
    boxes (part_centres, part_extents). Pairs by their bounds (rest.bound), found along the
    plant's longer axis from each row outwards. Only `rows` and the bodies of `against` are
    bounded and sorted."""
    positions, orientations, velocities, spins = body.positions, body.orientations, body.velocities, body.spins
    radii, half_heights, ahead = body.radii, body.half_heights, way.ahead
    farthest = 0.0
    for q in range(play.shape[0]):
        farthest = max(farthest, ahead[play[q]] * times)
    # Only `rows` and the bodies they are looked at against are bounded and sorted (against the
    # bodies awake in the engine: a third of those in play), in the order of `play`.
    wanted = against.copy()
    wanted[rows] = True
    count = 0
    for q in range(play.shape[0]):
        count += wanted[play[q]]
    kept = np.empty(count, np.int64)
    count = 0
    for q in range(play.shape[0]):
        if wanted[play[q]]:
            kept[count] = play[q]
            count += 1
    play = kept
    reaches = np.empty(count)
    steady = np.empty(count, np.bool_)
    belt = np.full(count, -2, np.int64)   # worked out for a body once a pair needs it (`_belt`)
    tilt = math.cos(TILT)
    for q in range(count):
        n = play[q]
        w = spins[n]
        reaches[q] = bound(radii[n], half_heights[n], velocities[n], w, ahead[n] * times * dt, SHAPE_MARGIN)
        spin = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        x, y = orientations[n, 0], orientations[n, 1]
        # Upright and not rocking much: its footprint is its base's circle (a bob up and down moves
        # it not at all; one above another is apart only as far as falling cannot close, `_pair`).
        steady[q] = free[n] or (1.0 - 2.0 * (x * x + y * y) > tilt and spin < SPIN)
    lo_x, hi_x, lo_y, hi_y = np.inf, -np.inf, np.inf, -np.inf
    for q in range(count):
        lo_x = min(lo_x, positions[play[q], 0])
        hi_x = max(hi_x, positions[play[q], 0])
        lo_y = min(lo_y, positions[play[q], 1])
        hi_y = max(hi_y, positions[play[q], 1])
    axis = 0 if hi_x - lo_x >= hi_y - lo_y else 1
    key = np.empty(count)
    for q in range(count):
        key[q] = positions[play[q], axis]
    order = np.argsort(key, kind="mergesort")
    rank = np.empty(count, np.int64)
    for q in range(count):
        rank[order[q]] = q
    widest = reaches.max() if count else 0.0
    touching = np.zeros(rows.shape[0], np.bool_)
    for i in range(rows.shape[0]):
        a = np.searchsorted(play, rows[i])
        n = rows[i]
        for m in range(part_centres.shape[0]):   # a moving part's box against the reaches (which holds the box)
            if (abs(positions[n, 0] - part_centres[m, 0]) < reaches[a] + part_extents[m, 0]
                    and abs(positions[n, 1] - part_centres[m, 1]) < reaches[a] + part_extents[m, 1]
                    and abs(positions[n, 2] - part_centres[m, 2]) < reaches[a] + part_extents[m, 2]):
                touching[i] = True
        for step in (1, -1):
            t = rank[a] + step
            while 0 <= t < count and not touching[i]:
                o = order[t]
                if abs(key[o] - key[a]) >= reaches[a] + widest:
                    break
                t += step
                na, no, reach = play[a], play[o], reaches[a] + reaches[o]
                if not against[no]:
                    continue
                if (abs(positions[na, 0] - positions[no, 0]) >= reach or abs(positions[na, 1] - positions[no, 1]) >= reach
                        or abs(positions[na, 2] - positions[no, 2]) >= reach):
                    continue      # their bounds do not meet
                if _pair(a, o, play, times, dt, body, way, belt, farthest, regions, reaches, steady, joined):
                    touching[i] = True
    return touching


@njit(cache=True)
def _pair(a, o, play, times, dt, body, way, belt, farthest, regions, reaches, steady, joined):
    """Whether bodies play[a] and play[o] could touch within the look (`_touching`);
    not when they are a train: both joined, on one straight belt whose law scales with the mass
    and staying on it, at the same velocity and not turning — the law moves them alike."""
    positions, orientations, velocities, spins = body.positions, body.orientations, body.velocities, body.spins
    radii, half_heights, ahead, most = body.radii, body.half_heights, way.ahead, way.most
    na, no = play[a], play[o]       # their bounds meet (the caller tested them)
    if steady[a] and steady[o]:
        n = max(ahead[na], ahead[no]) * times
        ax, ay = positions[na, 0] - positions[no, 0], positions[na, 1] - positions[no, 1]
        # One above the other: apart if their heights cannot close over the look (at their
        # vertical speeds, and one falling freely).
        span = n * dt
        fall = (abs(velocities[na, 2]) + abs(velocities[no, 2])) * span + 0.5 * FALL * span * span
        if abs(positions[na, 2] - positions[no, 2]) >= half_heights[na] + half_heights[no] + fall:
            return False
        closing = math.hypot(velocities[na, 0] - velocities[no, 0], velocities[na, 1] - velocities[no, 1])
        rock = turning(radii[na], half_heights[na], spins[na]) + turning(radii[no], half_heights[no], spins[no])
        travel = (closing + rock) * n * dt
        for q in (a, o):
            if belt[q] == -2:
                belt[q] = _belt(play[q], farthest, dt, body, way, regions)
        one_belt = belt[a] >= 0 and belt[a] == belt[o]
        if not one_belt:
            travel += (most[na] + most[no]) * n * (n + 1.0) / 2.0 * dt   # the most each may be pulled (_pulls)
        if math.hypot(ax, ay) - radii[na] - radii[no] - 2.0 * SHAPE_MARGIN >= travel:
            return False
        return not (one_belt and travel == 0.0 and joined[na] and joined[no])
    ka, ko = ahead[na] * times, ahead[no] * times
    for c in range(3):
        # The wake rule's boxes without the contact breaking threshold (a free bottle is in no island
        # of the engine's: what matters is a contact).
        reach = (extent(orientations[na], radii[na], half_heights[na], velocities[na], spins[na], ka * dt, c,
                        SHAPE_MARGIN)
                 + extent(orientations[no], radii[no], half_heights[no], velocities[no], spins[no], ko * dt, c,
                          SHAPE_MARGIN))
        if abs(positions[na, c] - positions[no, c]) >= reach:
            return False
    return True


@njit(cache=True)
def _belt(n, m, dt, body, way, regions):
    """The straight belt with a mass-scaled law body `n` stands on and stays on for `m` ticks at
    its velocity and pull, or −1."""
    table = regions.table
    positions, velocities, pulls = body.positions, body.velocities, way.pulls
    x, y, z = positions[n, 0], positions[n, 1], positions[n, 2]
    now = field_at(x, y, z, regions)
    if now < 0 or table[now, STRAIGHT] == 0.0:
        return -1
    # Its way lies in the parallelogram of its velocity's way and the pull's: all four corners on
    # the belt (a band, convex) keep all of it there.
    grow = m * (m + 1.0) / 2.0 * dt
    wx, wy = velocities[n, 0] * m * dt, velocities[n, 1] * m * dt
    gx, gy = pulls[n, 0] * grow, pulls[n, 1] * grow
    for cx, cy in ((wx, wy), (gx, gy), (wx + gx, wy + gy)):
        if field_at(x + cx, y + cy, z, regions) != now:
            return -1
    return now


@njit(cache=True)
def _grow(out, pool, body):
    """FreeTransport._trains: `out` grown in place by the bodies of `pool` within 2·SHAPE_MARGIN
    of one it holds (upright footprints, overlapping in height), theirs in turn."""
    positions, radii, half_heights = body.positions, body.radii, body.half_heights
    stack = [n for n in pool if out[n]]
    while stack:
        n = stack.pop()
        for m in pool:
            if (not out[m] and abs(positions[n, 2] - positions[m, 2]) < half_heights[n] + half_heights[m]
                    and math.hypot(positions[n, 0] - positions[m, 0], positions[n, 1] - positions[m, 1])
                    - radii[n] - radii[m] < 2.0 * SHAPE_MARGIN):
                out[m] = True
                stack.append(m)


@njit(cache=True)
def _grown(extents, growth, ahead, rows, times, dt):
    """The moving parts' half extents headed as far as the furthest look of `rows` goes."""
    farthest = 0.0
    for n in rows:
        farthest = max(farthest, ahead[n])
    return extents + growth * (farthest * times * dt)


@njit(cache=True)
def _look(tick, whole, rows, pulled, awake, play, dt, body, way, clear, free, explicit, regions, parts, fixed):
    """FreeTransport.release_near's look at the free `rows`, in one call: every pull taken afresh
    (`_pulls`, for `pulled`); the rows not due for a whole look against the bodies `awake` in
    the engine; those due (all when `whole`) LONG look-aheads forward, and what that finds near
    one look-ahead forward, each by `_on_belt`, `_touching` and `_fixed_hit`, with `clear` set to
    the tick their look holds to. Returns (due, back, ok, still, near, now): per row whether it
    was due and whether the look against the awake bodies found it near; per row due, riding on
    (ok), coming to a stop on a still belt (still), near something (near), and its field now.
    `regions`: ForceFields.regions; `parts`: FreeTransport._part_boxes; `fixed`: the fixed boxes (`_fixed_hit`)."""
    positions, ahead = body.positions, way.ahead
    way.most[:] = 0.0
    if pulled.shape[0]:
        _pulls(pulled, dt, explicit, body, way, regions)
    count = rows.shape[0]
    due = np.empty(count, np.bool_)
    for i in range(count):
        due[i] = whole or clear[rows[i]] < tick + ahead[rows[i]]
    back = np.zeros(count, np.bool_)
    others = rows[~due]
    if others.shape[0] and awake.shape[0]:
        against = np.zeros(free.shape[0], np.bool_)
        against[awake] = True
        found = _touching(others, play, 1.0, dt, body, way, free, free, against, regions, parts[:, 0:3],
                          _grown(parts[:, 3:6], parts[:, 6:9], ahead, others, 1.0, dt))
        k = 0
        for i in range(count):
            if not due[i]:
                back[i] = found[k]
                k += 1
    look = rows[due]
    m = look.shape[0]
    ok, still, near = np.zeros(m, np.bool_), np.zeros(m, np.bool_), np.zeros(m, np.bool_)
    now = np.full(m, -1, np.int64)
    if m == 0:
        return due, back, ok, still, near, now
    for i in range(m):
        n = look[i]
        now[i] = field_at(positions[n, 0], positions[n, 1], positions[n, 2], regions)
    everyone = np.ones(free.shape[0], np.bool_)
    # LONG look-aheads forward first, then what that finds near, or off its belt, one forward.
    ok, still, stays = _on_belt(look, now, float(LONG), dt, body, way, regions)
    near = _near(look, float(LONG), play, dt, body, way, free, everyone, regions, parts, fixed)
    for i in range(m):
        clear[look[i]] = tick + LONG * ahead[look[i]]
    short = np.flatnonzero(~ok | ~stays | near)
    if short.shape[0]:
        these = look[short]
        ok1, still1, _ = _on_belt(these, now[short], 1.0, dt, body, way, regions)
        near1 = _near(these, 1.0, play, dt, body, way, free, everyone, regions, parts, fixed)
        for j in range(short.shape[0]):
            i = short[j]
            ok[i], still[i], near[i] = ok1[j], still1[j], near1[j]
            clear[look[i]] = tick + ahead[look[i]]
    return due, back, ok, still, near, now


@njit(cache=True)
def _near(rows, times, play, dt, body, way, free, against, regions, parts, fixed):
    """`_touching` or `_fixed_hit`, for `_look`."""
    near = _touching(rows, play, times, dt, body, way, free, free, against, regions, parts[:, 0:3],
                     _grown(parts[:, 3:6], parts[:, 6:9], way.ahead, rows, times, dt))
    if fixed.boxes.shape[0]:
        near = near | _fixed_hit(rows, times, dt, body, way, regions, fixed)
    return near


@njit(cache=True)
def _leave(rows, pulled, play, dt, body, way, free, joined, explicit, regions, parts, fixed):
    """FreeTransport._leaving in one call: every pull afresh (`_pulls`, for `pulled`), then of
    `rows` those steady (upright, tilt under TILT, spin under SPIN, vertical speed under RISE, or
    free) with their base on a belt's surface, on it 2 ×
    their look-ahead forward (`_on_belt`), and touching nothing then (`_touching`, `_fixed_hit`):
    masks over `rows` of those that go and those near something."""
    table = regions.table
    positions, orientations, velocities = body.positions, body.orientations, body.velocities
    spins, half_heights, ahead = body.spins, body.half_heights, way.ahead
    way.most[:] = 0.0
    if pulled.shape[0]:
        _pulls(pulled, dt, explicit, body, way, regions)
    count = rows.shape[0]
    tilt = math.cos(TILT)
    riding = np.zeros(count, np.bool_)
    field = np.full(count, -1, np.int64)
    for i in range(count):
        n = rows[i]
        x, y, w = orientations[n, 0], orientations[n, 1], spins[n]
        if not (free[n] or (1.0 - 2.0 * (x * x + y * y) > tilt and w[0] * w[0] + w[1] * w[1] + w[2] * w[2] < SPIN * SPIN
                            and abs(velocities[n, 2]) < RISE)):
            continue
        k = field_at(positions[n, 0], positions[n, 1], positions[n, 2], regions)
        if k >= 0 and abs(positions[n, 2] - half_heights[n] - table[k, HEIGHT]) < SINK:
            riding[i], field[i] = True, k
    these = rows[riding]
    ok = _on_belt(these, field[riding], 2.0, dt, body, way, regions)[0]
    go, near = np.zeros(count, np.bool_), np.zeros(count, np.bool_)
    these = these[ok]
    if these.shape[0] == 0:
        return go, near
    close = _touching(these, play, 2.0, dt, body, way, free, joined, np.ones(free.shape[0], np.bool_), regions,
                      parts[:, 0:3], _grown(parts[:, 3:6], parts[:, 6:9], ahead, these, 2.0, dt))
    if fixed.boxes.shape[0] and not close.all():
        rest = these[~close]
        hit = _fixed_hit(rest, 2.0, dt, body, way, regions, fixed)
        k = 0
        for j in range(close.shape[0]):
            if not close[j]:
                close[j] = hit[k]
                k += 1
    at = np.flatnonzero(riding)[ok]
    for j in range(at.shape[0]):
        go[at[j]], near[at[j]] = not close[j], close[j]
    return go, near


_NO_PARTS = np.zeros((0, 9))   # moving parts' boxes: centre, half extents, growth (FreeTransport._part_boxes)


def with_grid(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fixed boxes as Fixed holds them: `table` (centre, half extents, cos and sin of the
    yaw, a row each) and its grid (hub/physics/grid.py), so that a bottle's tests look at the
    boxes near it, not at all of a hall's."""
    return table, grid_of(table)


_NO_BOXES = with_grid(np.zeros((0, 8)))   # fixed boxes: their table and grid (with_grid, Fixed)
