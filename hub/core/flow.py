"""A flow copies one source slot to one target slot when its execution condition holds."""
from __future__ import annotations

import enum
from dataclasses import dataclass

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
