"""Belt force fields: the paper's control law F = k·m·(v_tar − v) over straight and curved regions, integrated exactly."""
from __future__ import annotations

import math

import numpy as np

from hub.physics.frames import Arc, CentreLines, Pose, Straight

GRIPS = ("surface", "along")
INTEGRATORS = ("exact", "explicit")
SPIN_AT_REST = 0.01   # rad/s: a bottle spinning slower than this about the vertical is left alone


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

    A field may be given a `limit` on the acceleration it gives (μ·g for a belt's friction
    coefficient μ): the velocity change of one tick is then cut to limit·dt in magnitude, keeping
    its direction. A bottle held back by a gate or a queue slides on the belt under the force
    friction can give, instead of the exact update's m·(v_belt − v)·(1 − e^(−k·dt))/dt, which
    grows with the belt speed and k without bound (k = 16/s, 0.5 m/s: 0.8 g).

    `integrator="explicit"` is the paper's own update, kept for comparison only (the speed-against-
    error report sets it beside the exact one): the force k·m·(v_tar − v) held over the tick, that
    is e^(−k·dt) replaced by its first-order 1 − k·dt in the same formulas. A velocity error then
    shrinks by the factor 1 − k·dt a tick: it overshoots once k·dt > 1, oscillates without decay at
    k·dt = 2 and grows beyond (k = 16/s: from 8 Hz down; k = 150/s at 60 Hz: ×1.5 a tick).

    A body inside several regions follows the one whose centre line is nearest (ties: the one
    declared first). Regions are half-open along their line, [0, length), so belts that are
    chained end to start hand a body over at one exact point.
    """

    def __init__(self, dt: float, integrator: str = "exact"):
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {', '.join(INTEGRATORS)}, not {integrator!r}")
        self.dt = dt
        self.explicit = integrator == "explicit"
        self.lines = CentreLines()
        self.half_widths = np.zeros(0)
        self.z_lo = np.zeros(0)
        self.z_hi = np.zeros(0)
        self.rates = np.zeros(0)       # k in 1/s, or the gain in N·s/m where not per_mass
        self.per_mass = np.zeros(0, bool)
        self.surface = np.zeros(0, bool)
        self.speeds = np.zeros(0)
        self.limits = np.zeros(0)      # most acceleration friction can give, m/s² (inf: none)
        self.surfaces = np.zeros(0)    # height of the belt's surface, m (its centre line's)
        self.limited = False           # some field has a finite limit

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
                   speed: float, *, grip: str = "surface", per_mass: bool = True, limit: float = math.inf) -> int:
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
        self.limits = np.append(self.limits, float(limit))
        self.surfaces = np.append(self.surfaces, float(line.start.z))
        self.limited = bool(np.isfinite(self.limits).any())
        return index

    def set_speed(self, field: int, speed: float) -> None:
        self.speeds[field] = speed

    def locate(self, points: np.ndarray):
        """For points (N,3): (field index or −1, along, across), each (N,), by the rule above."""
        n = len(points)
        if len(self) == 0 or n == 0:
            return np.full(n, -1), np.zeros(n), np.zeros(n)
        field, along, across = self._nearest(points)
        columns = np.arange(n)
        return field, along[np.maximum(field, 0), columns], across[np.maximum(field, 0), columns]

    def which(self, points: np.ndarray) -> np.ndarray:
        """The field index of each point (N,3), or −1: `locate` without the coordinates (every tick)."""
        if len(self) == 0 or len(points) == 0:
            return np.full(len(points), -1)
        return self._nearest(points)[0]

    def _nearest(self, points):
        along, across = self.lines.local(points)
        z = points[:, 2]
        distance = np.abs(across)
        inside = ((along >= 0.0) & (along < self.lines.length[:, None]) & (distance <= self.half_widths[:, None])
                  & (z >= self.z_lo[:, None]) & (z <= self.z_hi[:, None]))
        distance[~inside] = np.inf
        field = distance.argmin(axis=0)
        field[~inside[field, np.arange(len(points))]] = -1
        return field, along, across

    def forces(self, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray):
        """Return (body indices, forces (M,3)) for the bodies whose point lies in some field."""
        if len(self) == 0 or len(points) == 0:
            return np.zeros(0, int), np.zeros((0, 3))
        field = self.which(points)
        bodies = np.flatnonzero(field >= 0)
        return bodies, self.forces_at(field[bodies], points[bodies], velocities[bodies], masses[bodies])

    def forces_at(self, f: np.ndarray, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray) -> np.ndarray:
        """Forces (M,3) on M bodies driven by the fields `f`, each gripped at `points` moving at
        `velocities` (the centre of mass, or the base for a bottle that rocks): the velocity
        change of `changes_at` over one tick, times the mass."""
        if len(f) == 0:
            return np.zeros((0, 3))
        dvx, dvy = self.changes_at(f, points, velocities, masses)
        forces = np.zeros((len(f), 3))
        per_second = masses / self.dt
        forces[:, 0] = dvx * per_second
        forces[:, 1] = dvy * per_second
        return forces

    def changes_at(self, f: np.ndarray, points: np.ndarray, velocities: np.ndarray,
                   masses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The horizontal velocity changes (dvx, dvy), each (M,), that the law gives M bodies in
        one tick: what the engine adds to a driven body's velocity, and what free transport
        (transport.py) adds itself.

        Written component by component on (M,) arrays: this runs at every tick for every bottle
        on a belt, and for a hundred bottles numpy's per-call overhead, not the arithmetic, is
        the cost (half the time of the same law on (M,2) arrays with stacks and einsum)."""
        dt, lines = self.dt, self.lines
        px, py = points[:, 0], points[:, 1]
        vx, vy = velocities[:, 0], velocities[:, 1]
        per_mass = self.per_mass[f]
        rate = self.rates[f]
        if not per_mass.all():
            rate = np.where(per_mass, rate, rate / masses)
        keep = self._keep(rate)                     # e^(−k·dt): what is left of a velocity error
        speed = self.speeds[f]
        arc = lines.is_arc[f]
        surface = self.surface[f]
        tx, ty = lines.cos[f], lines.sin[f]         # direction of travel (the tangent on a curve)
        curved = arc.any()
        if curved:
            rx, ry = px - lines.origin[f, 0], py - lines.origin[f, 1]
            rho = np.maximum(np.hypot(rx, ry), 1e-12)
            turn = lines.turn[f]
            tx, ty = np.where(arc, -turn * ry / rho, tx), np.where(arc, turn * rx / rho, ty)
        if not surface.all():
            # along: only the component on the belt direction relaxes.
            u = (speed - (vx * tx + vy * ty)) * (1.0 - keep)
            along_x, along_y = u * tx, u * ty
        if surface.any():
            if not curved:
                # A straight belt's surface moves at speed·d: the relative velocity decays.
                gone = 1.0 - keep
                dvx, dvy = (speed * tx - vx) * gone, (speed * ty - vy) * gone
            else:
                # In the surface's frame: rotate by ω·dt about the centre (no rotation on a
                # straight); w carries a surface point where the surface moves it in one tick.
                radius = np.where(arc, lines.radius[f], 1.0)
                angle = np.where(arc, turn * speed / radius, 0.0) * dt
                c, s = np.cos(angle), np.sin(angle)
                wx = np.where(arc, (c * rx - s * ry - rx) / dt, speed * tx)
                wy = np.where(arc, (s * rx + c * ry - ry) / dt, speed * ty)
                qx, qy = (c * vx - s * vy - wx) * keep, (s * vx + c * vy - wy) * keep
                dvx, dvy = wx + c * qx - s * qy - vx, wy + s * qx + c * qy - vy
            if not surface.all():
                dvx, dvy = np.where(surface, dvx, along_x), np.where(surface, dvy, along_y)
        else:
            dvx, dvy = along_x, along_y
        if self.limited:
            # Friction gives at most μ·g: a bottle held back slides on the belt.
            size = np.hypot(dvx, dvy)
            scale = np.minimum(1.0, self.limits[f] * dt / np.maximum(size, 1e-300))
            dvx, dvy = dvx * scale, dvy * scale
        return dvx, dvy

    def _keep(self, rate: np.ndarray) -> np.ndarray:
        """What is left of a velocity error after one tick at `rate` (1/s): e^(−k·dt) exactly, or
        the explicit law's 1 − k·dt."""
        return 1.0 - rate * self.dt if self.explicit else np.exp(-rate * self.dt)

    def spin_torques(self, f: np.ndarray, spin: np.ndarray, masses: np.ndarray, radii: np.ndarray) -> np.ndarray:
        """Torques about the vertical (M,) with which a belt's surface grips the base of bottles
        spinning at `spin` (rad/s about z): the spin decays at the field's rate, exactly, like
        the relative velocity, and by at most what friction over the base gives, (2/3)·μ·m·g·r.
        Zero for `along` fields (the paper's law) and for a spin under SPIN_AT_REST.

        Without it a frictionless bottle keeps any spin: in a pressed queue the engine's contact
        normals, not all through the axis, spun a held bottle up to 15 rad/s in 0.3 s, and once
        released it wobbled over (10° and more, bottling_plant.yaml at 20 solver iterations).
        The spin is taken to zero even on a curve, whose surface turns at speed/R: a bottle's
        turn about its own axis shows nowhere (it is round, its sensors read positions), while
        a spinning bottle's slight rocking grows in the engine (the paper's loop, 50 s: tilt
        0.6° without spin, 1.6° spun with each curve)."""
        torques = np.zeros(len(f))
        on = self.surface[f] & (np.abs(spin) > SPIN_AT_REST)
        if not on.any():
            return torques
        rate = np.where(self.per_mass[f], self.rates[f], self.rates[f] / masses)
        inertia = masses * radii * radii / 2.0          # the homogeneous cylinder's, about its axis
        torque = -spin * (1.0 - self._keep(rate)) * inertia / self.dt
        if self.limited:
            most = (2.0 / 3.0) * self.limits[f] * masses * radii
            torque = np.clip(torque, -most, most)
        torques[on] = torque[on]
        return torques
