"""The `logic` component of an FMU or participant object: feeds its slave the inputs of a point and brings back its outputs."""
from __future__ import annotations

import logging
import operator

from hub.core.component import Component
from hub.core.errors import SimulationError
from hub.core.slots import SlotType

log = logging.getLogger("planthub.logic")

#: What a non-finite real from the logic does: stop the run (the default), or hold the last good value.
ON_BAD_VALUE = ("stop", "hold")


class LogicComponent(Component):
    """An object's `logic` component: steps its slave (an FMU, a participant, in-process Python) over the master's communication steps, or over its own longer `every` ticks.

    Jacobi in both cases: the FMU steps from t with the inputs it got at t, and its new outputs
    are held back until the point at t + h, so the result does not depend on when the master
    calls it in between. They are fetched only there (`slave.outputs()`), so logic served by a
    participant computes while the hub goes on: the step is sent in `step`, collected in `sense`.

    Every output is checked where it enters the plant, when it is fetched: a real (or a vec3 or
    quat) that is not finite stops the run naming the slot, the tick and the time, or, with
    `on_bad_value: hold`, keeps the slot's last good value and logs each occurrence.
    """

    #: hub/core/state.py; save_state adds the slave's own state (hub.core.slave).
    STATE = ("latest", "ready_at", "bad_values")

    def __init__(self, obj, name, slots, slave, inputs, outputs, rate: int, every: int | None,
                 on_bad_value: str = "stop", starts: dict | None = None):
        super().__init__(obj, name)
        self.SLOTS = slots
        self.slave = slave
        self.inputs = inputs      # [(slot name, is event)] in the FMU's input order
        self.outputs = outputs    # [(slot name, is event)] in the FMU's output order
        self.rate = rate
        self.every = every        # own step in ticks, or None: every master step
        self.latest = None        # outputs in use; fetched at the first point
        self.ready_at = None      # the tick at which the last step's outputs are due
        self._reads = ()          # (slot number, is event) per input, in the FMU's order
        self._states = self._events = ((), _getter([]))   # output slot numbers, a getter of their values
        self.on_bad_value = on_bad_value
        kinds = {s.name: s.type for s in slots}
        numeric = (SlotType.REAL, SlotType.VEC3, SlotType.QUAT)
        #: (position in the outputs, slot name, scalar?) of every output that must be finite
        self._numeric = tuple((k, slot, kinds[slot] is SlotType.REAL) for k, (slot, event) in enumerate(outputs)
                              if not event and kinds[slot] in numeric)
        self.bad_values = 0       # non-finite outputs held (on_bad_value: hold)
        self.starts = starts or {}   # input slot → the value it holds until a flow writes it

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers resolved once: sense and step run at every point for every logic object.
        self._reads = tuple((index[slot], event) for slot, event in self.inputs)
        # Outputs split once into states (written at every point) and events (active when true),
        # each with its slot numbers and a getter of its values: no test of the kind per value.
        states = [k for k, (_, event) in enumerate(self.outputs) if not event]
        events = [k for k, (_, event) in enumerate(self.outputs) if event]
        self._states = (tuple(index[self.outputs[k][0]] for k in states), _getter(states))
        self._events = (tuple(index[self.outputs[k][0]] for k in events), _getter(events))
        for slot, value in self.starts.items():   # the logic's own start values, not the type's zero
            signals.values[index[slot]] = value

    def _fetch(self, tick: int) -> None:
        outputs = self.slave.outputs()
        for k, slot, scalar in self._numeric:
            value = outputs[k]
            # x − x is 0.0 for every finite float, NaN for NaN and ±inf: one subtraction per output.
            if value is not None and (value - value != 0.0 if scalar else any(x - x != 0.0 for x in value)):
                outputs = list(outputs)
                outputs[k] = self._bad(tick, slot, value)
        self.latest, self.ready_at = outputs, None

    def _bad(self, tick: int, slot: str, value):
        """The value to use in place of a non-finite one, or a SimulationError (on_bad_value: stop)."""
        where = f"{self.obj}.{self.name}.{slot}"
        what = getattr(self.slave, "instance", self.obj)
        when = f"at t = {tick / self.rate:.9g} s (tick {tick})"
        if self.on_bad_value == "stop":
            raise SimulationError(f"{where}: the logic {what!r} gave {value!r} {when}; every value entering the "
                                  f"plant must be finite, so the run stops here (on_bad_value: hold keeps the last "
                                  f"good value instead)")
        self.bad_values += 1
        held = self.signals.values[self.index[slot]]
        log.warning("%s: the logic %r gave %r %s; holding the last good value %r (on_bad_value: hold)",
                    where, what, value, when, held)
        return held

    def sense(self, tick):
        if self.latest is None or (self.ready_at is not None and tick >= self.ready_at):
            self._fetch(tick)
        signals, latest = self.signals, self.latest
        values, active = signals.values, signals.active
        slots, get = self._states
        for i, value in zip(slots, get(latest)):   # Signals.emit, inlined
            if value is not None:
                values[i] = value
            active[i] = True
        slots, get = self._events
        for i, value in zip(slots, get(latest)):
            if value:
                active[i] = True

    def step(self, tick, ticks):
        if self.every is not None:
            if tick % self.every:
                return   # between two of its own points: it already stepped over this interval
            ticks = self.every
        signals = self.signals
        updated, values = signals.updated, signals.values
        self.slave.set_inputs([updated[i] if event else values[i] for i, event in self._reads])
        self.slave.step(tick / self.rate, ticks / self.rate)
        self.ready_at = tick + ticks

    def emit_ready(self, tick):
        if self.ready_at != tick:
            return False   # stepping on its own grid: its outputs belong to a later point
        self._fetch(tick)
        self.sense(tick)
        return True

    def save_state(self) -> dict:
        return {"fields": {name: getattr(self, name) for name in self.STATE}, "slave": self.slave.save()}

    def restore_state(self, saved: dict) -> None:
        self.slave.restore(saved["slave"])
        for name, value in saved["fields"].items():
            setattr(self, name, value)

    def close(self):
        self.slave.close()


def _getter(positions: list[int]):
    """The values at `positions` of a list, as an iterable."""
    if len(positions) > 1:
        return operator.itemgetter(*positions)
    if positions:
        k = positions[0]
        return lambda values: (values[k],)
    return lambda values: ()
