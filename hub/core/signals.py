"""The one state object of a running plant: every slot's value and its activity in the current step."""
from __future__ import annotations

from hub.core.slots import Direction, Slot


class Signals:
    """Values and per-step flags of all slots, indexed by slot number.

    `active` is the paper's slot activity. A component sets it on a source when it emits in
    this step; on a target it means "ready to receive" and is true unless the owning component
    clears it. `updated` marks a target that a flow wrote in this step.
    """

    #: hub/core/state.py: the values, and the activity of the point the run is at (a Gauss-Seidel
    #: step evaluates flows between two logic steps from it). The lists keep their identity.
    STATE = ("values", "active", "updated")

    def __init__(self, slots: list[Slot]):
        self.slots = slots
        self.values = [s.type.initial() for s in slots]
        self._active_at_start = [s.direction is Direction.TARGET for s in slots]
        self._is_target = list(self._active_at_start)
        self._none_updated = [False] * len(slots)
        self.active = list(self._active_at_start)
        self.updated = list(self._none_updated)

    def begin_step(self) -> None:
        """Forget last step's activity: sources go quiet, targets are ready and not yet written."""
        self.active[:] = self._active_at_start
        self.updated[:] = self._none_updated

    def emit(self, index: int, value=None) -> None:
        """Write a source slot and mark it active for this step (for void slots: fire the event)."""
        if value is not None:
            self.values[index] = value
        self.active[index] = True

    def fired(self, index: int) -> bool:
        """Whether the slot carried something in this step: a source emitted, a target was fed."""
        return self.updated[index] if self._is_target[index] else self.active[index]
