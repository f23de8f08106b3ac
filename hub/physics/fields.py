"""Belt force fields: the paper's control law F = k·m·(v_tar − v) over straight and curved regions, integrated exactly."""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from hub.physics.frames import TAU, Arc, CentreLines, Pose, Straight
from hub.physics.grid import MARGIN, at_point, grid_of

GRIPS = ("surface", "along")
INTEGRATORS = ("exact", "explicit")
SPIN_AT_REST = 0.01   # rad/s: a bottle spinning slower than this about the vertical is left alone

# The columns of the regions' table (ForceFields.table), one row a region: what compiled loops
# take as one array — a compiled call pays for each array it is given, and the most after the
# engine's step has cleared the caches (30 arrays: 15 µs a call, one: 6).
# HEIGHT: the belt surface's height; STRAIGHT: straight with its law scaled by the mass (`straight_law`).
OX, OY, COS, SIN, ARC, TURN, RADIUS, ANGLE0, LENGTH, HALF_WIDTH, Z_LO, Z_HI, RATE, PER_MASS, SPEED, SURFACE, LIMIT, \
    HEIGHT, STRAIGHT = range(19)
COLUMNS = 19

#: The regions as `field_at` takes them: the table above and a grid of the regions' bounds
#: (hub/physics/grid.py), so that finding the region under a point looks at the few near it.
Regions = namedtuple("Regions", "table grid")


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

    STATE = ("speeds", "_table")   # hub/core/state.py: a belt's speed is all that changes while it runs

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
        self.straight_law = np.zeros(0, bool)
        # The regions as one array for compiled loops, made again when a region is added; the
        # arrays above are copied into it, so they change only through add_region and set_speed.
        self._table = self._regions = None

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
        # Two bottles on it follow one law that never lets their velocities part (transport.py):
        # not on an arc, nor with the gain per body, nor with the explicit law (unstable past k·dt = 2).
        self.straight_law = ~self.lines.is_arc & self.per_mass & (not self.explicit)
        self._table = self._regions = None
        return index

    def set_speed(self, field: int, speed: float) -> None:
        self.speeds[field] = speed
        if self._table is not None:
            self._table[field, SPEED] = speed

    def locate(self, points: np.ndarray):
        """For points (N,3): (field index or −1, along, across), each (N,), by the rule above."""
        n = len(points)
        if len(self) == 0 or n == 0:
            return np.full(n, -1), np.zeros(n), np.zeros(n)
        field = self.which(points)
        along, across = self.lines.local(points)
        columns = np.arange(n)
        return field, along[np.maximum(field, 0), columns], across[np.maximum(field, 0), columns]

    def which(self, points: np.ndarray) -> np.ndarray:
        """The field index of each point (N,3), or −1: `locate` without the coordinates (every tick,
        for every body that moves: one compiled loop, a fifth of the same test on numpy arrays)."""
        if len(self) == 0 or len(points) == 0:
            return np.full(len(points), -1)
        return _nearest(np.ascontiguousarray(points, float), *self.regions())

    def table(self) -> np.ndarray:
        """(regions, COLUMNS): every region's centre line, half width, heights and law, in the columns
        named above (booleans as 0 and 1) — made again only after a region is added; a speed is
        set in it as in `speeds`."""
        if self._table is None:
            lines, n = self.lines, len(self.lines)
            table = np.zeros((n, COLUMNS))
            if n:
                table[:, OX], table[:, OY] = lines.origin[:, 0], lines.origin[:, 1]
            for column, values in ((COS, lines.cos), (SIN, lines.sin), (ARC, lines.is_arc), (TURN, lines.turn),
                                   (RADIUS, lines.radius), (ANGLE0, lines.angle0), (LENGTH, lines.length),
                                   (HALF_WIDTH, self.half_widths), (Z_LO, self.z_lo), (Z_HI, self.z_hi),
                                   (RATE, self.rates), (PER_MASS, self.per_mass), (SPEED, self.speeds),
                                   (SURFACE, self.surface), (LIMIT, self.limits), (HEIGHT, self.surfaces),
                                   (STRAIGHT, self.straight_law)):
                table[:, column] = values
            self._table = table
        return self._table

    def regions(self) -> Regions:
        """The table with its grid (`Regions`), as `field_at` takes them. A region's bounds: a
        straight's rectangle, an arc's whole ring."""
        table = self.table()
        if self._regions is None or self._regions.table is not table:
            straight = table[:, ARC] == 0.0
            half = 0.5 * table[:, LENGTH] * straight
            reach = np.where(straight, 0.0, table[:, RADIUS]) + table[:, HALF_WIDTH] + MARGIN
            boxes = np.column_stack((table[:, OX] + half * table[:, COS], table[:, OY] + half * table[:, SIN],
                                     np.zeros(len(table)), np.where(straight, half + MARGIN, reach), reach,
                                     np.zeros(len(table)), np.where(straight, table[:, COS], 1.0),
                                     np.where(straight, table[:, SIN], 0.0)))
            self._regions = Regions(table, grid_of(boxes))
        return self._regions

    def forces(self, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray):
        """Return (body indices, forces (M,3)) for the bodies whose point lies in some field."""
        if len(self) == 0 or len(points) == 0:
            return np.zeros(0, int), np.zeros((0, 3))
        field = self.which(points)
        bodies = np.flatnonzero(field >= 0)
        return bodies, self.forces_at(field[bodies], points[bodies], velocities[bodies], masses[bodies])

    def forces_at(self, f: np.ndarray, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray) -> np.ndarray:
        """Forces (M,3) on M bodies driven by the fields `f`, each gripped at `points` moving at
        `velocities` (the centre of mass, or the base for a bottle that rocks): `drive`'s."""
        forces = np.zeros((len(f), 3))
        if len(f):
            forces[:, 0], forces[:, 1], _ = self.drive(f, points, velocities, masses, np.zeros(len(f)),
                                                       np.zeros(len(f)))
        return forces

    def drive(self, f: np.ndarray, points: np.ndarray, velocities: np.ndarray, masses: np.ndarray,
              radii: np.ndarray, spins: np.ndarray) -> tuple:
        """A tick's drive of M bodies on the fields `f` (Bottles.drive) in one compiled loop:
        (fx, fy, torques) — the velocity change the law gives each in one tick (`law_at`: what
        the engine adds to a driven body's velocity, and what free transport adds itself,
        transport.py), times the mass over dt; and the torques of `spin_torques`. This runs at
        every tick for every bottle on a belt in the engine, where numpy's per-call overhead, not
        the arithmetic, was the cost."""
        return _drive(np.asarray(f, np.int64), np.ascontiguousarray(points, float),
                      np.ascontiguousarray(velocities, float), np.ascontiguousarray(masses, float),
                      np.ascontiguousarray(radii, float), np.ascontiguousarray(spins, float), *self.laws())

    def drive_rows(self, rows: np.ndarray, field: np.ndarray, positions: np.ndarray, velocities: np.ndarray,
                   masses: np.ndarray, radii: np.ndarray, spins: np.ndarray) -> tuple:
        """`drive` for bodies gripped at their centre of mass, picked in the same compiled call:
        of `rows` (body rows, `field` the field under each, −1: none) those on a field, with
        (bodies, points, fx, fy, torques) — `spins` the bodies' angular velocities (N,3)."""
        return _drive_rows(np.asarray(rows, np.int64), np.asarray(field, np.int64), positions, velocities, masses,
                           radii, spins, *self.laws())

    def laws(self) -> tuple:
        """The belts' laws as compiled loops take them (`law_at`): dt, the explicit law or not, the table."""
        return (self.dt, self.explicit, self.table())

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
        return np.array([spin_torque_at(k, w, m, r, *self.laws())
                         for k, w, m, r in zip(np.asarray(f).tolist(), np.asarray(spin, float).tolist(),
                                               np.asarray(masses, float).tolist(), np.asarray(radii, float).tolist())])


