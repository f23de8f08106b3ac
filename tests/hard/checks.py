"""What the hard cases measure at every communication point, and bounds stated against what was measured."""
from __future__ import annotations

import math
import resource
from dataclasses import dataclass, field

import numpy as np

from hub.physics.parking import PARKED
from modules.gate import Blocker, depths


@dataclass(frozen=True)
class Bound:
    """One stated bound: `measured` must not exceed `limit` (`at_least`: must not fall below it)."""

    name: str
    limit: float
    measured: float
    unit: str = ""
    at_least: bool = False

    @property
    def passed(self) -> bool:
        if math.isnan(self.measured):
            return False
        return self.measured >= self.limit if self.at_least else self.measured <= self.limit

    def line(self) -> str:
        relation = "≥" if self.at_least else "≤"
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.name} {self.measured:.4g}{unit} (bound {relation} {self.limit:g}{unit})"


@dataclass
class Result:
    """One hard case run: what it simulated, what it cost, each bound with its measured value."""

    name: str
    simulated: float = 0.0
    wall: float = 0.0
    bounds: list[Bound] = field(default_factory=list)
    error: str = ""          # a run that the engine or the physics watch stopped

    def bound(self, name: str, limit: float, measured: float, unit: str = "", at_least: bool = False) -> None:
        self.bounds.append(Bound(name, limit, float(measured), unit, at_least))

    @property
    def passed(self) -> bool:
        return not self.error and all(b.passed for b in self.bounds)

    def failures(self) -> list[str]:
        return ([self.error] if self.error else []) + [b.line() for b in self.bounds if not b.passed]

    def check(self) -> None:
        """Raise AssertionError naming every broken bound (pytest's view of a case)."""
        assert self.passed, f"{self.name}: " + "; ".join(self.failures())

    def as_dict(self) -> dict:
        return {"name": self.name, "simulated_seconds": self.simulated, "wall_seconds": round(self.wall, 3),
                "passed": self.passed, "error": self.error,
                "bounds": [{"name": b.name, "limit": b.limit,
                            "measured": b.measured if math.isfinite(b.measured) else str(b.measured),
                            "unit": b.unit, "relation": ">=" if b.at_least else "<=", "passed": b.passed}
                           for b in self.bounds]}


COLUMNS = ("speed", "tilt", "overlap", "gate", "rail", "base", "energy", "nonfinite")


class Checker:
    """An observer of a run: at every communication point, over the bottles in play (not parked,
    not held by an arm; `only`: those labels), the worst of each figure, kept as a time series:

    - `speed`: the fastest horizontal speed, m/s; `tilt`: the largest angle from the plumb line, °;
    - `overlap`: the deepest bottle into another, m — radii minus the horizontal distance of the
      centres, where their heights overlap (bottles touch at their contact ring, at the centre
      of mass: hub/physics/world.py RING);
    - `gate`: the deepest bottle into a closed gate of `gates` (modules/gate.py `depths`), m;
    - `rail`: the deepest bottle into a guard rail of the straight lanes `lanes`, (y, half width)
      of belts along x, each bottle judged by the nearest lane's centre line, m;
    - `base`: the lowest base (centre height minus half height), m: a fallen bottle is below 0;
    - `energy`: their kinetic energy, J: translation, and rotation as homogeneous cylinders;
    - `nonfinite`: how many have a state that is not finite.

    `crossings` lists (time, gate, bottle) for each bottle whose axis went from one side of a
    closed one-box gate of `gates` to the other between two points while it stood across its lane.

    With `keep=False` only the extremes over the run are kept, not the series (an hour of the
    bottling plant whose memory is judged: 180 000 points would be 11 MB of it).
    """

    def __init__(self, world, *, gates: dict[str, Blocker] | None = None, lanes=(), pairs: bool = True,
                 only=None, keep: bool = True):
        self.world = world
        self.gates = dict(gates or {})
        self.lanes = np.array(lanes, float).reshape(-1, 2)
        self.pairs = pairs
        self.only = None if only is None else np.array([world.labels.index(n) for n in only], int)
        self.keep = keep
        self.ticks: list[int] = []
        self._rows: list[tuple] = []
        self._extremes = Extremes()
        self.crossings: list[tuple[float, str, str]] = []
        self._sides = {name: np.zeros(len(world.labels)) for name in self.gates}   # −1, +1; 0: unknown

    def observe(self, tick: int, signals=None, events=()) -> None:
        w = self.world
        rows = w.bodies.in_play_rows()
        if self.only is not None:
            rows = rows[np.isin(rows, self.only)]
        held = w.robots.held_rows()
        if held:
            rows = rows[~np.isin(rows, held)]
        # A bottle a source put out at this point is read from the next tick on: still off stage.
        rows = rows[w.positions[rows, 2] > PARKED[2] / 2]
        if not len(rows):
            self._keep(tick, (0.0, 0.0, -math.inf, -math.inf, -math.inf, math.inf, 0.0, 0))
            return
        p, q, v, spin = w.positions[rows], w.orientations[rows], w.velocities[rows], w.angular_velocities[rows]
        m, r, h = w.masses[rows], w.radii[rows], w.half_heights[rows]
        finite = np.isfinite(p).all(1) & np.isfinite(q).all(1) & np.isfinite(v).all(1) & np.isfinite(spin).all(1)
        speed = float(np.hypot(v[:, 0], v[:, 1]).max())
        up = np.clip(1.0 - 2.0 * (q[:, 0] ** 2 + q[:, 1] ** 2), -1.0, 1.0)
        tilt = math.degrees(float(np.arccos(up).max()))
        overlap = -math.inf
        if self.pairs and len(rows) > 1:
            d = np.hypot(p[:, None, 0] - p[None, :, 0], p[:, None, 1] - p[None, :, 1])
            level = np.abs(p[:, None, 2] - p[None, :, 2]) < h[:, None] + h[None, :]
            reach = np.where(level, r[:, None] + r[None, :] - d, -math.inf)
            np.fill_diagonal(reach, -math.inf)
            overlap = float(reach.max())
        gate = -math.inf
        for name, blocker in self.gates.items():
            if blocker.solid:
                gate = max(gate, float(depths(blocker.boxes, p, r, h).max()))
            if len(blocker.boxes) == 1:
                self._cross(tick, name, blocker, rows, p, r, h)
        rail = -math.inf
        if len(self.lanes):
            offset = np.abs(p[:, None, 1] - self.lanes[None, :, 0])
            nearest = offset.argmin(1)
            rail = float((offset[np.arange(len(rows)), nearest] + r - self.lanes[nearest, 1]).max())
        base = float((p[:, 2] - h).min())
        # A homogeneous cylinder: m·r²/2 about its axis, m·(3r² + 4h²)/12 across it (h: half height).
        across, axis = m * (3 * r * r + 4 * h * h) / 12, m * r * r / 2
        energy = float(0.5 * (m * (v * v).sum(1)).sum()
                       + 0.5 * (across * (spin[:, 0] ** 2 + spin[:, 1] ** 2) + axis * spin[:, 2] ** 2).sum())
        self._keep(tick, (speed, tilt, overlap, gate, rail, base, energy, int((~finite).sum())))

    def _keep(self, tick: int, row: tuple) -> None:
        if self.keep:
            self.ticks.append(tick)
            self._rows.append(row)
        else:
            self._extremes.add(row)

    def _cross(self, tick, name, blocker, rows, p, r, h) -> None:
        local = blocker.boxes.local(p)[0]
        e = blocker.boxes.half_extents[0]
        side = np.where(local[:, 0] > 0, 1.0, -1.0)
        across = (np.abs(local[:, 1]) < e[1] + r) & (np.abs(local[:, 2]) < e[2] + h)
        before = self._sides[name][rows]
        crossed = across & (before != 0) & (side != before)
        for n in rows[crossed].tolist():
            self.crossings.append((tick / self.world.rate, name, self.world.labels[n]))
        # Only a closed gate keeps a side: an open one lets bottles through, and one that closes
        # starts afresh from where each bottle stands then.
        self._sides[name][rows] = side if blocker.solid else 0.0

    def close(self, reason: str) -> None:
        """The series stay readable."""

    def series(self) -> Series | Extremes:
        if not self.keep:
            return self._extremes
        data = np.array(self._rows, float).reshape(-1, len(COLUMNS))
        return Series(np.array(self.ticks, float) / self.world.rate, {c: data[:, i] for i, c in enumerate(COLUMNS)})


