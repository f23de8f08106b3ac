"""The floor's grid of boxes (hub/physics/grid.py): what a point or a rectangle finds in it. The
lookups against every box on random scenes are in test_kernels.py (the triggers, the regions, the
fixed boxes); these are the edges: the off-grid, the infinite and what is not a number, which the
JIT-off run of tests/physics takes through plain Python as well."""
import numpy as np

from hub.physics.grid import at_point, grid_of, in_cells

# A box across the origin, another about (1, 1) turned by 90°: centre, half extents, cos and sin of the yaw.
BOXES = np.array([[0.0, 0.0, 0.0, 0.2, 0.1, 0.1, 1.0, 0.0], [1.0, 1.0, 0.0, 0.1, 0.1, 0.1, 0.0, 1.0]])


def found(grid, *rectangle) -> list[int]:
    out = np.empty(len(BOXES), np.int64)
    return out[:in_cells(grid, *rectangle, out)].tolist()


def listed(grid, x, y) -> list[int]:
    first, last = at_point(grid, x, y)
    return grid[first:last].tolist()


def test_a_point_finds_the_boxes_of_its_cell_and_off_the_grid_none():
    grid = grid_of(BOXES)
    assert listed(grid, 0.0, 0.0) == [0] and listed(grid, 1.0, 1.0) == [1]
    assert listed(grid, -5.0, 0.0) == listed(grid, 0.0, 7.0) == []


def test_a_rectangle_finds_each_box_it_reaches_once_in_their_order():
    grid = grid_of(BOXES)
    assert found(grid, -1.0, 2.0, -1.0, 2.0) == [0, 1]
    assert found(grid, 0.9, 1.1, 0.9, 1.1) == [1]
    assert found(grid, 5.0, 6.0, 5.0, 6.0) == []


def test_what_is_not_a_number_is_off_the_grid_and_the_infinite_reaches_every_box():
    grid = grid_of(BOXES)
    for x, y in ((np.nan, 0.0), (0.0, np.nan), (np.inf, 0.0), (0.0, -np.inf)):
        assert listed(grid, x, y) == []
    assert found(grid, np.nan, np.nan, 0.0, 0.0) == found(grid, 0.0, 0.0, np.nan, 1.0) == []
    assert found(grid, -np.inf, np.inf, -np.inf, np.inf) == [0, 1]


def test_a_grid_without_boxes_finds_nothing():
    grid = grid_of(np.zeros((0, 8)))
    assert listed(grid, 0.0, 0.0) == [] and found(grid, -1.0, 1.0, -1.0, 1.0) == []
