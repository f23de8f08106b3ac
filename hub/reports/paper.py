"""The paper's three plausibility tests as measurements on finished runs: acceleration, tipping torque, constant distances."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hub.core.resources import SCENARIOS as SHIPPED
from hub.reports.runs import Run, pitch

SCENARIOS = SHIPPED / "paper"
ACCELERATION = SCENARIOS / "acceleration.yaml"
TIPPING = SCENARIOS / "tipping_torque.yaml"
DISTANCES = SCENARIOS / "constant_distances.yaml"

#: What the paper reports, for the tables beside ours.
PAPER = {
    "tilt_20g": "~3°, then ~1/3° in a second motion",
    "tilt_80g": "~1°",
    "distance_min_cm": 15.8,
    "distance_max_cm": 22.4,
    "distance_variance_cm2": 1.6,
}


def _objects(run: Run, module: str) -> dict[str, dict]:
    return {o.name: o.params for o in run.scenario.objects if o.module_name == module}


# --- 1. acceleration --------------------------------------------------------------------------
@dataclass
class Acceleration:
    belt: str
    k: float
    speed: float
    time: np.ndarray
    velocity: np.ndarray          # along the belt, m/s
    analytical: np.ndarray

    @property
    def max_error(self) -> float:
        """Largest |v − v_analytical| over the run, as a fraction of the belt speed."""
        return float(np.max(np.abs(self.velocity - self.analytical)) / abs(self.speed))

    @property
    def t90(self) -> float:
        """First recorded time at which the bottle has 90 % of the belt speed."""
        return float(self.time[np.argmax(self.velocity >= 0.9 * self.speed)])

    @property
    def t90_analytical(self) -> float:
        return math.log(10.0) / self.k


def acceleration(run: Run) -> list[Acceleration]:
    """For each belt `NAME`, the bottle `bottle_NAME` on it: velocity along the belt against
    v(t) = v_tar·(1 − e^(−k·t))."""
    out = []
    for belt, params in _objects(run, "conveyor").items():
        yaw = math.radians(params.get("yaw", 0.0))
        v = run.vec3(f"bottle_{belt}.body.velocity")[:, :2] @ np.array([math.cos(yaw), math.sin(yaw)])
        t = run.time
        k, speed = params["k"], params["speed"]
        out.append(Acceleration(belt, k, speed, t, v, speed * (1.0 - np.exp(-k * t))))
    return out


# --- 2. tipping torque ------------------------------------------------------------------------
@dataclass
class Tipping:
    bottle: str
    model: str
    mass: float                   # kg
    time: np.ndarray
    pitch: np.ndarray             # degrees, negative: leaning back against the motion

    @property
    def first(self) -> float:
        """Largest inclination, degrees (the first rocking motion)."""
        return float(np.max(np.abs(self.pitch)))

    @property
    def second(self) -> float:
        """Largest inclination after the first motion has died down to a tenth of its peak."""
        peak = int(np.argmax(np.abs(self.pitch)))
        settled = np.nonzero(np.abs(self.pitch[peak:]) < 0.1 * self.first)[0]
        if len(settled) == 0:
            return float("nan")
        rest = self.pitch[peak + settled[0]:]
        return float(np.max(np.abs(rest)))

    @property
    def final(self) -> float:
        return float(abs(self.pitch[-1]))


def tipping(run: Run) -> list[Tipping]:
    """Inclination in the direction of motion of every bottle of the run."""
    out = []
    for name, params in _objects(run, "bottle").items():
        angle = pitch(run.quat(f"{name}.body.orientation"))
        out.append(Tipping(name, params["model"], params["mass"], run.time, angle))
    return out


# --- 3. constant distances --------------------------------------------------------------------
@dataclass
class Distances:
    time: np.ndarray
    manhattan: np.ndarray         # |Δx| + |Δy| between the bottles, m (the paper's measure)
    reference: np.ndarray         # the same for two points exactly `spacing` apart on the centre line, m
    gap: np.ndarray               # distance along the loop's centre line, m
    lateral: np.ndarray           # (T, 2): each bottle's offset from the centre line, m
    tilt: np.ndarray              # (T, 2): degrees
    on_belt: bool                 # both bottles inside some belt's field at every sample
    loop_length: float
    closure: float                # distance from the last segment's end to the first one's start, m

    def stats(self, series: np.ndarray) -> tuple[float, float, float]:
        """(min, max, variance) in cm and cm²."""
        cm = 100.0 * series
        return float(cm.min()), float(cm.max()), float(np.var(cm))


def chain(fields) -> tuple[np.ndarray, float]:
    """Start offsets of the fields along a loop declared in travel order, and how far its end
    misses its start (m)."""
    lines = fields.lines
    offsets = np.concatenate([[0.0], np.cumsum(lines.length)])
    last = len(lines) - 1
    end = lines.points(np.array([last]), np.array([lines.length[last]]))[0]
    start = lines.points(np.array([0]), np.array([0.0]))[0]
    return offsets, float(np.hypot(*(end - start)))


def distances(run: Run, lead: str = "lead", follow: str = "follow", spacing: float = 0.2) -> Distances:
    """The paper's Manhattan distance and our path gap between two bottles on a closed loop."""
    fields = run.fields
    offsets, closure = chain(fields)
    total = offsets[-1]
    positions = [run.vec3(f"{name}.body.position") for name in (lead, follow)]
    path, lateral, inside = [], [], True
    for p in positions:
        field, along, across = fields.locate(p)
        inside &= bool(np.all(field >= 0))
        path.append(offsets[np.maximum(field, 0)] + along)
        lateral.append(across)
    gap = np.mod(path[0] - path[1], total)
    manhattan = np.abs(positions[0][:, :2] - positions[1][:, :2]).sum(axis=1)
    # Where the follower would be if it were exactly `spacing` behind the leader's centre-line point.
    behind = np.mod(path[0] - spacing, total)
    line_lead = _line_at(offsets, path[0])
    line_behind = _line_at(offsets, behind)
    a = fields.lines.points(line_lead, path[0] - offsets[line_lead])
    b = fields.lines.points(line_behind, behind - offsets[line_behind])
    reference = np.abs(a - b).sum(axis=1)
    tilt = np.stack([run.columns[f"{name}.body.tilt"] for name in (lead, follow)], axis=1)
    return Distances(run.time, manhattan, reference, gap, np.stack(lateral, axis=1), tilt, inside, float(total),
                     closure)


def _line_at(offsets: np.ndarray, s: np.ndarray) -> np.ndarray:
    return np.clip(np.searchsorted(offsets, s, side="right") - 1, 0, len(offsets) - 2)
