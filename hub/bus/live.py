"""Live participants (HMI, viewer, dashboard): watch slots of a running plant and send operator
commands, without ever holding the loop back."""
from __future__ import annotations

import time
import uuid
from dataclasses import dataclass

from hub.bus import wire
from hub.bus.commands import command_message
from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings
from hub.core.errors import PlanthubError
from hub.core.slots import SlotType

_TYPES = {f"planthub/{t.value}": t for t in SlotType}


__all__ = ["Sample", "Viewer"]


@dataclass(frozen=True)
class Sample:
    slot: str          # object.component.slot
    value: object      # the canonical slot value (None for a void event)
    tick: int          # the communication point it belongs to


class Viewer:
    """Watches slots by key expression and sends commands. Its liveliness token ends its rate
    requests when it goes; samples it does not fetch in time are dropped by the hub, not queued."""

    def __init__(self, run: str, connect, *, mode: str = "peer", name: str | None = None, tls=None):
        self.run = wire.check_run_name(run)
        self.id = name or uuid.uuid4().hex
        self.bus = Bus(BusSettings(mode=mode, connect=tuple(connect), tls=tls), listen=False)   # tls: hub.tls.TlsSettings
        self._samples, self._control = Inbox(), Inbox()
        self.hub_alive = False
        self.state: dict = {}
        try:
            self.bus.watch_tokens(wire.hub_token(run), lambda m: self._control.put(("hub", m.alive)))
            self.bus.subscribe(wire.control_key(run, "command", "result"),
                               lambda m: self._control.put(("result", m.payload)))
            self.bus.subscribe(wire.instructor_key(run, "command", "result"),   # a fault's, an instructor's
                               lambda m: self._control.put(("result", m.payload)))
            self.bus.subscribe(wire.control_key(run, "state"), lambda m: self._control.put(("state", m.payload)))
            self.bus.declare_token(wire.control_key(run, "viewer", self.id))
        except BaseException:
            self.bus.close()
            raise
        self._results: dict[str, dict] = {}

    def watch(self, slots: str = "**", period: float | None = None) -> None:
        """Subscribe to `plant/<run>/<slots>` (a key expression: `belt/drive/speed`, `belt/**`, `**`);
        with `period` (s), ask the hub to publish those slots no faster than that."""
        key = f"plant/{self.run}/{slots}"
        self.bus.subscribe(key, lambda m: self._samples.put(m))
        if period is not None:
            self.wait_for_hub()   # a put before the hub's subscription is known here goes nowhere
            self.bus.put(wire.control_key(self.run, "viewer", self.id, "rate"),
                         wire.pack({"key": key, "period": period}), wire.MSGPACK)

    def next(self, timeout: float) -> Sample | None:
        """The next sample, or None if none came within `timeout` s."""
        message = self._samples.get(timeout)
        if message is None:
            return None
        kind = _TYPES.get(message.encoding.rpartition(";")[2])
        if kind is None:
            raise PlanthubError(f"{message.key}: unknown encoding {message.encoding!r}")
        tick = wire.TICK.unpack(message.attachment)[0] if message.attachment else -1
        return Sample(".".join(message.key.split("/")[2:]), wire.unpack_value(kind, message.payload), tick)

    def wait_for_hub(self, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while not self.hub_alive:
            self._handle(self._control.get(deadline - time.monotonic()))
            if time.monotonic() >= deadline and not self.hub_alive:
                raise PlanthubError(f"no hub for run {self.run!r} within {timeout:g} s")

    def wait_state(self, state: str, timeout: float = 10.0) -> dict:
        """Wait until the run's state (schemas/wire.md `state`) is `state`; returns the state map."""
        deadline = time.monotonic() + timeout
        while self.state.get("state") != state:
            left = deadline - time.monotonic()
            if left <= 0:
                raise PlanthubError(f"run {self.run!r} not {state} within {timeout:g} s "
                                    f"(it is {self.state.get('state', 'unknown')})")
            self._handle(self._control.get(min(left, 0.1)))
        return self.state

    def command(self, op: str, slot: str = "", value=None, *, by: str = "", wait: float | None = 5.0,
                instructor: bool = False):
        """Send a command. With `wait` (s), return the hub's answer, a map {id, ok, tick, error}, once the
        command was applied or refused at a communication point; without, return its id (see `answer`).
        `instructor`: on the instructor's key, where a `fault` or `repair` must come from (hub/bus/commands.py)."""
        ident = uuid.uuid4().hex
        self.wait_for_hub()
        key = wire.instructor_key(self.run, "command") if instructor else wire.control_key(self.run, "command")
        self.bus.put(key, command_message(op, slot, value, by, ident), wire.MSGPACK)
        return ident if wait is None else self.answer(ident, wait)

    def answer(self, ident: str, timeout: float) -> dict:
        deadline = time.monotonic() + timeout
        while ident not in self._results:
            item = self._control.get(deadline - time.monotonic())
            if item is None:
                raise PlanthubError(f"no answer to command {ident} within {timeout:g} s (is the run going?)")
            self._handle(item)
        return self._results.pop(ident)

    def _handle(self, item) -> None:
        if item is None:
            return
        kind, value = item
        if kind == "hub":
            self.hub_alive = value
        elif kind == "result":
            result = wire.unpack(value)
            self._results[result.get("id", "")] = result
        elif kind == "state":
            self.state = wire.unpack(value)

    def close(self) -> None:
        self.bus.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
