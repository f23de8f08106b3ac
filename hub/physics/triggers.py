"""Volume triggers: box tests on positions already read, latched across physics substeps."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .frames import Boxes


@dataclass
class Latch:
    """What one trigger saw since it was last taken: (tick, body) enters and leaves, in order."""

    entered: list[tuple[int, int]] = field(default_factory=list)
    left: list[tuple[int, int]] = field(default_factory=list)
    stayed: bool = False          # something was inside at some tick
    inside: tuple[int, ...] = ()  # bodies inside at the latest tick, in body order


class VolumeTriggers:
    """Box volumes that report upright cylinders (radius r, half height hz) overlapping them.

    The test is exact for an upright cylinder against a yawed box: in the box frame the
    horizontal distance from the axis to the box must be at most r and the vertical extents
    must overlap. Each evaluation compares with the previous tick, so an object that enters
    and leaves between two communication points still produces both events.
    """

    def __init__(self):
        self.boxes = Boxes()
        self.latches: list[Latch] = []
        self._inside = np.zeros((0, 0), bool)

    def __len__(self) -> int:
        return len(self.boxes)

    def add(self, center, half_extents, yaw: float) -> int:
        index = self.boxes.add(center, half_extents, yaw)
        self.latches.append(Latch())
        self._inside = np.zeros((len(self.boxes), self._inside.shape[1]), bool)
        return index

    def evaluate(self, tick: int, positions: np.ndarray, radii: np.ndarray, half_heights: np.ndarray) -> bool:
        """Compare occupancy with the previous tick and latch the changes; True if there was one."""
        if len(self) == 0:
            return False
        local = self.boxes.local(positions)
        e = self.boxes.half_extents[:, None, :]
        gap = np.maximum(np.abs(local[..., :2]) - e[..., :2], 0.0)
        inside = (np.einsum("tnk,tnk->tn", gap, gap) <= radii[None, :] ** 2) & (
            np.abs(local[..., 2]) <= e[..., 2] + half_heights[None, :]
        )
        previous = self._inside
        if previous.shape != inside.shape:
            previous = np.zeros_like(inside)
        self._inside = inside
        for t in np.nonzero(inside.any(axis=1))[0]:
            self.latches[t].stayed = True
        if np.array_equal(inside, previous):
            return False
        for t, n in zip(*np.nonzero(inside & ~previous)):
            self.latches[t].entered.append((tick, int(n)))
        for t, n in zip(*np.nonzero(previous & ~inside)):
            self.latches[t].left.append((tick, int(n)))
        return True

    def take(self, trigger: int) -> Latch:
        """Hand over what the trigger latched and start a new latch with the current occupancy."""
        latch = self.latches[trigger]
        row = self._inside[trigger] if self._inside.size else np.zeros(0, bool)
        latch.inside = tuple(int(n) for n in np.nonzero(row)[0])
        self.latches[trigger] = Latch()
        return latch
