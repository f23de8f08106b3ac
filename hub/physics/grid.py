"""A grid of square cells over the floor listing the yawed boxes that reach each cell, so that a
test of one bottle looks at the boxes near it, not at every box of a hall: the fixed boxes free
transport keeps clear of (transport_kernels.py), the belts' regions a point lies in (fields.py),
the volume triggers a bottle may be inside (triggers.py).

A grid is one int64 array, so that compiled loops take it as one argument: the first cell's
indices (x, y), the cells across (x, y), the boxes, the cell's side in µm; then each box's first
and last cell (x, x, y, y); then where each cell's list begins (cells + 1); then the lists, each
in the boxes' order. A box is listed in every cell its bounding rectangle covers; a point outside
every listed cell of a box is outside the box."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

CELL = 0.25           # m: the side of a cell, at least
CELLS = 1 << 20       # cells a grid has at most: a larger floor gets larger cells
MARGIN = 1e-6         # m a box's bounds are widened by where a test must find every box it can (rounding)


@njit(cache=True)
def extents(cos, sin, hx, hy):
    """The half extents along x and y of the bounding rectangle of a box yawed by (cos, sin), of
    half extents (hx, hy): for numbers or arrays."""
    return np.abs(cos) * hx + np.abs(sin) * hy, np.abs(sin) * hx + np.abs(cos) * hy


def grid_of(boxes: np.ndarray) -> np.ndarray:
    """The grid of `boxes` (centre, half extents, cos and sin of the yaw: 8 columns, a row each)."""
    m = boxes.shape[0]
    if m == 0:
        return np.array([0, 0, 0, 0, 0, round(CELL * 1e6)], np.int64)
    cx, cy = boxes[:, 0], boxes[:, 1]
    ex, ey = extents(boxes[:, 6], boxes[:, 7], boxes[:, 3], boxes[:, 4])
    span = max(float((cx + ex).max() - (cx - ex).min()), float((cy + ey).max() - (cy - ey).min()))
    cell = max(CELL, span / math.sqrt(CELLS) * 1.01)
    um = round(cell * 1e6)
    cell = um / 1e6
    lo_x, hi_x = np.floor((cx - ex) / cell).astype(np.int64), np.floor((cx + ex) / cell).astype(np.int64)
    lo_y, hi_y = np.floor((cy - ey) / cell).astype(np.int64), np.floor((cy + ey) / cell).astype(np.int64)
    x0, y0 = int(lo_x.min()), int(lo_y.min())
    nx, ny = int(hi_x.max()) - x0 + 1, int(hi_y.max()) - y0 + 1
    ranges = np.column_stack((lo_x - x0, hi_x - x0, lo_y - y0, hi_y - y0))
    lists = [[] for _ in range(nx * ny)]
    for k, (ax, bx, ay, by) in enumerate(ranges.tolist()):
        for i in range(ax, bx + 1):
            for j in range(ay, by + 1):
                lists[j * nx + i].append(k)
    starts = np.cumsum([0] + [len(cell_list) for cell_list in lists])
    items = [k for cell_list in lists for k in cell_list]
    return np.concatenate(([x0, y0, nx, ny, m, um], ranges.ravel(), starts, items)).astype(np.int64)


@njit(cache=True)
def in_cells(grid, x_lo, x_hi, y_lo, y_hi, found):
    """The boxes listed in the cells the rectangle [x_lo, x_hi] × [y_lo, y_hi] covers, each once (at
    the first of its cells in the rectangle), into `found` in the boxes' order; returns how many
    (none for a rectangle off the grid or not a number)."""
    x0, y0, nx, ny, m, cell = grid[0], grid[1], grid[2], grid[3], grid[4], grid[5] / 1e6
    if nx == 0:
        return 0
    fx_lo, fx_hi = np.floor(x_lo / cell) - x0, np.floor(x_hi / cell) - x0   # floats: compared before made integers
    fy_lo, fy_hi = np.floor(y_lo / cell) - y0, np.floor(y_hi / cell) - y0
    if not (fx_hi >= 0.0 and fx_lo < nx and fy_hi >= 0.0 and fy_lo < ny):   # off the grid, or not a number
        return 0
    i_lo, i_hi = int(max(fx_lo, 0.0)), int(min(fx_hi, nx - 1.0))
    j_lo, j_hi = int(max(fy_lo, 0.0)), int(min(fy_hi, ny - 1.0))
    ranges, starts = 6, 6 + 4 * m
    items = starts + nx * ny + 1
    count = 0
    for j in range(j_lo, j_hi + 1):
        for i in range(i_lo, i_hi + 1):
            at = j * nx + i
            for s in range(grid[starts + at], grid[starts + at + 1]):
                k = grid[items + s]
                if max(grid[ranges + 4 * k], i_lo) == i and max(grid[ranges + 4 * k + 2], j_lo) == j:
                    found[count] = k
                    count += 1
    found[:count] = np.sort(found[:count])   # in the boxes' order, as a walk over every box finds them
    return count


@njit(cache=True)
def at_point(grid, x, y):
    """Where the list of the cell holding the point (x, y) lies in `grid`: `grid[first:last]` are
    its boxes, in their order (first == last off the grid, or for a point that is not a number)."""
    x0, y0, nx, ny, m, cell = grid[0], grid[1], grid[2], grid[3], grid[4], grid[5] / 1e6
    fx, fy = np.floor(x / cell) - x0, np.floor(y / cell) - y0   # floats: compared before made integers
    if not (0.0 <= fx < nx and 0.0 <= fy < ny):
        return 0, 0
    at = int(fy) * nx + int(fx)
    starts = 6 + 4 * m
    items = starts + nx * ny + 1
    return items + grid[starts + at], items + grid[starts + at + 1]