@njit(cache=True)
def _nearest(points, table, grid):
    """Per point (N,3): `field_at` (the regions' arrays given plain: it runs every tick, see
    transport_kernels._advance)."""
    regions = Regions(table, grid)
    out = np.empty(points.shape[0], np.int64)
    for i in range(points.shape[0]):
        out[i] = field_at(points[i, 0], points[i, 1], points[i, 2], regions)
    return out


@njit(cache=True)
def field_at(x, y, z, regions):
    """The region the point (x, y, z) lies in whose centre line is nearest (the first on a tie),
    or −1 — CentreLines.local's coordinates, region by region, of the regions listed in the
    point's cell of the grid (the others' bounds do not reach it). `regions`: ForceFields.regions."""
    table, grid = regions
    best, found = np.inf, -1
    first, last = at_point(grid, x, y)
    for s in range(first, last):
        k = grid[s]
        if z < table[k, Z_LO] or z > table[k, Z_HI]:
            continue
        dx, dy = x - table[k, OX], y - table[k, OY]
        if table[k, ARC]:
            radius = table[k, RADIUS]
            across = table[k, TURN] * (radius - math.hypot(dx, dy))
            if abs(across) > table[k, HALF_WIDTH]:
                continue          # off the ring: no angle needed
            along = ((table[k, TURN] * (math.atan2(dy, dx) - table[k, ANGLE0])) % TAU) * radius
        else:
            along = table[k, COS] * dx + table[k, SIN] * dy
            across = table[k, COS] * dy - table[k, SIN] * dx
        distance = abs(across)
        if 0.0 <= along < table[k, LENGTH] and distance <= table[k, HALF_WIDTH] and distance < best:
            best, found = distance, k
    return found


