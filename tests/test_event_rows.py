"""The event-log rows of a point (hub/run/events.py): tick order, then component order; default and own rules."""
from __future__ import annotations

from hub.core.component import Component
from hub.core.signals import Signals
from hub.core.slots import Slot
from hub.run.events import EventRows


class Button(Component):
    """Keeps the default rule: every active void source is a row."""

    SLOTS = (Slot.source("pressed", "void"), Slot.source("count", "int"), Slot.source("released", "void"))


class Latch(Component):
    """Its own rule: rows of earlier ticks, given as a generator (any iterable is fine)."""

    SLOTS = (Slot.source("seen", "void"),)

    def __init__(self, obj, name, rows):
        super().__init__(obj, name)
        self.rows = rows

    def events(self, tick):
        yield from self.rows


class Quiet(Component):
    SLOTS = (Slot.source("level", "real"),)


def _bind(components):
    slots, locals_ = [], []
    for comp in components:
        local = {}
        for slot in comp.SLOTS:
            local[slot.name] = len(slots)
            slots.append(slot)
        locals_.append(local)
    signals = Signals(slots)
    for comp, local in zip(components, locals_):
        comp.bind(signals, local, frozenset())
    return signals


def test_rows_in_tick_order_then_component_order():
    a, b = Button("a", "button"), Button("b", "button")
    latch = Latch("l", "trigger", [(7, "on_enter", "P1"), (9, "on_leave", "P1")])
    comps = [a, Quiet("q", "sensor"), latch, b]
    signals = _bind(comps)
    rows = EventRows(comps)
    signals.begin_step()
    a.emit("released")
    a.emit("pressed")
    b.emit("pressed")
    a.emit("count", 3)   # not void: no row
    got = rows.gather(9, signals, [(8, "operator.command", "x")])
    assert got == [(7, "l.trigger.on_enter", "P1"),
                   (8, "operator.command", "x"),
                   (9, "a.button.pressed", ""), (9, "a.button.released", ""),
                   (9, "l.trigger.on_leave", "P1"),
                   (9, "b.button.pressed", "")]


def test_a_quiet_point_has_no_rows():
    a = Button("a", "button")
    latch = Latch("l", "trigger", [])
    signals = _bind([a, latch])
    signals.begin_step()
    assert EventRows([a, latch]).gather(3, signals, []) == []
