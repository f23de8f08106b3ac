"""Support surfaces: the floor areas of belts that touch merge into one box, so no seam lies under a bottle.

Bullet collides a bottle riding ~2 mm deep in its support (at 150 Hz) with the end face of the
next box at every seam between two boxes, butted, overlapping or stepped: measured with one
bottle at 0.5 m/s over four 0.5 m boxes at 150 Hz, it tips over at the first seam (90°), while
one box of the same extent carries it with 0.18° of tilt. So belts declare the area they stand
on, and the world builds one box per group of areas at the same height that touch or overlap:
the box spans the group's bounding rectangle. Inside that rectangle a bottle that leaves a
belt finds floor rather than a drop; guard rails keep it on the belt.
"""
from __future__ import annotations

from dataclasses import dataclass

TOLERANCE = 1e-6   # m: areas closer than this touch; heights closer than this are one level


@dataclass(frozen=True)
class SupportArea:
    """A belt's floor: the rectangle (xmin, ymin, xmax, ymax) at surface height z, `thickness` deep."""

    z: float
    rect: tuple[float, float, float, float]
    thickness: float


def _touch(a, b) -> bool:
    return (a[0] <= b[2] + TOLERANCE and b[0] <= a[2] + TOLERANCE
            and a[1] <= b[3] + TOLERANCE and b[1] <= a[3] + TOLERANCE)


def _union(a, b):
    return min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3])


def merge(areas: list[SupportArea]) -> list[SupportArea]:
    """Groups of touching areas at one height, each as one area, in the order of their first member."""
    groups: list[tuple[int, SupportArea]] = []   # (index of the first member, merged area)
    for index, area in enumerate(areas):
        first, rect, thickness = index, area.rect, area.thickness
        # A grown rectangle may touch groups it did not touch before: absorb until none is left.
        while True:
            hit = next((i for i, (_, g) in enumerate(groups)
                        if abs(g.z - area.z) <= TOLERANCE and _touch(g.rect, rect)), None)
            if hit is None:
                break
            other_first, other = groups.pop(hit)
            first = min(first, other_first)
            rect, thickness = _union(other.rect, rect), max(other.thickness, thickness)
        groups.append((first, SupportArea(area.z, rect, thickness)))
    return [g for _, g in sorted(groups, key=lambda item: item[0])]


def box(area: SupportArea) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(centre, half extents) of the box whose top face is the area."""
    xmin, ymin, xmax, ymax = area.rect
    half = ((xmax - xmin) / 2, (ymax - ymin) / 2, area.thickness / 2)
    return ((xmin + xmax) / 2, (ymin + ymax) / 2, area.z - area.thickness / 2), half
