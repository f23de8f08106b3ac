"""Belt regions: straight and arc fields, the nearest-centre-line rule, both grips, the unscaled law."""
import math

import numpy as np
import pytest

from hub.physics.fields import ForceFields
from hub.physics.frames import Arc, Pose, Straight

DT = 1.0 / 150


def field_with(*lines, k=16.0, speed=0.5, grip="surface", per_mass=True):
    fields = ForceFields(DT)
    for line in lines:
        fields.add_region(line, 0.05, -0.02, 0.3, k, speed, grip=grip, per_mass=per_mass)
    return fields


def integrate(fields, p, v, ticks, mass=0.05):
    """Semi-implicit Euler, as Bullet steps a free body: v += F/m·dt, then p += v·dt."""
    p, v = np.array([p], float), np.array([v], float)
    path = []
    for _ in range(ticks):
        bodies, forces = fields.forces(p, v, np.array([mass]))
        v = v + (forces / mass * DT if len(bodies) else 0.0)
        p = p + v * DT
        path.append(p[0].copy())
    return np.array(path), v[0]


def test_arc_geometry_a_left_quarter_turn_ends_heading_north():
    arc = Arc(Pose(0.0, 0.0, 0.1, 0.0), 0.5, math.pi / 2, +1)
    assert arc.centre == pytest.approx((0.0, 0.5))
    end = arc.end
    assert (end.x, end.y, end.z) == pytest.approx((0.5, 0.5, 0.1))
    assert end.yaw == pytest.approx(math.pi / 2)
    right = Arc(Pose(0.0, 0.0, 0.0, 0.0), 0.5, math.pi / 2, -1).end
    assert (right.x, right.y, right.yaw) == pytest.approx((0.5, -0.5, -math.pi / 2))


def test_locate_gives_the_arc_length_and_the_offset_to_the_left():
    arc = Arc(Pose(0.0, 0.0, 0.0, 0.0), 0.5, math.pi / 2, +1)
    fields = field_with(arc)
    # 30° into the turn, 2 cm towards the centre (which lies to the left of a left turn).
    a = math.radians(30)
    point = np.array([[0.48 * math.sin(a), 0.5 - 0.48 * math.cos(a), 0.05]])
    field, along, across = fields.locate(point)
    assert field.tolist() == [0]
    assert along[0] == pytest.approx(0.5 * a)
    assert across[0] == pytest.approx(0.02)
    outside = np.array([[-0.01, 0.0, 0.05], [0.5, 0.51, 0.05], [0.1, 0.0, 0.5]])  # before, after, above
    assert fields.locate(outside)[0].tolist() == [-1, -1, -1]


def test_chained_regions_hand_over_at_one_point():
    first = Straight(Pose(0.0, 0.0, 0.0, math.radians(30)), 1.0)
    second = Arc(first.end, 0.4, math.pi / 2, -1)
    fields = field_with(first, second)
    seam = np.array([[first.end.x, first.end.y, 0.05]])
    direction = np.array(first.end.direction)
    before, after = seam.copy(), seam.copy()
    before[0, :2] -= 1e-9 * direction
    after[0, :2] += 1e-9 * direction
    assert fields.locate(before)[0].tolist() == [0]
    assert fields.locate(after)[0].tolist() == [1]


def test_where_regions_overlap_the_nearest_centre_line_wins_not_the_first_declared():
    # A feeder joins a main belt from the side at 30° and runs on over it: where a bottle is
    # nearer the main belt's centre line, the main belt drives it.
    main = Straight(Pose(-1.0, 0.0, 0.0, 0.0), 2.0)
    yaw = math.radians(30)
    feeder = Straight(Pose(-0.2 * math.cos(yaw), -0.2 * math.sin(yaw), 0.0, yaw), 0.3)
    fields = field_with(feeder, main)
    points = np.array([[-0.03, -0.03, 0.05],    # 3 cm off the main line, 1.1 cm off the feeder's
                       [0.03, -0.004, 0.05]])   # 0.4 cm off the main line, 1.85 cm off the feeder's
    field, _, across = fields.locate(points)
    assert field.tolist() == [0, 1]
    assert across.tolist() == pytest.approx([0.5 * 0.03 - math.sqrt(0.75) * 0.03, -0.004])


def test_a_feeder_reaching_over_a_main_belt_drives_up_to_its_own_end():
    # A T: on the feeder's centre line the feeder is nearest until its region ends.
    main = Straight(Pose(-1.0, 0.0, 0.0, 0.0), 2.0)
    feeder = Straight(Pose(0.0, -1.0, 0.0, math.pi / 2), 0.98)   # its region ends 2 cm onto the main belt
    field, _, _ = field_with(main, feeder).locate(np.array([[0.0, -0.03, 0.05], [0.0, -0.01, 0.05]]))
    assert field.tolist() == [1, 0]


