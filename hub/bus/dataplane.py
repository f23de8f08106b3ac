"""The data plane: every exposed slot on `plant/<run>/<object>/<component>/<slot>`, published only
while someone subscribes, at the rate subscribers asked for.

Each exposed slot has a publisher whose matching listener says when subscribers come and go; a
point publishes only the slots that have one, so a slot nobody reads costs nothing, and a body
slot nothing else reads is computed only while it is watched. A viewer asks for a rate with
`{"key": KEYEXPR, "period": SECONDS}` on `plant/<run>/@cosim/viewer/<id>/rate`, holding the
liveliness token `plant/<run>/@cosim/viewer/<id>`; a slot goes out at the fastest rate asked for
a key expression that covers it (`run.bus.publish_period` where none does; a void slot at every
point it fires), and a viewer's requests end with its token. With `run.bus.publish: change` a slot
goes out at such a point only if its value differs from the last sample sent (byte for byte, as
encoded), so a value that holds costs nothing; its current value still goes out when its first
subscriber comes and when a viewer asks for a rate that covers it. A sample's payload is the raw
value (schemas/wire.md), its attachment the tick of its communication point (uint64, little-endian).
"""
from __future__ import annotations

import fnmatch
import math

from hub.bus.session import Bus, Inbox, key_intersects
from hub.bus.settings import BusSettings
from hub.core.slots import Direction, SlotType
from hub.bus import wire


class _Exposed:
    __slots__ = ("ref", "key", "index", "void", "pack", "put", "publisher", "component", "period", "due", "last")

    def __init__(self, ref, key, index, kind, publisher, component):
        self.ref, self.key, self.index = ref, key, index
        self.void = kind is SlotType.VOID
        self.pack = wire.value_packer(kind)
        self.publisher, self.put = publisher, publisher.put
        self.component = component      # the component that writes it (a source), else None
        self.period = 1
        self.due = 0
        self.last = None                # payload of the last sample sent (publish: change); None: send the next


class DataPlane:
    def __init__(self, bus: Bus, run: str, plant, settings: BusSettings):
        self.rate = plant.scenario.run.physics_rate
        self.default_period = max(1, round(settings.publish_period * self.rate))
        self.on_change = settings.publish == "change"
        self.inbox = inbox = Inbox()
        self.samples = 0
        self.requests: dict[str, dict[str, int]] = {}    # viewer id → {key expression: period in ticks}
        owners = {(c.obj, c.name): c for c in plant.components}
        self.plant = plant
        self.exposed: list[_Exposed] = []
        for ref, index in plant.index.items():
            if not any(fnmatch.fnmatchcase(str(ref), p) or fnmatch.fnmatchcase(f"{ref.obj}.{ref.component}", p)
                       or fnmatch.fnmatchcase(ref.obj, p) for p in settings.expose):
                continue
            slot = plant.signals.slots[index]
            key = wire.data_key(run, ref)
            publisher = bus.publisher(key, wire.value_encoding(slot.type), lossy=True, express=False)
            owner = owners[(ref.obj, ref.component)] if slot.direction is Direction.SOURCE else None
            entry = _Exposed(ref, key, index, slot.type, publisher, owner)
            entry.period = self.default_period
            self.exposed.append(entry)
            publisher.on_matching(lambda matching, e=entry: inbox.put(("match", e, matching)))
        self.live: list[_Exposed] = [e for e in self.exposed if e.publisher.matching]
        self._refresh_needed()
        bus.subscribe(wire.control_key(run, "viewer", "*", "rate"), lambda m: inbox.put(("rate", m)))
        bus.watch_tokens(wire.control_key(run, "viewer", "*"), lambda m: inbox.put(("viewer", m)))

    def publish(self, tick: int, signals) -> None:
        """Send what subscribers asked for at this point (the observe step of the step loop, hub/run/master.py)."""
        if not self.inbox.empty():
            self.update()
        if not self.live:
            return
        values, fired, on_change = signals.values, signals.fired, self.on_change
        attachment = wire.TICK.pack(tick)
        for e in self.live:
            if e.void:   # an event is sent whenever it fires: a slower rate must not lose it
                if not fired(e.index):
                    continue
                payload = b""
            elif tick < e.due:
                continue
            else:
                payload = e.pack(values[e.index])
                if on_change:
                    if payload == e.last:
                        continue   # still due: a change goes out at the first point it shows
                    e.last = payload
            e.put(payload, attachment=attachment)
            e.due = tick + e.period
            self.samples += 1

    def update(self) -> None:
        """Take in subscribers that came or went and rate requests (between two points only)."""
        rates_changed = needs_changed = False
        asked_now = []   # key expressions of this update's rate requests: their slots go out afresh
        for kind, *rest in self.inbox.drain():
            if kind == "match":
                entry, matching = rest
                if matching and entry not in self.live:
                    entry.due, entry.last = 0, None
                    self.live.append(entry)
                elif not matching and entry in self.live:
                    self.live.remove(entry)
                needs_changed = True
            elif kind == "rate":
                message = rest[0]
                viewer = message.key.split("/")[-2]
                try:
                    request = wire.unpack(message.payload)
                    key, period = request["key"], request.get("period")
                    key_intersects(key, key)
                except Exception:
                    continue   # a malformed request changes nothing
                asked = self.requests.setdefault(viewer, {})
                if isinstance(period, (int, float)) and not isinstance(period, bool) and math.isfinite(period) \
                        and period >= 0:
                    asked[key] = max(1, round(period * self.rate))
                else:
                    asked.pop(key, None)
                asked_now.append(key)
                rates_changed = True
            elif kind == "viewer":
                message = rest[0]
                if not message.alive:
                    rates_changed |= self.requests.pop(message.key.rsplit("/", 1)[-1], None) is not None
        if rates_changed:
            asked = [(k, p) for requests in self.requests.values() for k, p in requests.items()]
            for e in self.exposed:
                periods = [p for k, p in asked if key_intersects(k, e.key)]
                e.period = min(periods) if periods else self.default_period
                if self.on_change and any(key_intersects(k, e.key) for k in asked_now):
                    e.due, e.last = 0, None   # a viewer that asks gets the current values at the next point
        if needs_changed:
            self._refresh_needed()

    def _refresh_needed(self) -> None:
        """A component computes the sources a flow, the recording or a live subscriber reads."""
        watched: dict[int, set[str]] = {}
        for e in self.live:
            if e.component is not None:
                watched.setdefault(id(e.component), set()).add(e.ref.slot)
        for comp in {id(e.component): e.component for e in self.exposed if e.component is not None}.values():
            self.plant.watch(comp, watched.get(id(comp), ()))
