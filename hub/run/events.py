"""A communication point's event-log rows, gathered from the components in their order (step 4 of the step loop, hub/run/master.py)."""
from __future__ import annotations

from operator import itemgetter

from hub.core.component import Component
from hub.core.signals import Signals
from hub.core.slots import Direction, SlotType

_TICK = itemgetter(0)


class EventRows:
    """Gathers the rows `(tick, "obj.component.slot", detail)` of a point in tick order, those of
    one tick in the order of the components (then as each gives them).

    Settled at load: each component's prefix, and for a component that keeps the default rule
    (Component.events: every active void source) the numbers and full names of its void
    sources, checked here flag by flag without calling it; a component with its own rule is
    asked, and an empty answer costs nothing more; one that names the void sources its rows come
    with (Component.EVENTS_WHEN) only at a point where one of them is active. The bottling plant
    has 42 components that may log events and a few rows at one point in ten: asking every one
    cost 60 µs a point.
    """

    def __init__(self, components: list[Component]):
        # (None, ((slot number, full name), ...), ()) for a run of default-rule components, or
        # (component, its prefix, the slot numbers of its EVENTS_WHEN) for one with its own rule,
        # in the components' order.
        self._steps: list[tuple[Component | None, object, tuple[int, ...]]] = []
        for comp in components:
            prefix = f"{comp.obj}.{comp.name}."
            if type(comp).events is not Component.events:
                when = _events_when(type(comp))
                voids = {s.name for s in comp.SLOTS if s.type is SlotType.VOID and s.direction is Direction.SOURCE}
                if not set(when) <= voids:
                    raise ValueError(f"{type(comp).__name__}.EVENTS_WHEN names {sorted(set(when) - voids)}, "
                                     f"not void sources of it ({sorted(voids)})")
                self._steps.append((comp, prefix, tuple(comp.index[name] for name in when)))
                continue
            voids = tuple((comp.index[s.name], prefix + s.name) for s in comp.SLOTS
                          if s.type is SlotType.VOID and s.direction is Direction.SOURCE)
            if not voids:
                continue
            if self._steps and self._steps[-1][0] is None:
                self._steps[-1] = (None, self._steps[-1][1] + voids, ())
            else:
                self._steps.append((None, voids, ()))

    def gather(self, tick: int, signals: Signals, rows: list) -> list:
        """`rows` (a manipulator's, given first) with the components' rows of this point, sorted by tick."""
        active = signals.active
        for comp, found, when in self._steps:
            if comp is None:
                rows += [(tick, name, "") for i, name in found if active[i]]
                continue
            if when:
                for i in when:
                    if active[i]:
                        break
                else:
                    continue   # none of the voids its rows come with fired: no rows
            own = comp.events(tick)
            if own:
                rows += [(t, found + slot, detail) for t, slot, detail in own]
        if len(rows) > 1:
            rows.sort(key=_TICK)   # stable: rows of one tick keep the components' order
        return rows


def _events_when(cls: type) -> tuple[str, ...]:
    """The EVENTS_WHEN declared by the class whose `events` a component has: a subclass with rows
    of its own (a gripper's grips, beside its trigger's entries) is asked at every point unless it
    declares its own."""
    owner = next(c for c in cls.__mro__ if "events" in c.__dict__)
    return owner.__dict__.get("EVENTS_WHEN", ())
