"""Frames of the plant plane: yaw-rotated boxes, and belt centre lines (straight or arc) with along/across coordinates."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hub.core import state

TAU = 2.0 * math.pi


@state.value   # also a plain value inside a cache (modules/gate.py Holders)
class Boxes:
    """A growing set of boxes, each with a centre, half extents and a yaw about the vertical axis."""

    STATE = ("centers", "half_extents", "cos", "sin")   # a trigger's box follows a tool (hub/core/state.py)

    def __init__(self):
        self.centers = np.zeros((0, 3))
        self.half_extents = np.zeros((0, 3))
        self.cos = np.zeros(0)
        self.sin = np.zeros(0)

    def __len__(self) -> int:
        return len(self.cos)

    def add(self, center, half_extents, yaw: float) -> int:
        self.centers = np.vstack([self.centers, np.asarray(center, float)])
        self.half_extents = np.vstack([self.half_extents, np.asarray(half_extents, float)])
        self.cos = np.append(self.cos, np.cos(yaw))
        self.sin = np.append(self.sin, np.sin(yaw))
        return len(self.cos) - 1

    def local(self, points: np.ndarray) -> np.ndarray:
        """Points (N,3) in every box's frame: array (boxes, N, 3)."""
        d = points[None, :, :] - self.centers[:, None, :]
        c = self.cos[:, None]
        s = self.sin[:, None]
        out = np.empty_like(d)
        out[..., 0] = c * d[..., 0] + s * d[..., 1]
        out[..., 1] = -s * d[..., 0] + c * d[..., 1]
        out[..., 2] = d[..., 2]
        return out


@dataclass(frozen=True)
class Pose:
    """A point on a belt's surface and the heading of travel there (yaw, radians from +x)."""

    x: float
    y: float
    z: float
    yaw: float

    @property
    def direction(self) -> tuple[float, float]:
        return math.cos(self.yaw), math.sin(self.yaw)

    @property
    def left(self) -> tuple[float, float]:
        return -math.sin(self.yaw), math.cos(self.yaw)


@dataclass(frozen=True)
class Straight:
    """A straight centre line from `start` along its yaw."""

    start: Pose
    length: float

    def pose_at(self, s: float) -> Pose:
        dx, dy = self.start.direction
        return Pose(self.start.x + dx * s, self.start.y + dy * s, self.start.z, self.start.yaw)

    @property
    def end(self) -> Pose:
        return self.pose_at(self.length)

    def footprint(self, half_span: float) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the band `half_span` either side of the line."""
        lx, ly = self.start.left
        xs, ys = [], []
        for p in (self.start, self.end):
            for side in (1.0, -1.0):
                xs.append(p.x + side * half_span * lx)
                ys.append(p.y + side * half_span * ly)
        return min(xs), min(ys), max(xs), max(ys)


@dataclass(frozen=True)
class Arc:
    """A circular centre line from `start`, turning left (turn = +1, counter-clockwise) or right
    (turn = −1) by `sweep` radians on `radius`."""

    start: Pose
    radius: float
    sweep: float
    turn: int

    @property
    def centre(self) -> tuple[float, float]:
        lx, ly = self.start.left
        return self.start.x + self.turn * self.radius * lx, self.start.y + self.turn * self.radius * ly

    @property
    def start_angle(self) -> float:
        """Polar angle of `start` seen from the centre."""
        cx, cy = self.centre
        return math.atan2(self.start.y - cy, self.start.x - cx)

    @property
    def length(self) -> float:
        return self.radius * self.sweep

    def pose_at(self, s: float) -> Pose:
        cx, cy = self.centre
        phi = self.start_angle + self.turn * s / self.radius
        return Pose(cx + self.radius * math.cos(phi), cy + self.radius * math.sin(phi), self.start.z,
                    _wrap(self.start.yaw + self.turn * s / self.radius))

    @property
    def end(self) -> Pose:
        return self.pose_at(self.length)

    def footprint(self, half_span: float) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the annular sector `half_span` either side of the line."""
        cx, cy = self.centre
        a0 = self.start_angle
        # The extremes lie at the ends of the sector and at every axis direction it sweeps over.
        angles = [a0, a0 + self.turn * self.sweep]
        for k in range(-8, 9):
            a = k * math.pi / 2
            if 0.0 <= self.turn * (a - a0) <= self.sweep:
                angles.append(a)
        xs, ys = [], []
        for a in angles:
            for r in (self.radius - half_span, self.radius + half_span):
                xs.append(cx + r * math.cos(a))
                ys.append(cy + r * math.sin(a))
        return min(xs), min(ys), max(xs), max(ys)


