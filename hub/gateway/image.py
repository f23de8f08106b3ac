"""The process image a gateway shares between the plant's steps and its protocol server, and the
lockstep handshake: the plant holds at a scan until the PLC writes the scan's number back.

The plant side (the participant, in the serve loop's thread) puts the PLC's inputs and takes its
outputs; the protocol side (the server's event-loop thread) reads the inputs and writes the outputs.
One lock guards both; a condition wakes the plant when the PLC writes a handshake tag (only those
are waited on), and a PLC's read of `cycle` held between two scans (`hold`) when the next begins.
`hold` is called by a protocol server's thread (snap7's) or a thread of its event loop's pool
(Modbus, EtherNet/IP), `begin_hold` by OPC UA's event loop; `begin_scan` and `release` by the
plant's thread alone. Every wait has a limit.
"""
from __future__ import annotations

import logging
import threading
import time

from hub.core.errors import PlanthubError
from hub.core.slots import SlotType
from hub.gateway.tags import INPUT, TagMap

_log = logging.getLogger("planthub.gateway")
HOLD = 0.1   # s at most that a PLC's read of `cycle` is held for the next scan


class ProcessImage:
    def __init__(self, tags: TagMap, lockstep: bool = False, hold: float = HOLD):
        self.tags = tags
        self.values = {t.slot: (0 if t.type is SlotType.VOID and t.direction == INPUT else
                                False if t.type is SlotType.VOID else t.type.initial()) for t in tags.tags}
        self.changed = set(self.values)        # inputs not yet handed to the server
        self.refused = 0                       # requests the server refused (each logged)
        self._lock = threading.Condition()
        self._edges = {t.slot: False for t in tags.outputs if t.type is SlotType.VOID}
        # A PLC writes a scan's commands one tag after another (11 for the bottling plant): waking the
        # waiting plant at each of them only to find cycle_done unchanged held the server's thread up
        # at the GIL; the plant waits on handshake tags alone, so only they wake it.
        self._wakers = frozenset(t.slot for t in tags.tags if t.handshake)
        self._order = [t.slot for t in tags.tags if not t.handshake] + [t.slot for t in tags.tags if t.handshake]
        self.holds = lockstep   # a read of `cycle` between two scans is held for the next (until `release`)
        self.hold_limit = hold
        self.at_scan = None     # the scan the plant is at or last was (None: none yet)
        self.held_reads = 0     # reads of `cycle` that were held for a scan
        self._listeners = ()    # called when a scan begins and when the run ends (`listen`)

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

    def hold(self) -> None:
        """A PLC's read of `cycle`, in lockstep: while the plant steps toward its next scan (it has none
        yet, or the PLC answered the last), wait for that scan, at most `hold_limit` s. A PLC polling
        `cycle` then learns of a scan as soon as the plant is at it, and its polls between two scans
        cost the plant nothing. The read is answered either way: after the limit, with the scan it
        answered last."""
        deadline = time.monotonic() + self.hold_limit
        with self._lock:
            if not self._begin_hold():
                return
            while self._between():
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                self._lock.wait(left)

    def begin_hold(self) -> bool:
        """A PLC's read of `cycle` for a server that waits in its own way (OPC UA, in its event loop):
        True if it is to be held (counted in `held_reads`); the server then lets it go on when a
        listener (`listen`) is called, or after `hold_limit` s."""
        with self._lock:
            return self._begin_hold()

    def between_scans(self) -> bool:
        """Lockstep, and the plant steps toward its next scan: it has none yet, or the PLC answered
        the last. A read of `cycle` now would be held."""
        with self._lock:
            return self._between()

    def listen(self, listener) -> None:
        """Call `listener()` when a scan begins and when the run ends, in the plant's thread."""
        self._listeners = (*self._listeners, listener)   # a new tuple: the plant's thread may be calling them

    def unlisten(self, listener) -> None:
        self._listeners = tuple(k for k in self._listeners if k is not listener)

    def _begin_hold(self) -> bool:
        if self._between():
            self.held_reads += 1
            return True
        return False

    def _between(self) -> bool:
        return self.holds and (self.at_scan is None or self.values["cycle_done"] == self.at_scan)

    def refuse(self, where: str, why: str, access: str = "a write to") -> None:
        """A PLC's request the server refused, logged as "refused {access} {where}: {why}" (`access`: "a
        write to" a tag, "a read of" one, "a request" a server could not read…)."""
        with self._lock:
            self.refused += 1
        _log.warning("gateway: refused %s %s: %s", access, where, why)

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

    def begin_scan(self, cycle: int) -> None:
        """The plant is at scan `cycle`, its values published: the reads held for it go on."""
        with self._lock:
            self.at_scan = cycle
            self._lock.notify_all()
        for listener in self._listeners:
            listener()

    def release(self) -> None:
        """The run is over: no read is held any more."""
        with self._lock:
            self.holds = False
            self._lock.notify_all()
        for listener in self._listeners:
            listener()

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
