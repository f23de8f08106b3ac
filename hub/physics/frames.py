"""Yaw-rotated boxes in the plant plane, shared by force fields and volume triggers."""
from __future__ import annotations

import numpy as np


class Boxes:
    """A growing set of boxes, each with a centre, half extents and a yaw about the vertical axis."""

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