def _wrap(angle: float) -> float:
    """An angle in (−π, π]."""
    return math.atan2(math.sin(angle), math.cos(angle))


class CentreLines:
    """A growing set of straight and arc centre lines, for numpy tests on many points at once.

    `local(points)` gives each point's coordinates in every line's frame: `along` (arc length
    from the line's start, m; for arcs measured on the centre radius), `across` (distance to the
    left of the line, m) — for arcs the angle along the sector comes with it.
    """

    def __init__(self):
        self.is_arc = np.zeros(0, bool)
        self.origin = np.zeros((0, 2))     # start point (straight) or centre (arc)
        self.cos = np.zeros(0)             # straight: direction; arc: unused
        self.sin = np.zeros(0)
        self.radius = np.zeros(0)          # 0 for straight lines
        self.turn = np.zeros(0)            # +1 left, −1 right, 0 straight
        self.angle0 = np.zeros(0)          # arc: polar angle of the start point
        self.length = np.zeros(0)          # along-extent, m
        self.arcs = np.zeros(0, int)       # rows of the arcs

    def __len__(self) -> int:
        return len(self.is_arc)

    def add(self, line: Straight | Arc) -> int:
        arc = isinstance(line, Arc)
        self.is_arc = np.append(self.is_arc, arc)
        self.origin = np.vstack([self.origin, line.centre if arc else (line.start.x, line.start.y)])
        self.cos = np.append(self.cos, math.cos(line.start.yaw))
        self.sin = np.append(self.sin, math.sin(line.start.yaw))
        self.radius = np.append(self.radius, line.radius if arc else 0.0)
        self.turn = np.append(self.turn, float(line.turn) if arc else 0.0)
        self.angle0 = np.append(self.angle0, line.start_angle if arc else 0.0)
        self.length = np.append(self.length, line.length)
        self.arcs = np.flatnonzero(self.is_arc)
        return len(self.is_arc) - 1

    def points(self, lines: np.ndarray, along: np.ndarray) -> np.ndarray:
        """Centre-line points (N, 2) at `along` metres on the lines numbered `lines` (N each)."""
        lines = np.asarray(lines, int)
        along = np.asarray(along, float)
        origin = self.origin[lines]
        direction = np.stack([self.cos[lines], self.sin[lines]], axis=1)
        straight = origin + along[:, None] * direction
        radius = np.where(self.is_arc[lines], self.radius[lines], 1.0)
        angle = self.angle0[lines] + self.turn[lines] * along / radius
        arc = origin + radius[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        return np.where(self.is_arc[lines][:, None], arc, straight)

    def local(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(along, across), each (lines, N), for points (N, 2 or 3)."""
        dx = points[:, 0] - self.origin[:, 0, None]
        dy = points[:, 1] - self.origin[:, 1, None]
        c, s = self.cos[:, None], self.sin[:, None]
        along = c * dx + s * dy
        across = c * dy - s * dx
        arcs = self.arcs
        if len(arcs):
            # Only the arcs' rows: angles for every line would double the cost of a plant's locate.
            ax, ay = dx[arcs], dy[arcs]
            turn, radius = self.turn[arcs, None], self.radius[arcs, None]
            along[arcs] = np.mod(turn * (np.arctan2(ay, ax) - self.angle0[arcs, None]), TAU) * radius
            across[arcs] = turn * (radius - np.hypot(ax, ay))
        return along, across


def base_points(positions, orientations, velocities, angular, offsets):
    """The centre of each upright body's bottom face and that point's velocity.

    Bodies have their axis on their local z and their centre of mass `offsets` above the base.
    """
    x, y, z, w = orientations.T
    axis = np.stack([2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)], axis=1)
    lever = -offsets[:, None] * axis
    wx, wy, wz = angular.T
    lx, ly, lz = lever.T
    # ω × lever, written out: np.cross costs more than the rest of this function together.
    spin = np.stack([wy * lz - wz * ly, wz * lx - wx * lz, wx * ly - wy * lx], axis=1)
    return positions + lever, velocities + spin
