"""Support surfaces: touching belt floors at one height merge into one box; others stay apart."""
from hub.physics.supports import SupportArea, box, merge


def area(rect, z=0.0, thickness=0.02):
    return SupportArea(z, rect, thickness)


def test_touching_floors_merge_into_their_bounding_box():
    merged = merge([area((0, -0.06, 2, 0.06)), area((2, -0.06, 2.5, 0.5))])
    assert [m.rect for m in merged] == [(0, -0.06, 2.5, 0.5)]


def test_floors_apart_or_at_another_height_stay_separate():
    merged = merge([area((0, 0, 1, 1)), area((1.01, 0, 2, 1)), area((1, 0, 2, 1), z=0.1)])
    assert [(m.z, m.rect) for m in merged] == [(0.0, (0, 0, 1, 1)), (0.0, (1.01, 0, 2, 1)), (0.1, (1, 0, 2, 1))]


def test_a_grown_floor_absorbs_groups_it_now_touches():
    # The third area bridges the first two, which did not touch each other.
    merged = merge([area((0, 0, 1, 1)), area((2, 0, 3, 1)), area((0.5, 0, 2.5, 1), thickness=0.03)])
    assert [(m.rect, m.thickness) for m in merged] == [((0, 0, 3, 1), 0.03)]


def test_the_box_has_the_area_as_its_top_face():
    center, half = box(area((0, -1, 4, 1), z=0.5, thickness=0.02))
    assert center == (2, 0, 0.49) and half == (2, 1, 0.01)
