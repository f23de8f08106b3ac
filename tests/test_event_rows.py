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


class Counter(Component):
    """Its own rule, with rows only at points where `passed` fired (EVENTS_WHEN)."""

    SLOTS = (Slot.source("passed", "void"), Slot.source("total", "int"))
    EVENTS_WHEN = ("passed",)

    def __init__(self, obj, name):
        super().__init__(obj, name)
        self.asked = 0

    def events(self, tick):
        self.asked += 1
        return [(tick, "passed", "P1")] if self.active_passed() else []

    def active_passed(self):
        return self.signals.active[self.index["passed"]]


def test_a_component_is_asked_only_when_its_events_slot_fired():
    counter = Counter("c", "count")
    signals = _bind([counter])
    rows = EventRows([counter])
    signals.begin_step()
    counter.emit("total", 4)
    assert rows.gather(5, signals, []) == []
    assert counter.asked == 0
    signals.begin_step()
    counter.emit("passed")
    assert rows.gather(6, signals, []) == [(6, "c.count.passed", "P1")]
    assert counter.asked == 1


def test_events_when_must_name_void_sources():
    class Wrong(Counter):
        EVENTS_WHEN = ("total",)

        def events(self, tick):
            return []

    wrong = Wrong("w", "count")
    _bind([wrong])
    try:
        EventRows([wrong])
    except ValueError as exc:
        assert str(exc) == "Wrong.EVENTS_WHEN names ['total'], not void sources of it (['passed'])"
    else:
        raise AssertionError("EventRows took an EVENTS_WHEN naming an int slot")


def test_a_subclass_with_rows_of_its_own_is_asked_at_every_point():
    class Gripping(Counter):
        """Rows of its own at points where `passed` did not fire (like a gripper's grips)."""

        def events(self, tick):
            self.asked += 1
            return [(tick, "gripped", "P2")]

    gripping = Gripping("g", "gripper")
    signals = _bind([gripping])
    signals.begin_step()
    assert EventRows([gripping]).gather(5, signals, []) == [(5, "g.gripper.gripped", "P2")]
    assert gripping.asked == 1
