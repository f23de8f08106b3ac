"""Every compiled kernel of the physics tick (numba, hub/physics/) against a plain numpy statement
of what it computes (tests/physics/reference.py), on random inputs drawn by hypothesis.

A decision — in a field or not, inside a trigger or not, at rest or not, near something or not,
free or not — must agree exactly: the engine's course follows it. Numbers agree bit for bit where
the reference does the same operations in the same order; elsewhere to TOL (relative), because the
reference writes the law differently (a rotation as a matrix, a relaxation as
v_belt + (v − v_belt)·e^(−k·dt) instead of (v_belt − v)·(1 − e^(−k·dt))), which moves the last bits.
Inputs keep clear of a decision's threshold by far more than rounding where the two are computed
in different orders (`clear_of`), so that an agreement asked for is one rounding cannot break.

The last test runs these and the rest of tests/physics once more with the JIT off, so that the
kernels' Python — what a reader reads and a debugger steps — is what the compiled code does.
"""
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from hub.physics import fields as F
from hub.physics import rest as R
from hub.physics import transport_kernels as T
from hub.physics import triggers as G
from hub.physics import watch as W
from hub.physics.fields import ForceFields
from hub.physics.frames import Arc, Pose, Straight

from ..helpers import ROOT
from . import reference as ref

