"""Runs a scenario for a report or a test and hands back its recording as numpy columns with the belt geometry."""
from __future__ import annotations

import csv
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hub.core import scratch
from hub.physics.fields import ForceFields
from hub.run.assembly import Run as Assembly
from hub.scenario.checker import Scenario, load_scenario


@dataclass
class Run:
    """One finished run: its scenario, every recorded column and the belts' force fields."""

    scenario: Scenario
    columns: dict[str, np.ndarray]
    fields: ForceFields
    wall_seconds: float
    directory: Path | None

    @property
    def time(self) -> np.ndarray:
        return self.columns["time"]

    def vec3(self, slot: str) -> np.ndarray:
        """A recorded vec3 slot as an array (T, 3)."""
        return np.stack([self.columns[f"{slot}.{c}"] for c in "xyz"], axis=1)

    def quat(self, slot: str) -> np.ndarray:
        """A recorded quat slot as an array (T, 4), (x, y, z, w)."""
        return np.stack([self.columns[f"{slot}.{c}"] for c in "xyzw"], axis=1)

    def belt_of(self, name: str) -> int:
        """The force-field index of the belt object `name` (fields are made in declaration order)."""
        belts = [o.name for o in self.scenario.objects if o.module_name in ("conveyor", "curve")]
        return belts.index(name)


def run(path, out: Path | None = None, overrides: dict | None = None) -> Run:
    """Run the scenario at `path` (recording into `out`, or a temporary folder) and read it back."""
    scenario = load_scenario(path, overrides)
    with tempfile.TemporaryDirectory(dir=scratch.folder()) as tmp:
        directory = Path(out) if out is not None else Path(tmp)
        with Assembly(scenario, out=directory) as assembled:
            started = time.perf_counter()
            assembled.run()
            wall = time.perf_counter() - started
            fields = assembled.plant.world.fields   # pure numpy: usable after the world is closed
        data = read_recording(directory / "recording.csv")
    return Run(scenario, data, fields, wall, Path(out) if out is not None else None)


def read_recording(path: Path) -> dict[str, np.ndarray]:
    """recording.csv as {column name: float array}."""
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    header, body = rows[0], rows[1:]
    values = np.array(body, dtype=float) if body else np.zeros((0, len(header)))
    return {name: values[:, i] for i, name in enumerate(header)}


def pitch(orientations: np.ndarray, heading: float = 0.0) -> np.ndarray:
    """Inclination of each body's axis in the direction of motion `heading` (radians), degrees;
    positive leans forward, negative back."""
    x, y, z, w = orientations.T
    axis_x, axis_y, axis_z = 2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)
    forward = np.cos(heading) * axis_x + np.sin(heading) * axis_y
    return np.degrees(np.arctan2(forward, axis_z))
