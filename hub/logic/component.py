"""The `logic` component of an FMU or participant object: feeds its slave the inputs of a point and brings back its outputs."""
from __future__ import annotations

from hub.core.component import Component


class LogicComponent(Component):
    """An object's `logic` component: steps its slave (an FMU, a participant, in-process Python) over the master's communication steps, or over its own longer `every` ticks.

    Jacobi in both cases: the FMU steps from t with the inputs it got at t, and its new outputs
    are held back until the point at t + h, so the result does not depend on when the master
    calls it in between. They are fetched only there (`slave.outputs()`), so logic served by a
    participant computes while the hub goes on: the step is sent in `step`, collected in `sense`.
    """

    def __init__(self, obj, name, slots, slave, inputs, outputs, rate: int, every: int | None):
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
        self._writes = ()         # (slot number, is event) per output

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers resolved once: sense and step run at every point for every logic object.
        self._reads = tuple((index[slot], event) for slot, event in self.inputs)
        self._writes = tuple((index[slot], event) for slot, event in self.outputs)

    def sense(self, tick):
        if self.latest is None or (self.ready_at is not None and tick >= self.ready_at):
            self.latest, self.ready_at = self.slave.outputs(), None
        signals = self.signals
        values, active = signals.values, signals.active
        for (i, event), value in zip(self._writes, self.latest):   # Signals.emit, inlined
            if not event:
                if value is not None:
                    values[i] = value
                active[i] = True
            elif value:
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
        self.latest, self.ready_at = self.slave.outputs(), None
        self.sense(tick)
        return True

    def close(self):
        self.slave.close()
