"""The view's side of the bus: a live participant of one run that hands what the hub sends to the view's loop and puts what the browsers ask for.

It joins as any viewer does (schemas/wire.md, "Live participants"): subscribers first, then its
liveliness token `plant/<run>/@cosim/viewer/<name>`, which holds its rate requests. An instructor's
view also subscribes to the instructor's key (`instruct`: the board of faults, their event rows,
the answers to its commands) and puts its commands there; a trainee's never touches it. Every callback
only hands the raw payload to a `Bridge` (hub/view/bridge.py); decoding happens on the loop.
"""
from __future__ import annotations

import uuid

from hub.bus import wire
from hub.bus.commands import command_message
from hub.bus.session import Bus, Message
from hub.bus.settings import BusSettings
from hub.bus.tls import common_name
from hub.core.errors import PlanthubError
from hub.core.slots import SlotType
from hub.view.scene import read_scene

#: the belts' speeds, watched for the panel's plots, and how often (s of plant time)
SPEEDS = "*/drive/velocity"   # what each belt drives its bottles to now (drive.speed is only its target)
SPEEDS_PERIOD = 0.2

_TYPES = {f"planthub/{t.value}": t for t in SlotType}


class ViewError(PlanthubError):
    """The view cannot join its run or make sense of what the hub sent; the message names the run and endpoint."""


class Relay:
    """One run's view on the bus, under the viewer name `name` (also the `by` of its commands)."""

    def __init__(self, run: str, connect, *, mode: str = "peer", tls=None, name: str | None = None):
        self.run = wire.check_run_name(run)
        self.name = wire.check_run_name(name) if name else f"view-{uuid.uuid4().hex[:8]}"
        self.connect = tuple(connect)
        self.bus = Bus(BusSettings(mode=mode, connect=self.connect, tls=tls), listen=False)
        # The name access control knows this view by: its certificate's common name (None: none shown).
        self.common_name = common_name(tls.certificate) if tls is not None and tls.certificate else None
        self.speeds = f"plant/{self.run}/{SPEEDS}"
        self.instructing = False   # subscribed to the instructor's key (`instruct`)
        self._bridge = None

    @property
    def where(self) -> str:
        return ", ".join(self.connect)

    def join(self, bridge) -> None:
        """Subscribe to what the view relays, then declare the viewer token."""
        key, bus = self._key, self.bus
        self._bridge = bridge
        try:
            bus.subscribe_payloads(key("bodies"), lambda p: bridge.latest("bodies", p))
            bus.subscribe_payloads(key("figures"), lambda p: bridge.latest("figures", p))
            bus.subscribe_payloads(key("events"), lambda p: bridge.put("events", p))
            bus.subscribe_payloads(key("state"), lambda p: bridge.put("state", p))
            bus.subscribe_payloads(key("checkpoints"), lambda p: bridge.latest("checkpoints", p))
            bus.subscribe_payloads(key("command", "result"), lambda p: bridge.put("result", p))
            bus.subscribe(self.speeds, lambda m: bridge.put("slot", m))
            bus.watch_tokens(wire.hub_token(self.run), lambda m: bridge.put("hub", m.alive))
            bus.declare_token(key("viewer", self.name))
        except BaseException:
            self.close()
            raise

    def instruct(self) -> None:
        """Subscribe to the instructor's key (once joined): the faults' board, their event rows, the
        answers to this view's commands (which `command(…, instructor=True)` puts there)."""
        if self.instructing:
            return
        self.instructing = True
        key, bus, bridge = lambda *p: wire.instructor_key(self.run, *p), self.bus, self._bridge
        bus.subscribe_payloads(key("faults"), lambda p: bridge.latest("faults", p))
        bus.subscribe_payloads(key("events"), lambda p: bridge.put("fault_events", p))
        bus.subscribe_payloads(key("command", "result"), lambda p: bridge.put("result", p))

    def ask_scene(self, timeout: float) -> dict | None:
        """The scene document, or None when the hub did not answer within `timeout` s (blocks)."""
        message = self.bus.ask(self._key("scene"), timeout)
        return None if message is None else self._scene(message.payload)

    def ask_checkpoints(self, timeout: float) -> bytes | None:
        """The checkpoints a rewind may go back to (schemas/wire.md `checkpoints`) as the hub answers
        them now, or None when it did not within `timeout` s (blocks)."""
        message = self.bus.ask(self._key("checkpoints"), timeout)
        return None if message is None else message.payload

    def command(self, op: str, slot: str, value, ident: str, instructor: bool = False) -> None:
        """An operator command, sent by this view (blocks while Zenoh is congested: call it off the loop);
        `instructor`: on the instructor's key, where faults must come from and any command may."""
        key = wire.instructor_key(self.run, "command") if instructor else self._key("command")
        self.bus.put(key, command_message(op, slot, value, self.name, ident), wire.MSGPACK)

    def rate(self, key: str, period: float | None) -> None:
        """A rate request for the slots (or the bodies message) under `key`; None forgets it."""
        self.bus.put(self._key("viewer", self.name, "rate"), wire.pack({"key": key, "period": period}), wire.MSGPACK)

    def close(self) -> None:
        self.bus.close()

    def _key(self, *parts: str) -> str:
        return wire.control_key(self.run, *parts)

    def _scene(self, payload: bytes) -> dict:
        try:
            return read_scene(payload, f"the scene the hub of run {self.run!r} answered ({self.where})")
        except PlanthubError as exc:
            raise ViewError(str(exc)) from None


def slot_sample(message: Message) -> tuple[str, object, int]:
    """A data-plane sample as (object.component.slot, value, tick); a WireError if it is not one."""
    kind = _TYPES.get(message.encoding.rpartition(";")[2])
    if kind is None:
        raise wire.WireError(f"{message.key}: unknown encoding {message.encoding!r}")
    tick = wire.TICK.unpack(message.attachment)[0] if message.attachment and len(message.attachment) == 8 else -1
    name = ".".join(message.key.split("/")[2:])
    return name, wire.unpack_value(kind, message.payload), tick