TOL = 1e-12
DT = 1.0 / 150
SETTINGS = settings(max_examples=int(os.environ.get("KERNEL_EXAMPLES", 150)), deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
seeds = st.integers(0, 2**32 - 1)


def close(a, b, scale=1.0) -> bool:
    return bool(np.all(np.abs(np.asarray(a, float) - np.asarray(b, float)) <= TOL * (scale + np.abs(b))))


# --- random scenes ---------------------------------------------------------------------------
def belts(rng, explicit=False, hall=False) -> ForceFields:
    """Two to five belts, straights and arcs, overlapping near the origin, of every grip and law;
    in a `hall`, as many again spread over 8 m, so that a point's cell of the regions' grid lists
    a few of them (hub/physics/grid.py)."""
    fields = ForceFields(DT, "explicit" if explicit else "exact")
    for b in range(rng.integers(2, 6) * (2 if hall else 1)):
        far = rng.uniform(-4.0, 4.0, 2) if hall and b % 2 else np.zeros(2)
        start = Pose(*(rng.uniform(-0.6, 0.1, 2) + far), rng.uniform(-0.01, 0.01), rng.uniform(-math.pi, math.pi))
        line = (Arc(start, rng.uniform(0.2, 0.8), rng.uniform(0.5, 3.0), int(rng.choice([-1, 1])))
                if rng.random() < 0.35 else Straight(start, rng.uniform(0.3, 1.5)))
        fields.add_region(line, rng.uniform(0.03, 0.2), start.z - 0.03, start.z + 0.12, rng.uniform(1.0, 40.0),
                          rng.choice([0.0, rng.uniform(-1.0, 1.0)]), grip=rng.choice(F.GRIPS),
                          per_mass=bool(rng.random() < 0.7),
                          limit=math.inf if rng.random() < 0.5 else rng.uniform(1.0, 5.0))
    return fields


def quaternions(rng, n, tilt):
    """n unit quaternions: a yaw, then a tilt of up to `tilt` rad about a random horizontal axis."""
    yaw, lean, axis = rng.uniform(-math.pi, math.pi, n), rng.uniform(0, tilt, n), rng.uniform(-math.pi, math.pi, n)
    a = np.stack((np.zeros(n), np.zeros(n), np.sin(yaw / 2), np.cos(yaw / 2)), axis=1)
    b = np.stack((np.cos(axis) * np.sin(lean / 2), np.sin(axis) * np.sin(lean / 2), np.zeros(n), np.cos(lean / 2)),
                 axis=1)
    x1, y1, z1, w1 = b.T
    x2, y2, z2, w2 = a.T
    q = np.stack((w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                  w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2), axis=1)
    return q / np.linalg.norm(q, axis=1)[:, None]


def bodies(rng, n, spread=0.5):
    """n bottles on and around the belts: mostly upright and steady, some rocking, some fast."""
    positions = np.column_stack((rng.uniform(-spread, spread, (n, 2)), rng.uniform(0.03, 0.07, n)))
    velocities = rng.normal(0, 0.3, (n, 3)) * np.array([1, 1, 0.05])
    spins = rng.normal(0, 0.5, (n, 3)) * (rng.random((n, 1)) < 0.3)
    orientations = quaternions(rng, n, 0.03)
    return dict(positions=positions, velocities=velocities, spins=spins, orientations=orientations,
                radii=rng.uniform(0.02, 0.04, n), half_heights=rng.uniform(0.04, 0.07, n),
                masses=rng.uniform(0.02, 0.5, n), ahead=rng.integers(2, 9, n).astype(float))


def body(b, positions=None):
    """The bodies of `bodies` as the kernels take them (`positions`: in place of theirs)."""
    return T.Body(b["positions"] if positions is None else positions, b["orientations"], b["velocities"], b["spins"],
                  b["masses"], b["radii"], b["half_heights"])


def way(ahead, pulls, most=None):
    """Each body's look as the kernels take it."""
    return T.Way(ahead, np.zeros(len(ahead)) if most is None else most, pulls)


def fixed_table(c, h, cos, sin):
    """The fixed boxes as free transport's kernels take them (FreeTransport._fixed: the table and its grid)."""
    return T.with_grid(np.column_stack((c, h, cos, sin)))


def yawed_boxes(rng, m, spread=0.6):
    c = np.column_stack((rng.uniform(-spread, spread, (m, 2)), rng.uniform(0.0, 0.1, m)))
    h = np.column_stack((rng.uniform(0.002, 0.3, m), rng.uniform(0.002, 0.05, m), rng.uniform(0.02, 0.06, m)))
    yaw = rng.uniform(-math.pi, math.pi, m)
    return c, h, np.cos(yaw), np.sin(yaw)


# --- fields ---------------------------------------------------------------------------------
@SETTINGS
@given(seeds)
def test_the_field_a_point_lies_in_is_the_one_the_centre_lines_say(seed):
    rng = np.random.default_rng(seed)
    hall = rng.random() < 0.5
    fields = belts(rng, hall=hall)
    spread = 5.0 if hall else 1.5
    points = np.column_stack((rng.uniform(-spread, spread, (400, 2)), rng.uniform(-0.05, 0.15, 400)))
    assert (fields.which(points) == ref.field_of(fields, points)).all()


@SETTINGS
@given(seeds, st.booleans())
def test_a_belts_law_gives_the_velocity_change_its_docstring_states(seed, explicit):
    rng = np.random.default_rng(seed)
    fields = belts(rng, explicit)
    table = fields.table()
    for k in range(len(fields)):
        for _ in range(20):
            p, v, mass = rng.uniform(-1, 1, 2), rng.normal(0, 0.6, 2), rng.uniform(0.02, 0.5)
            dv = F.law_at(k, p[0], p[1], v[0], v[1], mass, DT, fields.explicit, table)
            expected = ref.law(fields, k, p, v, mass, DT)
            assert close(dv, expected, 1.0 + abs(fields.speeds[k]) + np.abs(v).max()), (k, dv, expected)
            spin, radius = rng.normal(0, 2.0), rng.uniform(0.02, 0.04)
            torque = F.spin_torque_at(k, spin, mass, radius, DT, fields.explicit, table)
            assert torque == ref.spin_torque(fields, k, spin, mass, radius, DT)   # the same operations


@SETTINGS
@given(seeds)
def test_a_ticks_drive_is_each_bodys_law_times_its_mass_over_dt(seed):
    rng = np.random.default_rng(seed)
    fields = belts(rng)
    b = bodies(rng, 40)
    field = fields.which(b["positions"])
    rows = np.arange(40)
    got = fields.drive_rows(rows, field, b["positions"], b["velocities"], b["masses"], b["radii"], b["spins"])
    on = rows[field >= 0]
    assert (got[0] == on).all() and (got[1] == b["positions"][on]).all()
    for j, n in enumerate(on):
        dv = ref.law(fields, field[n], b["positions"][n], b["velocities"][n], b["masses"][n], DT)
        scale = b["masses"][n] / DT
        assert close((got[2][j], got[3][j]), dv * scale, scale * (1.0 + np.abs(b["velocities"][n]).max()))
        assert got[4][j] == ref.spin_torque(fields, field[n], b["spins"][n, 2], b["masses"][n], b["radii"][n], DT)
    # `drive` (gripped anywhere: the base of a rocking bottle) is the same law at the given points.
    fx, fy, torques = fields.drive(field[on], b["positions"][on], b["velocities"][on], b["masses"][on],
                                   b["radii"][on], b["spins"][on, 2])
    assert (fx == got[2]).all() and (fy == got[3]).all() and (torques == got[4]).all()


# --- triggers and the watch ----------------------------------------------------------------------
@SETTINGS
@given(seeds)
def test_a_trigger_holds_the_upright_cylinders_that_overlap_its_box(seed):
    rng = np.random.default_rng(seed)
    b = bodies(rng, 30)
    c, h, cos, sin = yawed_boxes(rng, 8)
    got = G._overlap(b["positions"], b["radii"], b["half_heights"], c, h, cos, sin)
    assert (got == ref.inside(b["positions"], b["radii"], b["half_heights"], c, h, cos, sin)).all()


@SETTINGS
@given(seeds)
def test_a_ticks_occupancy_lists_who_entered_and_left_each_trigger(seed):
    """Near the origin, or spread over a hall (the kernel looks a body up in a grid of the boxes
    that never moved, hub/physics/grid.py: there some bodies stand near a box, most far from every
    box, some off the grid)."""
    rng = np.random.default_rng(seed)
    hall = rng.random() < 0.5
    b = bodies(rng, 30, 8.0 if hall else 0.5)
    c, h, cos, sin = yawed_boxes(rng, 6, 6.0 if hall else 0.6)
    if hall:
        near = rng.random(30) < 0.5
        b["positions"][near, :2] = c[rng.integers(0, 6, near.sum()), :2] + rng.uniform(-0.3, 0.3, (near.sum(), 2))
    before = rng.random((6, 30)) < 0.3
    moved = np.sort(rng.choice(30, rng.integers(0, 30), replace=False)).astype(np.int64)
    shifted = rng.random(6) < 0.3
    every = np.arange(30, dtype=np.int64)
    inside, stayed = before.copy(), np.zeros(6, bool)
    held, within = before.sum(axis=1), before.sum(axis=0)
    triggers = G.VolumeTriggers()
    for k in range(6):
        triggers.add(c[k], h[k], math.atan2(sin[k], cos[k]))
    triggers.boxes.cos[:], triggers.boxes.sin[:] = cos, sin
    for k in np.flatnonzero(shifted | (rng.random(6) < 0.2)):   # moved once, or this tick
        triggers.move(k, c[k])
    grid, still, mobile = triggers._grid(b["radii"])
    if rng.random() < 0.5:   # not every body in play; those that moved are
        every = np.union1d(moved, rng.choice(30, 20, replace=False)).astype(np.int64)
    changes = G._moved(inside, stayed, held, within, moved, every, shifted, b["positions"], b["radii"],
                       b["half_heights"], c, h, cos, sin, grid, still, mobile)
    now = ref.inside(b["positions"], b["radii"], b["half_heights"], c, h, cos, sin)
    looked = np.zeros((6, 30), bool)
    looked[:, moved] = True
    looked[np.ix_(shifted, every)] = True
    expected_inside = np.where(looked, now, before)
    assert (inside == expected_inside).all() and (stayed == expected_inside.any(axis=1)).all()
    assert (held == expected_inside.sum(axis=1)).all() and (within == expected_inside.sum(axis=0)).all()
    expected = []
    for t in range(6):
        flip = np.flatnonzero(expected_inside[t] != before[t])
        expected += [(t, n, 1) for n in flip if expected_inside[t, n]] + [(t, n, 0) for n in flip
                                                                          if not expected_inside[t, n]]
    assert [tuple(row) for row in changes.tolist()] == expected


@SETTINGS
@given(seeds, st.floats(0, 1))
def test_the_watch_passes_a_state_only_when_every_value_maps_into_its_box(seed, bad):
    rng = np.random.default_rng(seed)
    state = rng.uniform(-1.2, 1.2, (20, 13)) * (rng.random((20, 13)) < 0.97)
    if bad < 0.2:
        state[rng.integers(20), rng.integers(13)] = np.nan
    scale, shift = rng.uniform(0.5, 1.0, 13), rng.uniform(-0.1, 0.1, 13)
    assert W._within(state, scale, shift) == bool((np.abs(state * scale + shift) <= 1.0).all())


# --- rest ------------------------------------------------------------------------------------
@SETTINGS
@given(seeds)
def test_a_bodys_bound_holds_its_box_in_any_orientation_and_its_box_is_rests(seed):
    rng = np.random.default_rng(seed)
    b = bodies(rng, 30)
    q = quaternions(rng, 30, math.pi)    # any orientation: the bound must hold a bottle lying down too
    exact = R.boxes(q, b["radii"], b["half_heights"], b["velocities"], b["spins"], DT)
    for n in range(30):
        r, h, v, w = b["radii"][n], b["half_heights"][n], b["velocities"][n], b["spins"][n]
        assert R.turning(r, h, w) == ref.turning(r, h, w)
        reach = R.bound(r, h, v, w, DT, R.SHAPE_MARGIN + R.BREAKING)
        assert reach == ref.bound(r, h, v, w, DT, R.SHAPE_MARGIN + R.BREAKING)
        assert (exact[n] <= reach * (1 + TOL)).all()
        one = [R.extent(q[n], r, h, v, w, DT, axis, R.SHAPE_MARGIN + R.BREAKING) for axis in range(3)]
        assert close(one, exact[n])          # the rotation by products of q (rest.boxes) and written out


@SETTINGS
@given(seeds, st.integers(1, 3), st.integers(1, 20))
def test_still_bodies_are_counted_and_a_due_group_rests_together(seed, every, ticks):
    rng = np.random.default_rng(seed)
    n = 40
    b = bodies(rng, n)
    velocities = b["velocities"] * (rng.random((n, 1)) < 0.3) * 0.01
    spins = b["spins"] * (rng.random((n, 1)) < 0.3) * 0.1
    rows = np.sort(rng.choice(n, 30, replace=False)).astype(np.int64)
    field = rng.integers(-1, 3, 30).astype(np.int64)
    speeds = np.array([0.0, 0.3, 0.0])
    gripped, allowed = rng.random(n) < 0.1, rng.random(n) < 0.9
    still = rng.integers(0, 3 * ticks, n).astype(np.int64)
    args = (speeds, gripped, velocities, spins, allowed)
    counts = still.copy()
    got = R._candidates(rows, field, *args, counts, every, ticks, 2 * ticks, 15, 0.005 ** 2, 0.05 ** 2)
    expected, after = ref.candidates(rows, field, *args, still, every, ticks, 2 * ticks, 15, 0.005 ** 2, 0.05 ** 2)
    assert (got == expected).all() and (counts == after).all()


def resting_scene(rng):
    """A plant's worth of bodies, some resting in boxes (rest.boxes, fixed while they rest), the others awake."""
    b = bodies(rng, 50, spread=0.3)
    resting = rng.random(50) < 0.5
    rows = np.flatnonzero(resting)
    centres = b["positions"][rows]
    extents = R.boxes(b["orientations"][rows], b["radii"][rows], b["half_heights"][rows])
    return b, np.flatnonzero(~resting).astype(np.int64), centres, extents


@SETTINGS
@given(seeds)
def test_the_awake_bodies_near_resting_ones_and_the_islands_they_wake(seed):
    rng = np.random.default_rng(seed)
    b, awake, centres, extents = resting_scene(rng)
    state = (b["positions"], b["velocities"], b["spins"], b["radii"], b["half_heights"], DT, centres, extents)
    assert (R._within(awake, *state) == ref.within(awake, *state)).all()
    full = (b["positions"], b["orientations"], b["velocities"], b["spins"], b["radii"], b["half_heights"], DT,
            centres, extents)
    assert (R._seeds(awake, *full) == ref.seeds(awake, *full)).all()
    assert (R._woken(awake, *full) == ref.woken(awake, *full)).all()


# --- free transport: geometry ------------------------------------------------------------------
finite = st.floats(-0.5, 0.5, allow_nan=False)
sizes = st.floats(0.001, 0.3)


@settings(SETTINGS, max_examples=10 * SETTINGS.max_examples)
@given(finite, finite, finite, finite, sizes, sizes)
@example(-0.1, 0.0, 0.2, 0.0, 0.0025, 0.1)      # 0.2 m of way through a 5 mm gate: the ends 0.0975 m clear of it
def test_the_gap_from_a_bottles_way_to_a_box_is_the_exact_distance(a0, a1, d0, d1, hx, hy):
    """_segment_gap against the distance of a segment to a rectangle, 0 where the segment crosses it.
    Found so: the kernel took its ends' and the corners' distances only, and a way longer than the
    bottle is wide crossed a thin gate unseen (fixed in the kernel)."""
    got, expected = T._box_distance(a0, a1, hx, hy), ref.box_distance(a0, a1, hx, hy)
    if os.environ.get("NUMBA_DISABLE_JIT") == "1":   # the kernel's math.hypot is CPython's, correctly
        assert abs(got - expected) <= np.spacing(expected)   # rounded; numpy's and numba's are libm's
    else:
        assert got == expected
    got = T._segment_gap(a0, a1, d0, d1, hx, hy)
    expected = ref.segment_box_distance((a0, a1), (d0, d1), hx, hy)
    assert abs(got - expected) <= 1e-12, (got, expected)


@SETTINGS
@given(finite, finite, st.floats(-0.05, 0.05), st.floats(-0.05, 0.05), st.floats(-0.01, 0.01),
       st.floats(-0.01, 0.01), sizes, sizes, st.floats(0.02, 0.04))
def test_a_bottle_slides_along_a_box_only_beside_one_face_all_the_way(a0, a1, d0, d1, s0, s1, hx, hy, r):
    assert T._slides(a0, a1, d0, d1, s0, s1, hx, hy, r) == ref.slides((a0, a1), (d0, d1), (s0, s1), hx, hy, r)


@SETTINGS
@given(seeds)
def test_a_bottles_list_holds_the_fixed_boxes_within_reach_of_it(seed):
    rng = np.random.default_rng(seed)
    b = bodies(rng, 20)
    c, h, cos, sin = yawed_boxes(rng, int(rng.integers(1, 60)))
    size = int(rng.integers(1, 8))
    listed_at, near, count = np.zeros((20, 3)), np.zeros((20, size), np.int64), np.zeros(20, np.int64)
    for n in range(20):
        T._relist(n, body(b), T.Fixed(*fixed_table(c, h, cos, sin), listed_at, near, count))
        found, total = ref.listed(n, b["positions"], b["radii"], b["half_heights"], c, h, cos, sin, size)
        assert list(near[n, :len(found)]) == found and count[n] == total
        assert (listed_at[n] == b["positions"][n]).all()


@SETTINGS
@given(seeds, st.sampled_from([1.0, 2.0, float(T.LONG)]), st.floats(0.1, 3.0))
def test_a_bottles_way_reaches_a_fixed_box_as_against_every_box(seed, times, fast):
    """_fixed_hit, with its lists of nearby boxes made and kept as a run does, against every box.
    Found so: a list made LIST/2 back missed a box that a fast bottle's long look reached (fixed in
    the kernel: such a way is tested against every box)."""
    rng = np.random.default_rng(seed)
    fields, b = transport_scene(rng)
    b["velocities"] *= fast
    p, v = b["positions"], b["velocities"]
    c, h, cos, sin = yawed_boxes(rng, int(rng.integers(1, 30)))
    # Listed where each was up to LIST/2 back along its way, as the kernel relists no sooner.
    listed_at = p - np.column_stack((rng.uniform(-1, 1, (30, 2)) * (T.LIST / 2.0 / math.sqrt(2.0)), np.zeros(30)))
    near, count = np.zeros((30, T.NEAR), np.int64), np.zeros(30, np.int64)
    for n in range(30):
        T._relist(n, body(b, listed_at), T.Fixed(*fixed_table(c, h, cos, sin), listed_at.copy(), near, count))
    rows = np.arange(30, dtype=np.int64)
    got = T._fixed_hit(rows, times, DT, body(b), way(b["ahead"], b["pulls"]), fields.regions(),
                       T.Fixed(*fixed_table(c, h, cos, sin), listed_at, near, count))
    expected = ref.fixed_hit(fields, rows, times, DT, p, v, b["pulls"], b["ahead"], b["radii"], b["half_heights"],
                             c, h, cos, sin)
    assert (got == expected).all(), np.flatnonzero(got != expected)


# --- free transport: belts, pulls, the tick ------------------------------------------------------
def transport_scene(rng):
    fields = belts(rng)
    b = bodies(rng, 30)
    b["pulls"] = rng.normal(0, 0.01, (30, 2))
    return fields, b


@SETTINGS
@given(seeds, st.sampled_from([1.0, 2.0, float(T.LONG)]))
def test_whether_a_bottle_rides_on_its_belt_over_a_look(seed, times):
    rng = np.random.default_rng(seed)
    fields, b = transport_scene(rng)
    p, v, ahead = b["positions"], b["velocities"], b["ahead"]
    rows = np.arange(30, dtype=np.int64)
    now = fields.which(p)
    ok, still, stays = T._on_belt(rows, now, times, DT, body(b), way(ahead, b["pulls"]), fields.regions())
    for n in rows:
        k, m = now[n], ahead[n] * times
        there_point = p[n] + v[n] * (m * DT)
        there = ref.field_of(fields, there_point)[0]
        riding = k >= 0 and there >= 0 and fields.surfaces[k] == fields.surfaces[there]
        grow = m * (m + 1.0) / 2.0 * DT
        pulled = there_point + np.append(b["pulls"][n] * grow, 0.0)
        assert stays[n] == (riding and there == k and ref.field_of(fields, pulled)[0] == k)
        assert still[n] == (riding and ref.still_on(fields.speeds[k], v[n]))
        assert ok[n] == (riding and not still[n])
        assert T._belt(n, m, DT, body(b), way(ahead, b["pulls"]), fields.regions()) == ref.on_one_belt(
            fields, n, m, DT, p, v, b["pulls"])


@SETTINGS
@given(seeds)
def test_a_bodys_pull_is_its_belts_law_now_and_its_most_the_largest_on_its_way(seed):
    rng = np.random.default_rng(seed)
    fields, b = transport_scene(rng)
    p, v, ahead = b["positions"], b["velocities"], b["ahead"]
    rows = np.sort(rng.choice(30, 20, replace=False)).astype(np.int64)
    pulls, most = np.full((30, 2), 7.0), np.zeros(30)
    T._pulls(rows, DT, fields.explicit, body(b), way(ahead, pulls, most), fields.regions())
    for n in range(30):
        if n not in rows:
            assert (pulls[n] == 7.0).all() and most[n] == 0.0    # untouched
            continue
        sizes, now = [], None
        for times in (0.0, 1.0, 2.0, float(T.LONG)):
            point = p[n] + v[n] * (ahead[n] * times * DT)
            k = ref.field_of(fields, point)[0]
            dv = np.zeros(2) if k < 0 else ref.law(fields, k, point, v[n], b["masses"][n], DT)
            now = dv if now is None else now
            sizes.append(np.hypot(*dv))
        assert close(pulls[n], now, 1.0) and close(most[n], max(sizes), 1.0)


@SETTINGS
@given(seeds)
def test_a_free_bottle_moves_one_tick_by_its_belts_law_then_x_plus_v_dt(seed):
    rng = np.random.default_rng(seed)
    fields, b = transport_scene(rng)
    offsets = np.where(rng.random(30) < 0.3, rng.uniform(0.03, 0.06, 30), 0.0)
    rows = np.sort(rng.choice(30, 20, replace=False)).astype(np.int64)
    p, v = b["positions"].copy(), b["velocities"].copy()
    T._advance(rows, p, b["orientations"], v, b["masses"], offsets, DT, fields.explicit, *fields.regions())
    for n in range(30):
        if n not in rows:
            assert (p[n] == b["positions"][n]).all() and (v[n] == b["velocities"][n]).all()
            continue
        x, y, z, w = b["orientations"][n]
        axis = np.array([2 * (x * z + w * y), 2 * (y * z - w * x)])          # the body's up axis, in the plane
        grip = b["positions"][n, :2] - offsets[n] * axis
        k = ref.field_of(fields, b["positions"][n])[0]
        new = b["velocities"][n].copy()
        if k >= 0:
            new[:2] += ref.law(fields, k, grip, new, b["masses"][n], DT)
        assert close(v[n], new, 1.0) and v[n, 2] == b["velocities"][n, 2]
        assert close(p[n, :2], b["positions"][n, :2] + v[n, :2] * DT, 1.0) and p[n, 2] == b["positions"][n, 2]


# --- free transport: who touches whom ------------------------------------------------------------
@SETTINGS
@given(seeds, st.sampled_from([1.0, 2.0, float(T.LONG)]))
def test_the_bodies_a_free_bottle_could_touch_are_found_by_every_pair_alike(seed, times):
    """_touching's sweep along the longer axis against every pair (reference.touching)."""
    rng = np.random.default_rng(seed)
    fields = belts(rng)
    b = bodies(rng, 40, spread=0.4)
    b["velocities"] *= rng.random((40, 1)) < 0.7      # some at rest on their belts, lines setting off
    p, v = b["positions"], b["velocities"]
    free = rng.random(40) < 0.5
    joined = free | (rng.random(40) < 0.2)
    play = np.sort(rng.choice(40, 34, replace=False)).astype(np.int64)
    rows = play[rng.random(len(play)) < 0.5]
    against = np.zeros(40, bool)
    against[play[rng.random(len(play)) < 0.7]] = True
    pulls, most = np.zeros((40, 2)), np.zeros(40)
    T._pulls(play, DT, fields.explicit, body(b), way(b["ahead"], pulls, most), fields.regions())
    parts = (rng.uniform(-0.4, 0.4, (2, 3)), rng.uniform(0.005, 0.05, (2, 3)))
    got = T._touching(rows, play, times, DT, body(b), way(b["ahead"], pulls, most), free, joined, against,
                      fields.regions(), *parts)
    expected = ref.touching(fields, rows, play, times, DT, p, b["orientations"], v, b["spins"], b["radii"],
                            b["half_heights"], b["ahead"], most, pulls, free, joined, against, *parts)
    assert (got == expected).all(), np.flatnonzero(got != expected)


@SETTINGS
@given(seeds)
def test_a_train_grows_by_every_body_within_twice_the_margin_of_it(seed):
    rng = np.random.default_rng(seed)
    b = bodies(rng, 30, spread=0.15)
    pool = np.sort(rng.choice(30, 20, replace=False)).astype(np.int64)
    start = np.zeros(30, bool)
    start[rng.choice(30, 3, replace=False)] = True
    got = start.copy()
    T._grow(got, pool, body(b))
    p, r, h = b["positions"], b["radii"], b["half_heights"]
    apart = np.hypot(*(p[:, None, :2] - p[None, :, :2]).transpose(2, 0, 1)) - r[:, None] - r[None, :]
    near = (apart < 2.0 * R.SHAPE_MARGIN) & (np.abs(p[:, None, 2] - p[None, :, 2]) < h[:, None] + h[None, :])
    in_pool = np.zeros(30, bool)
    in_pool[pool] = True
    # Only members of the pool join, and they pass it on only from members of the pool.
    expected = start | ref.closure(start & in_pool, near & in_pool[:, None] & in_pool[None, :])
    assert (got == expected).all()
    extents, growth = rng.uniform(0, 0.1, (3, 3)), rng.uniform(0, 1, (3, 3))
    assert (T._grown(extents, growth, b["ahead"], pool, 2.0, DT)
            == extents + growth * (b["ahead"][pool].max() * 2.0 * DT)).all()


@pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="this is the run with the JIT off")
def test_the_physics_tests_pass_with_the_jit_off():
    """The kernels' Python is what a reader reads and a debugger steps; numba compiles a subset of
    Python with its own typing (integer division, wrap-around, bool arrays), where the two could
    part. So the physics tests run once more as plain Python — the kernel tests here with fewer
    examples, the worlds' tests as they are (about a minute on the shared machine: the plant runs
    of tests/physics are marked slow and left out)."""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", KERNEL_EXAMPLES="25")
    done = subprocess.run([sys.executable, "-m", "pytest", "tests/physics", "-q", "-x", "-m", "not slow",
                           "-p", "no:cacheprovider"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]


# --- free transport: the whole look and the leaving, in one call each ----------------------------------
def look_scene(rng):
    """A belt scene at a look: pulls taken afresh by _pulls (tested above) and fixed boxes listed
    where each bottle stands (_relist, tested above), so that both kernel and reference start there."""
    fields = belts(rng)
    b = bodies(rng, 30, spread=0.4)
    b["velocities"] *= rng.random((30, 1)) < 0.8
    b["positions"][:, 2] = rng.choice([0.0, 0.005], 30) + b["half_heights"] + rng.uniform(-0.008, 0.008, 30)
    b["play"] = np.sort(rng.choice(30, 26, replace=False)).astype(np.int64)
    b["pulls"], b["most"] = np.zeros((30, 2)), np.zeros(30)
    T._pulls(b["play"], DT, fields.explicit, body(b), way(b["ahead"], b["pulls"], b["most"]), fields.regions())
    c, h, cos, sin = yawed_boxes(rng, int(rng.integers(1, 12)))
    lists = (b["positions"].copy(), np.zeros((30, T.NEAR), np.int64), np.zeros(30, np.int64))
    for n in range(30):
        T._relist(n, body(b), T.Fixed(*fixed_table(c, h, cos, sin), *lists))
    parts = (rng.uniform(-0.4, 0.4, (1, 3)), rng.uniform(0.005, 0.05, (1, 3)), rng.uniform(0, 0.5, (1, 3)))
    return fields, b, parts, (c, h, cos, sin), lists


def kernel_state(b):
    """The scene's bodies and their look as the kernels take them, with pulls of their own to take afresh."""
    return body(b), way(b["ahead"], b["pulls"].copy(), b["most"].copy())


@SETTINGS
@given(seeds)
def test_which_awake_bottles_leave_the_engine(seed):
    rng = np.random.default_rng(seed)
    fields, b, parts, fixed, lists = look_scene(rng)
    free = rng.random(30) < 0.3
    joined = free | (rng.random(30) < 0.2)
    rows = b["play"][rng.random(len(b["play"])) < 0.6]
    bodies_, look = kernel_state(b)
    go, near = T._leave(rows, b["play"], b["play"], DT, bodies_, look, free, joined, fields.explicit, fields.regions(),
                        np.hstack(parts), T.Fixed(*fixed_table(*fixed), *lists))
    assert (look.most == b["most"]).all() and (look.pulls == b["pulls"]).all()   # taken afresh: the same again
    expected = ref.leave(fields, rows, DT, b, free, joined, parts, fixed)
    assert (go == expected[0]).all() and (near == expected[1]).all()


@SETTINGS
@given(seeds, st.booleans())
def test_a_look_at_the_free_bottles(seed, whole):
    rng = np.random.default_rng(seed)
    fields, b, parts, fixed, lists = look_scene(rng)
    free = np.zeros(30, bool)
    rows = b["play"][rng.random(len(b["play"])) < 0.5]
    free[rows] = True
    awake = np.setdiff1d(b["play"], rows)[: int(rng.integers(0, 10))].astype(np.int64)
    tick = 600
    clear = np.where(rng.random(30) < 0.5, tick + 30, tick).astype(np.int64)
    bodies_, look = kernel_state(b)
    got_clear = clear.copy()
    got = T._look(tick, whole, rows, b["play"], awake, b["play"], DT, bodies_, look, got_clear, free, fields.explicit,
                  fields.regions(), np.hstack(parts), T.Fixed(*fixed_table(*fixed), *lists))
    expected = ref.look(fields, tick, whole, rows, awake, DT, b, clear, free, parts, fixed)
    for name, a, e in zip(("due", "back", "ok", "still", "near", "now"), got, expected):
        assert (a == e).all(), (name, a, e)
    assert (got_clear == clear).all()
