"""The gateway participant: a scenario's participant object served to a PLC over OPC UA, Modbus TCP,
S7 or EtherNet/IP.

At every step the plant's values go into the process image (an event adds one to its counter) and
to the server; then, in *lockstep*, at every scan (every step, or the first step at or after each
multiple of `scan` s of plant time)
the gateway raises `cycle` and holds the plant until the PLC writes that number to `cycle_done`
(within `plc_timeout` s, or the step fails and the run stops saying so): a deterministic run, as
long as the PLC writes only between seeing a new cycle and answering it. In *live* mode it never
holds: the run is paced to the wall clock (`planthub run --realtime`) and the PLC reads and writes
whenever it scans, as against a real plant. The PLC's outputs are taken at every step; a command
bit fires its event once per rising edge. `step` runs in the plant's thread (the one `serve` steps
the gateway in), which alone begins a scan in the image (`begin_scan`) and, when the run ends,
releases it (`release`, hub/cli/gateway.py); a PLC's read of `cycle` is held (`hold`) in a protocol
server's thread or a thread of its event loop's pool (OPC UA's in its event loop, by `begin_hold`).
"""
from __future__ import annotations

from hub.bus.participant import Participant
from hub.core.slots import SlotType
from hub.gateway.tags import TagMap

LOCKSTEP, LIVE = "lockstep", "live"


class Gateway(Participant):
    def __init__(self, tags: TagMap, server, *, mode: str = LOCKSTEP, scan: float | None = None,
                 plc_timeout: float = 0.5, ready_timeout: float = 30.0):
        self.tags, self.server, self.mode = tags, server, mode
        self.image = server.protocol.image
        if self.image.holds != (mode == LOCKSTEP):
            raise ValueError(f"a {mode} gateway on a process image that {'holds' if self.image.holds else 'never holds'}"
                             f" reads of cycle: ProcessImage(tags, lockstep={mode == LOCKSTEP})")
        self.scan, self.plc_timeout, self.ready_timeout = scan, plc_timeout, ready_timeout
        plain = [t for t in tags.tags if not t.handshake]
        self.inputs = {t.slot: t.type.value for t in plain if t.direction == "input"}
        self.outputs = {t.slot: t.type.value for t in plain if t.direction == "output"}
        self._events = tuple(t.slot for t in plain if t.direction == "input" and t.type is SlotType.VOID)
        self._values = tuple(t.slot for t in plain if t.direction == "input" and t.type is not SlotType.VOID)
        self._counts = {slot: 0 for slot in self._events}
        self.cycle = 0
        self._next_scan = 0.0      # plant time of the next scan (with `scan`)

    def wait_for_plc(self) -> None:
        """Lockstep: the PLC sets `plc_ready` before the gateway joins the plant."""
        if self.mode == LOCKSTEP:
            self.image.wait(lambda v: v["plc_ready"], self.ready_timeout, "no PLC set plc_ready")

    def step(self, t, h):
        for slot in self._events:
            if getattr(self, slot):
                self._counts[slot] += 1
        values = {slot: getattr(self, slot) for slot in self._values}
        values.update(self._counts)
        held = self.mode == LOCKSTEP and (self.scan is None or t >= self._next_scan - 1e-9)
        if held and self.scan is not None:
            while self._next_scan <= t + 1e-9:
                self._next_scan += self.scan
        if held:
            self.cycle = (self.cycle + 1) % 65536
            values["cycle"] = self.cycle
        self.image.put(values)
        if held or self.mode == LIVE:   # in lockstep the PLC reads only at a scan: what changed in between goes then
            self.server.publish(self.image.take_changed())
        if held:
            cycle = self.cycle
            self.image.begin_scan(cycle)
            self.image.wait(lambda v: v["cycle_done"] == cycle, self.plc_timeout,
                            f"the PLC did not answer scan {cycle} (t = {t:.6g} s)")
        for slot, value in self.image.outputs().items():
            setattr(self, slot, value)