class Track:
    """An observer: time, position, velocity and tilt (°) of some bottles at every point they are in play."""

    def __init__(self, world, labels):
        self.world = world
        self.rows = {name: world.labels.index(name) for name in labels}
        self.samples: dict[str, list] = {name: [] for name in labels}

    def observe(self, tick: int, signals=None, events=()) -> None:
        w = self.world
        for name, n in self.rows.items():
            if not w.is_parked(n):
                self.samples[name].append((tick / w.rate, *w.positions[n], *w.velocities[n], math.degrees(w.tilt(n))))

    def close(self, reason: str) -> None:
        """The samples stay readable."""

    def of(self, name: str) -> np.ndarray:
        """(T, 8): t, x, y, z, vx, vy, vz, tilt."""
        return np.array(self.samples[name], float).reshape(-1, 8)


@dataclass
class Series:
    time: np.ndarray
    columns: dict[str, np.ndarray]

    def window(self, since: float = -math.inf, until: float = math.inf) -> np.ndarray:
        return (self.time >= since - 1e-9) & (self.time <= until + 1e-9)

    def max(self, column: str, since: float = -math.inf, until: float = math.inf) -> float:
        values = self.columns[column][self.window(since, until)]
        return float(values.max()) if len(values) else -math.inf

    def min(self, column: str, since: float = -math.inf, until: float = math.inf) -> float:
        values = self.columns[column][self.window(since, until)]
        return float(values.min()) if len(values) else math.inf

    def at(self, column: str, time: float) -> float:
        """The value at the last point at or before `time`."""
        i = int(np.searchsorted(self.time, time + 1e-9, side="right")) - 1
        return float(self.columns[column][max(i, 0)])

    def growth(self, column: str, since: float = -math.inf, until: float = math.inf) -> float:
        """The largest rise of a column from one point to the next within the window."""
        values = self.columns[column][self.window(since, until)]
        return float(np.diff(values).max()) if len(values) > 1 else 0.0


class Extremes:
    """What a Checker with `keep=False` holds: each column's largest and smallest value over the run."""

    def __init__(self):
        self.high = np.full(len(COLUMNS), -math.inf)
        self.low = np.full(len(COLUMNS), math.inf)

    def add(self, row: tuple) -> None:
        values = np.array(row, float)
        np.maximum(self.high, values, out=self.high)
        np.minimum(self.low, values, out=self.low)

    def max(self, column: str, since: float = -math.inf, until: float = math.inf) -> float:
        assert since == -math.inf and until == math.inf, "extremes hold the whole run only"
        return float(self.high[COLUMNS.index(column)])

    def min(self, column: str, since: float = -math.inf, until: float = math.inf) -> float:
        assert since == -math.inf and until == math.inf, "extremes hold the whole run only"
        return float(self.low[COLUMNS.index(column)])


def rss_mb() -> float:
    """This process's resident set now, MB (/proc/self/status VmRSS; else the peak, from getrusage)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
