"""A flow copies one source slot to one target slot when its execution condition holds."""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import ClassVar

from hub.core.signals import Signals


class Condition(enum.Enum):
    """When a flow executes, judged on the slots' activity in the current step."""

    SOURCE = "source"   # push: the source emitted
    TARGET = "target"   # pull: the target is ready, takes the source's held value
    BOTH = "both"
    EITHER = "either"


class Mode(enum.Enum):
    CONTINUOUS = "continuous"  # may execute in every step
    SINGULAR = "singular"      # executes once, then waits until its re-arm slot fires


@dataclass
class Flow:
    """A built flow over slot numbers. `rearm` is a void source that re-arms a singular flow."""

    source: int
    target: int
    condition: Condition = Condition.SOURCE
    mode: Mode = Mode.CONTINUOUS
    rearm: int | None = None
    armed: bool = True
    STATE: ClassVar[tuple[str, ...]] = ("armed",)   # hub/core/state.py

    def run(self, signals: Signals) -> bool:
        """Execute if armed and the condition holds; return whether it executed.

        A singular flow whose re-arm slot fires in this step is armed before it is judged, so it
        can execute in that same step.
        """
        if self.mode is Mode.SINGULAR:
            if self.rearm is not None and signals.active[self.rearm]:
                self.armed = True
            if not self.armed:
                return False
        src = signals.active[self.source]
        tgt = signals.active[self.target]
        cond = self.condition
        if cond is Condition.SOURCE:
            go = src
        elif cond is Condition.TARGET:
            go = tgt
        elif cond is Condition.BOTH:
            go = src and tgt
        else:
            go = src or tgt
        if not go:
            return False
        signals.values[self.target] = signals.values[self.source]
        signals.updated[self.target] = True
        if self.mode is Mode.SINGULAR:
            self.armed = False
        return True

    def runner(self, signals: Signals):
        """`run(signals)` as a call without arguments, for the plan a plant evaluates at every point
        (the bottling plant's 44 flows): a continuous flow's condition is settled here once, so a
        call costs a flag test where `run` cost its enum tests and look-ups (23 → 7 µs a point).
        Signals keeps its lists for its whole life, so the closure may hold them."""
        if self.mode is Mode.SINGULAR:
            return lambda: self.run(signals)
        active, values, updated = signals.active, signals.values, signals.updated
        source, target = self.source, self.target
        if self.condition is Condition.SOURCE:   # the common case (push), without a call for the test
            def run() -> bool:
                if not active[source]:
                    return False
                values[target] = values[source]
                updated[target] = True
                return True
            return run
        go = {
            Condition.TARGET: lambda: active[target],
            Condition.BOTH: lambda: active[source] and active[target],
            Condition.EITHER: lambda: active[source] or active[target],
        }[self.condition]

        def run() -> bool:
            if not go():
                return False
            values[target] = values[source]
            updated[target] = True
            return True
        return run
