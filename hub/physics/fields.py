"""Belt force fields: the paper's control law F = k·m·P·(v_tar − v), integrated exactly."""
from __future__ import annotations

import math

import numpy as np

from .frames import Boxes


class ForceFields:
    """Box regions that drive the bodies whose centre of mass lies inside them.

    The paper's law is F = k·diag(d)·(v_tar − v). Here `k` is a rate in 1/s and the force is
    scaled by the body's mass (as friction would be), so every bottle reaches the belt speed in
    the same time whatever it weighs; the direction is projected with d·dᵀ, which equals
    diag(d) for an axis-aligned belt and stays right for any yaw. Instead of the explicit
    update, which diverges once k·dt > 2, each substep applies the force that moves the
    velocity along d exactly as the continuous law would over dt:
        u ← u_tar + (u − u_tar)·e^(−k·dt),  F = m·(Δu/dt)·d.
    A body inside several fields follows the one declared first.
    """

    def __init__(self, dt: float):
        self.dt = dt
        self.boxes = Boxes()
        self.directions = np.zeros((0, 3))
        self.decay = np.zeros(0)      # e^(−k·dt) per field
        self.speeds = np.zeros(0)

    def __len__(self) -> int:
        return len(self.boxes)

    def add(self, center, half_extents, yaw: float, k: float, speed: float) -> int:
        index = self.boxes.add(center, half_extents, yaw)
        self.directions = np.vstack([self.directions, [math.cos(yaw), math.sin(yaw), 0.0]])
        self.decay = np.append(self.decay, math.exp(-k * self.dt))
        self.speeds = np.append(self.speeds, float(speed))
        return index

    def set_speed(self, field: int, speed: float) -> None:
        self.speeds[field] = speed

    def forces(self, positions: np.ndarray, velocities: np.ndarray, masses: np.ndarray):
        """Return (body indices, forces (M,3)) for the bodies inside some field."""
        if len(self) == 0 or len(positions) == 0:
            return np.zeros(0, int), np.zeros((0, 3))
        local = self.boxes.local(positions)
        inside = np.all(np.abs(local) <= self.boxes.half_extents[:, None, :], axis=2)
        hit = inside.any(axis=0)
        bodies = np.nonzero(hit)[0]
        field = np.argmax(inside[:, bodies], axis=0)
        d = self.directions[field]
        u = np.einsum("ij,ij->i", velocities[bodies], d)
        target = self.speeds[field]
        du = (target - u) * (1.0 - self.decay[field])
        force = (masses[bodies] * du / self.dt)[:, None] * d
        return bodies, force
