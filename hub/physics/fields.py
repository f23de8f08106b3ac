"""Belt force fields: the paper's control law F = k·m·(v_tar − v) over straight and curved regions, integrated exactly."""
from __future__ import annotations

import math

import numpy as np

from .frames import Arc, CentreLines, Pose, Straight

GRIPS = ("surface", "along")


class ForceFields:
    """Belt regions — a band either side of a straight or arc centre line, from `z_lo` to `z_hi` —
    that drive the bodies whose drive point lies inside them.

    The paper's law is F = k·diag(d)·(v_tar − v). Here `k` is a rate in 1/s and the force is
    scaled by the body's mass, as friction would be, so every bottle takes on the belt speed in
    the same time; a field made with `per_mass=False` uses the paper's unscaled law instead,
    F = gain·(v_tar − v) with the gain in N·s/m (rate gain/m: lighter bottles follow faster).

    What is driven is the field's *grip*:
    - `along` (the paper): only the velocity component along the belt direction d (the tangent
      on a curve) relaxes to the belt speed; a body keeps any sideways velocity, so on a curve
      it slides out to the outer rail and is turned by it.
    - `surface` (a real belt): the belt is a surface moving rigidly — a translation on a
      straight, a rotation ω = ±speed/R about the centre on a curve — and friction acts on
      both horizontal components of the velocity relative to that surface. The relative
      velocity decays as e^(−k·t) in the surface's own frame, so a bottle carried by a curve
      turns with it, at its own radius, without touching a rail.

    Instead of the explicit update, which diverges once k·dt > 2, each substep applies the force
    that reaches the exact solution after dt. For `along`: u ← u_tar + (u − u_tar)·e^(−k·dt) on
    u = v·d. For `surface`, with the rotation Q by ω·dt and the surface's step velocity
    w(p) = (Q − I)(p − c)/dt (the velocity that carries a surface point to where the surface
    moves it in one semi-implicit Euler step; speed·d on a straight): the relative velocity is
    r = Q·v − w(p) (that is v minus w at the previous position), and
    v ← w(p) + Q·r·e^(−k·dt). A body moving with the surface stays on its circle exactly.

    A body inside several regions follows the one whose centre line is nearest (ties: the one
    declared first). Regions are half-open along their line, [0, length), so belts that are
    chained end to start hand a body over at one exact point.
    """

    def __init__(self, dt: float):
        self.dt = dt
        self.lines = CentreLines()
        self.half_widths = np.zeros(0)
        self.z_lo = np.zeros(0)
        self.z_hi = np.zeros(0)
        self.rates = np.zeros(0)       # k in 1/s, or the gain in N·s/m where not per_mass
        self.per_mass = np.zeros(0, bool)
        self.surface = np.zeros(0, bool)
        self.speeds = np.zeros(0)

    def __len__(self) -> int:
        return len(self.lines)

    def add(self, center, half_extents, yaw: float, k: float, speed: float, *, grip: str = "along",
            per_mass: bool = True) -> int:
        """A straight region given as a yawed box (centre, half extents along/across/up)."""
        hx, hy, hz = half_extents
        start = Pose(center[0] - hx * math.cos(yaw), center[1] - hx * math.sin(yaw), center[2], yaw)
        return self.add_region(Straight(start, 2.0 * hx), hy, center[2] - hz, center[2] + hz, k, speed,
                               grip=grip, per_mass=per_mass)

    def add_region(self, line: Straight | Arc, half_width: float, z_lo: float, z_hi: float, k: float,
                   speed: float, *, grip: str = "surface", per_mass: bool = True) -> int:
        if grip not in GRIPS:
            raise ValueError(f"grip must be one of {', '.join(GRIPS)}, not {grip!r}")
        index = self.lines.add(line)
        self.half_widths = np.append(self.half_widths, half_width)
        self.z_lo = np.append(self.z_lo, z_lo)
        self.z_hi = np.append(self.z_hi, z_hi)
        self.rates = np.append(self.rates, float(k))
        self.per_mass = np.append(self.per_mass, per_mass)
        self.surface = np.append(self.surface, grip == "surface")
        self.speeds = np.append(self.speeds, float(speed))
        return index

    def set_speed(self, field: int, speed: float) -> None:
        self.speeds[field] = speed

    def locate(self, points: np.ndarray):
        """For points (N,3): (field index or −1, along, across), each (N,), by the rule above."""
        n = len(points)
        if len(self) == 0 or n == 0:
            return np.full(n, -1), np.zeros(n), np.zeros(n)
        along, across = self.lines.local(points)
        z = points[None, :, 2]
        inside = ((along >= 0.0) & (along < self.lines.length[:, None])
                  & (np.abs(across) <= self.half_widths[:, None])
                  & (z >= self.z_lo[:, None]) & (z <= self.z_hi[:, None]))
        distance = np.where(inside, np.abs(across), np.inf)
        field = np.argmin(distance, axis=0)
        columns = np.arange(n)
        hit = inside[field, columns]
        return np.where(hit, field, -1), along[field, columns], across[field, columns]

    def forces(self, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray):
        """Return (body indices, forces (M,3)) for the bodies whose point lies in some field."""
        if len(self) == 0 or len(points) == 0:
            return np.zeros(0, int), np.zeros((0, 3))
        field, _, _ = self.locate(points)
        bodies = np.nonzero(field >= 0)[0]
        return bodies, self.forces_at(field[bodies], points[bodies], velocities[bodies], masses[bodies])

    def forces_at(self, f: np.ndarray, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray) -> np.ndarray:
        """Forces (M,3) on M bodies driven by the fields `f`, each gripped at `points` moving at
        `velocities` (the centre of mass, or the base for a bottle that rocks)."""
        p, v, m = points[:, :2], velocities[:, :2], masses
        dt, lines = self.dt, self.lines
        per_mass = self.per_mass[f]
        rate = self.rates[f] if per_mass.all() else np.where(per_mass, self.rates[f], self.rates[f] / m)
        keep = np.exp(-rate * dt)[:, None]          # e^(−k·dt): what is left of a velocity error
        speed = self.speeds[f]
        arc = lines.is_arc[f]
        direction = np.stack([lines.cos[f], lines.sin[f]], axis=1)
        if arc.any():
            rel = p - lines.origin[f]
            rho = np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-12)
            tangent = lines.turn[f, None] * np.stack([-rel[:, 1], rel[:, 0]], axis=1) / rho[:, None]
            direction = np.where(arc[:, None], tangent, direction)
        surface = self.surface[f]
        if surface.all():
            dv = self._surface(f, p, v, speed, direction, keep)
        elif not surface.any():
            dv = _along(v, speed, direction, keep)
        else:
            dv, along = np.empty_like(v), ~surface
            dv[along] = _along(v[along], speed[along], direction[along], keep[along])
            dv[surface] = self._surface(f[surface], p[surface], v[surface], speed[surface], direction[surface],
                                        keep[surface])
        forces = np.zeros((len(f), 3))
        forces[:, :2] = m[:, None] * dv / dt
        return forces

    def _surface(self, f, p, v, speed, direction, keep):
        """Velocity change for the surface grip: the velocity relative to the moving surface
        decays in the surface's own frame."""
        dt, lines = self.dt, self.lines
        carried = speed[:, None] * direction      # a straight belt's surface velocity
        arc = lines.is_arc[f]
        if not arc.any():
            return (carried - v) * (1.0 - keep)
        radius = np.where(arc, lines.radius[f], 1.0)
        angle = np.where(arc, lines.turn[f] * speed / radius, 0.0) * dt
        c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]

        def rotate(x):
            return np.concatenate([c * x[:, :1] - s * x[:, 1:], s * x[:, :1] + c * x[:, 1:]], axis=1)

        rel = p - lines.origin[f]
        # On a curve: the velocity that carries a surface point where the surface moves it in one tick.
        carried = np.where(arc[:, None], (rotate(rel) - rel) / dt, carried)
        return carried + rotate(rotate(v) - carried) * keep - v


def _along(v, speed, direction, keep):
    """Velocity change for the along grip: only the component on the belt direction relaxes."""
    u = np.einsum("ij,ij->i", v, direction)
    return ((speed - u)[:, None] * (1.0 - keep)) * direction
