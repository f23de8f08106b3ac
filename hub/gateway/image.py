"""The process image a gateway shares between the plant's steps and its protocol server, and the
lockstep handshake: the plant holds at a scan until the PLC writes the scan's number back.

The plant side (the participant, in the serve loop's thread) puts the PLC's inputs and takes its
outputs; the protocol side (the server's event-loop thread) reads the inputs and writes the outputs.
One lock guards both; a condition wakes the plant when the PLC writes a handshake tag (only those
are waited on). Every wait has a limit.
"""
from __future__ import annotations

import logging
import threading
import time

from hub.core.errors import PlanthubError
from hub.core.slots import SlotType
from hub.gateway.tags import INPUT, TagMap

_log = logging.getLogger("planthub.gateway")


class ProcessImage:
    def __init__(self, tags: TagMap):
        self.tags = tags
        self.values = {t.slot: (0 if t.type is SlotType.VOID and t.direction == INPUT else
                                False if t.type is SlotType.VOID else t.type.initial()) for t in tags.tags}
        self.changed = set(self.values)        # inputs not yet handed to the server
        self.refused = 0                       # writes the server refused (each logged)
        self._lock = threading.Condition()
        self._edges = {t.slot: False for t in tags.outputs if t.type is SlotType.VOID}
        # A PLC writes a scan's commands one tag after another (11 for the bottling plant): waking the
        # waiting plant at each of them only to find cycle_done unchanged held the server's thread up
        # at the GIL; the plant waits on handshake tags alone, so only they wake it.
        self._wakers = frozenset(t.slot for t in tags.tags if t.handshake)
        self._order = [t.slot for t in tags.tags if not t.handshake] + [t.slot for t in tags.tags if t.handshake]

    # --- the protocol side
    def read(self, slot: str):
        with self._lock:
            return self.values[slot]

    def write(self, slot: str, value) -> None:
        """A write of the PLC's that the server accepted (it checked it with Tag.check_written)."""
        with self._lock:
            self.values[slot] = value
            if slot in self._wakers:
                self._lock.notify_all()

    def refuse(self, where: str, why: str) -> None:
        with self._lock:
            self.refused += 1
        _log.warning("gateway: refused a write to %s: %s", where, why)

    def take_changed(self) -> dict:
        """Inputs changed since the last call (the server publishes them), in the tag map's order with the
        handshake tags last: a client notified of changes in the order they are published (an OPC UA
        subscription) has a scan's values before its `cycle`."""
        with self._lock:
            changed = {slot: self.values[slot] for slot in self._order if slot in self.changed}
            self.changed = set()
            return changed

    # --- the plant side
    def put(self, inputs: dict) -> None:
        with self._lock:
            for slot, value in inputs.items():
                if self.values[slot] != value:
                    self.values[slot] = value
                    self.changed.add(slot)

    def outputs(self) -> dict:
        """The PLC's outputs for this step; a command bit fires on its rising edge."""
        with self._lock:
            out = {}
            for tag in self.tags.outputs:
                value = self.values[tag.slot]
                if tag.slot in self._edges:
                    out[tag.slot], self._edges[tag.slot] = value and not self._edges[tag.slot], value
                elif not tag.handshake:
                    out[tag.slot] = value
            return out

    def wait(self, until, limit: float, what: str) -> None:
        """Wait until `until(values)` holds, at most `limit` s; a PlanthubError names `what` otherwise.
        `until` reads handshake tags only (`plc_ready`, `cycle_done`): a write of another wakes no one."""
        deadline = time.monotonic() + limit
        with self._lock:
            while not until(self.values):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise PlanthubError(f"{what} within {limit:g} s")
                self._lock.wait(left)
