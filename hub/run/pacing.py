"""Real-time pacing: hold each communication point until the wall clock reaches its time, and count
the points that came too late (overruns)."""
from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass
class Pacer:
    """Paces simulated time to `factor` × the wall clock (2.0: twice as fast as real time).

    A point that is due is not waited for; one that is more than `tolerance` seconds late is an
    overrun, and the schedule restarts from it: after a stall the run goes on at the right pace
    rather than racing to catch up. Simulated results never depend on pacing.
    """

    rate: int                      # physics ticks per simulated second
    factor: float = 1.0
    tolerance: float = 0.001       # s of lateness that still counts as on time
    clock: object = time.perf_counter
    sleep: object = time.sleep
    overruns: int = 0
    worst: float = 0.0             # s: the latest a point came
    points: int = 0
    _anchor: tuple = field(default=None, repr=False)   # (wall time, tick) the schedule counts from
    _last: int = field(default=0, repr=False)          # the tick of the last point paced

    def __post_init__(self):
        if not self.factor > 0:
            raise ValueError(f"a real-time factor must be positive, got {self.factor!r}")

    def start(self, tick: int) -> None:
        self._anchor = (self.clock(), tick)
        self._last = tick

    def set_factor(self, factor: float) -> None:
        """A new pace (an operator's `pace`), counted from the last point paced."""
        if not (isinstance(factor, (int, float)) and factor > 0):
            raise ValueError(f"a real-time factor must be positive, got {factor!r}")
        self.factor = float(factor)
        if self._anchor is not None:
            self._anchor = (self.clock(), self._last)

    def due(self, tick: int) -> float:
        wall, start = self._anchor
        return wall + (tick - start) / (self.rate * self.factor)

    def wait(self, tick: int) -> None:
        """Call at every communication point, after its work: sleep until its wall-clock time."""
        if self._anchor is None:
            self.start(tick)
            return
        self.points += 1
        self._last = tick
        now = self.clock()
        late = now - self.due(tick)
        if late > self.tolerance:
            self.overruns += 1
            self.worst = max(self.worst, late)
            self._anchor = (now, tick)
        elif late < 0:
            self.sleep(-late)

    def summary(self) -> str:
        if not self.overruns:
            return f"paced at {self.factor:g}× real time, no overruns in {self.points} point{'s' * (self.points != 1)}"
        return (f"paced at {self.factor:g}× real time, {self.overruns} of {self.points} points late "
                f"(worst {1000 * self.worst:.1f} ms)")
