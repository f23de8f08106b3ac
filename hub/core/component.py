"""The component contract: a small piece of functionality that owns typed slots."""
from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from hub.core.signals import Signals
from hub.core.slots import Direction, Slot, SlotType


class Component:
    """Base of every component. Subclasses declare `SLOTS` and override the step hooks they need.

    Step hooks, called by the master in the order of the step loop (hub/run/master.py):
    `sense(tick)` writes sources from the world; `react()` (only for components that declare
    `FEEDTHROUGH`) computes sources from targets while flows are evaluated; `actuate()` reads
    targets and applies them to the world; `step(tick, ticks)` advances a logic component
    (an FMU) over the communication step that starts at `tick` and lasts `ticks`.
    """

    SLOTS: ClassVar[tuple[Slot, ...]] = ()
    #: The attributes that change while the plant runs (hub/core/state.py): saved and put back
    #: with a checkpoint; everything else a component holds is structure, fixed at build.
    STATE: ClassVar[tuple[str, ...]] = ()
    #: (target, source) pairs where the target's value reaches the source within the same step.
    FEEDTHROUGH: ClassVar[tuple[tuple[str, str], ...]] = ()
    #: Its `sense` computes only the sources something reads: with none, the master skips it (a
    #: source's 150 bottles, addressable by id, cost nothing unless a scenario reads one).
    QUIET_UNLESS_NEEDED: ClassVar[bool] = False
    #: Void sources of which one is active at every point where its own `events` has rows: it is
    #: asked only at those points (hub/run/events.py). Empty: asked at every point. Declared beside
    #: `events`: a subclass that overrides `events` is asked at every point unless it declares its own.
    EVENTS_WHEN: ClassVar[tuple[str, ...]] = ()
    #: Its slots are on the data plane (hub/bus/dataplane.py); False keeps them off it.
    PUBLISHED: ClassVar[bool] = True

    def __init__(self, obj: str, name: str):
        self.obj = obj
        self.name = name
        self.signals: Signals | None = None
        self.index: dict[str, int] = {}
        self.needed: frozenset[str] = frozenset()

    def bind(self, signals: Signals, index: dict[str, int], needed: frozenset[str]) -> None:
        """Attach the plant's state object, this component's slot numbers (slot name → index) and
        the names of its sources that something reads (a flow, the recording): a component may
        skip computing the others, so a scene pays only for what it uses."""
        self.signals = signals
        self.index = index
        self.needed = needed

    def sense(self, tick: int) -> None:
        """Write this point's source values (sense, step 1 of the step loop, hub/run/master.py)."""

    def react(self) -> None:
        """Compute feedthrough sources from targets already written in this step."""

    def actuate(self) -> None:
        """Apply this point's target values to the world (actuate, step 3 of the step loop)."""

    def step(self, tick: int, ticks: int) -> None:
        """Advance own logic over [tick, tick + ticks] with the inputs of this point; its new
        outputs are for the points that follow (sensed there, never earlier)."""

    def emit_ready(self, tick: int) -> bool:
        """Write now the outputs the last `step` computed for `tick` (Gauss-Seidel hands them on
        before the next point); False if the component cannot."""
        return False

    def close(self) -> None:
        """Release what the component holds (FMU instances, processes)."""

    def held(self, slot: str):
        """The value the component itself holds for the target `slot` now (a belt: whether it runs),
        or None when the slot's value says it all. An operator's `release` gives it back."""
        return None

    def events(self, tick: int) -> Sequence[tuple[int, str, str]]:
        """Event-log rows `(tick, slot, detail)` for this step: by default every active void source.

        A sequence, empty at most points: the master passes over an empty one at once (a
        generator it would have to run), and it asks a component that keeps this default rule
        nothing at all, checking its void sources itself (hub/run/events.py)."""
        active, index = self.signals.active, self.index
        return [(tick, slot.name, "") for slot in self.SLOTS
                if slot.type is SlotType.VOID and slot.direction is Direction.SOURCE and active[index[slot.name]]]

    # Helpers for subclasses: read a target / write a source by slot name.
    def updated(self, slot: str) -> bool:
        return self.signals.updated[self.index[slot]]

    def value(self, slot: str):
        return self.signals.values[self.index[slot]]

    def emit(self, slot: str, value=None) -> None:
        # Signals.emit inlined: ~150 emits a point in the bottling plant, and the call was half their cost.
        signals, i = self.signals, self.index[slot]
        if value is not None:
            signals.values[i] = value
        signals.active[i] = True