def test_surface_grip_carries_a_bottle_round_a_curve_on_its_circle():
    arc = Arc(Pose(0.0, 0.0, 0.0, 0.0), 0.4, math.pi, -1)
    fields = field_with(arc)
    centre = np.array(arc.centre)
    # Entering at belt speed on the centre line: once its velocity error (the tangent instead of
    # the chord of one tick) has decayed, it moves on one circle exactly, 0.1 mm inside.
    path, v = integrate(fields, (0.0, 0.0, 0.05), (0.5, 0.0, 0.0), 300)
    radii = np.hypot(*(path[:, :2] - centre).T)
    assert np.max(np.abs(radii - 0.4)) < 2e-4
    assert np.ptp(radii[200:]) < 1e-12
    omega = 0.5 / 0.4
    assert np.hypot(*v[:2]) == pytest.approx(2 * radii[-1] * math.sin(omega * DT / 2) / DT, rel=1e-9)
    # Put down at rest 2 cm off the centre line, it slips while it takes up speed (the slip turns
    # with the belt and carries it ~1 mm outwards), then turns with the surface at its radius.
    path, _ = integrate(fields, (0.0, -0.02, 0.05), (0.0, 0.0, 0.0), 300)
    radii = np.hypot(*(path[:, :2] - centre).T)
    assert np.max(np.abs(radii - 0.38)) < 2e-3
    assert np.ptp(radii[200:]) < 1e-9


def test_along_grip_leaves_the_sideways_velocity_so_a_curve_throws_the_bottle_outwards():
    arc = Arc(Pose(0.0, 0.0, 0.0, 0.0), 0.4, math.pi / 2, +1)
    path, _ = integrate(field_with(arc, grip="along"), (0.0, 0.0, 0.05), (0.5, 0.0, 0.0), 90)
    radii = np.hypot(*(path[:, :2] - np.array(arc.centre)).T)
    assert radii[-1] > 0.45          # no rail in this test: it has left the belt's 5 cm half width


def test_surface_grip_damps_sideways_velocity_on_a_straight():
    line = Straight(Pose(0.0, 0.0, 0.0, math.radians(20)), 5.0)
    sideways = 0.2 * np.array([-math.sin(math.radians(20)), math.cos(math.radians(20)), 0.0])
    _, v = integrate(field_with(line), (0.5, 0.2, 0.05), sideways, 150)
    along = np.array([math.cos(math.radians(20)), math.sin(math.radians(20))])
    assert v[:2] @ along == pytest.approx(0.5 * (1 - math.exp(-16.0)), rel=1e-9)
    assert abs(v[:2] @ np.array([-along[1], along[0]])) == pytest.approx(0.2 * math.exp(-16.0), rel=1e-9)


@pytest.mark.parametrize("grip", ["surface", "along"])
def test_exact_update_stays_stable_on_a_curve_at_a_large_k_dt(grip):
    arc = Arc(Pose(0.0, 0.0, 0.0, 0.0), 0.4, math.pi / 2, +1)
    path, v = integrate(field_with(arc, k=1000.0, grip=grip), (0.0, 0.0, 0.05), (-2.0, 0.0, 0.0), 20)  # k·dt ≈ 6.7
    rel = path[-1, :2] - np.array(arc.centre)
    tangent = np.array([-rel[1], rel[0]]) / np.hypot(*rel)
    assert np.all(np.isfinite(v)) and 0.0 < v[:2] @ tangent <= 0.5 + 1e-9


def test_the_papers_unscaled_law_drives_a_lighter_bottle_faster():
    fields = field_with(Straight(Pose(0.0, 0.0, 0.0, 0.0), 5.0), k=0.8, per_mass=False)
    velocities = {}
    for mass in (0.02, 0.08):
        _, v = integrate(fields, (0.1, 0.0, 0.05), (0.0, 0.0, 0.0), 15, mass=mass)
        velocities[mass] = v[0]
        assert v[0] == pytest.approx(0.5 * (1 - math.exp(-0.8 / mass * 15 * DT)), rel=1e-9)
    assert velocities[0.02] > velocities[0.08]


def test_a_bad_grip_is_named():
    with pytest.raises(ValueError, match="grip must be one of surface, along, not 'sideways'"):
        ForceFields(DT).add_region(Straight(Pose(0, 0, 0, 0), 1.0), 0.05, 0, 0.3, 16, 0.5, grip="sideways")