@njit(cache=True)
def _drive(f, points, velocities, masses, radii, spins, dt, explicit, table):
    """ForceFields.drive, body by body."""
    n = f.shape[0]
    fx, fy, torques = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        fx[i], fy[i], torques[i] = _grip(f[i], points[i, 0], points[i, 1], velocities[i, 0], velocities[i, 1],
                                         masses[i], radii[i], spins[i], dt, explicit, table)
    return fx, fy, torques


@njit(cache=True)
def _drive_rows(rows, field, positions, velocities, masses, radii, spins, dt, explicit, table):
    """ForceFields.drive_rows, body by body."""
    count = 0
    for i in range(rows.shape[0]):
        count += field[i] >= 0
    bodies, points = np.empty(count, np.int64), np.empty((count, 3))
    fx, fy, torques = np.empty(count), np.empty(count), np.empty(count)
    j = 0
    for i in range(rows.shape[0]):
        if field[i] < 0:
            continue
        n = bodies[j] = rows[i]
        points[j, 0], points[j, 1], points[j, 2] = positions[n, 0], positions[n, 1], positions[n, 2]
        fx[j], fy[j], torques[j] = _grip(field[i], positions[n, 0], positions[n, 1], velocities[n, 0],
                                         velocities[n, 1], masses[n], radii[n], spins[n, 2], dt, explicit, table)
        j += 1
    return bodies, points, fx, fy, torques


@njit(cache=True)
def _grip(k, px, py, vx, vy, mass, radius, spin, dt, explicit, table):
    """Field `k`'s force (fx, fy) on one body gripped at (px, py) moving at (vx, vy), and its
    torque against the spin about the vertical."""
    x, y = law_at(k, px, py, vx, vy, mass, dt, explicit, table)
    per_second = mass / dt
    return x * per_second, y * per_second, spin_torque_at(k, spin, mass, radius, dt, explicit, table)


@njit(cache=True)
def spin_torque_at(k, spin, mass, radius, dt, explicit, table):
    """ForceFields.spin_torques for one body on field `k`."""
    if not table[k, SURFACE] or abs(spin) <= SPIN_AT_REST:
        return 0.0
    rate = table[k, RATE] if table[k, PER_MASS] else table[k, RATE] / mass
    keep = 1.0 - rate * dt if explicit else math.exp(-rate * dt)
    torque = -spin * (1.0 - keep) * (mass * radius * radius / 2.0) / dt   # the homogeneous cylinder's inertia
    most = (2.0 / 3.0) * table[k, LIMIT] * mass * radius
    return min(max(torque, -most), most)


@njit(cache=True)
def law_at(k, px, py, vx, vy, mass, dt, explicit, table):
    """The velocity change (dvx, dvy) field `k`'s law gives a body at (px, py) moving at (vx, vy)
    in one tick (ForceFields.drive, FreeTransport.advance); after `mass`: `ForceFields.laws`."""
    rate = table[k, RATE] if table[k, PER_MASS] else table[k, RATE] / mass
    keep = 1.0 - rate * dt if explicit else math.exp(-rate * dt)
    speed = table[k, SPEED]
    tx, ty = table[k, COS], table[k, SIN]   # direction of travel (the tangent on a curve)
    rx = ry = 0.0
    arc, turn = table[k, ARC], table[k, TURN]
    if arc:
        rx, ry = px - table[k, OX], py - table[k, OY]
        rho = max(math.hypot(rx, ry), 1e-12)
        tx, ty = -turn * ry / rho, turn * rx / rho
    if not table[k, SURFACE]:
        # along: only the component on the belt direction relaxes.
        u = (speed - (vx * tx + vy * ty)) * (1.0 - keep)
        x, y = u * tx, u * ty
    elif not arc:
        # A straight belt's surface moves at speed·d: the relative velocity decays.
        gone = 1.0 - keep
        x, y = (speed * tx - vx) * gone, (speed * ty - vy) * gone
    else:
        # In the surface's frame: rotate by ω·dt about the centre; w carries a surface point
        # where the surface moves it in one tick.
        angle = turn * speed / table[k, RADIUS] * dt
        c, s = math.cos(angle), math.sin(angle)
        wx, wy = (c * rx - s * ry - rx) / dt, (s * rx + c * ry - ry) / dt
        qx, qy = (c * vx - s * vy - wx) * keep, (s * vx + c * vy - wy) * keep
        x, y = wx + c * qx - s * qy - vx, wy + s * qx + c * qy - vy
    limit = table[k, LIMIT]
    if limit < np.inf:
        # Friction gives at most μ·g: a bottle held back slides on the belt.
        scale = min(1.0, limit * dt / max(math.hypot(x, y), 1e-300))
        x, y = x * scale, y * scale
    return x, y
