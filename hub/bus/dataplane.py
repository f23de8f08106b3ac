"""The data plane: every exposed slot on `plant/<run>/<object>/<component>/<slot>`, published only
while someone subscribes, at the rate subscribers asked for.

Each exposed slot has a publisher whose matching listener says when subscribers come and go (looked
at every POLL s between two points); a point publishes only the slots that have one, so a slot nobody reads costs nothing, and a body
slot nothing else reads is computed only while it is watched. A viewer asks for a rate with
`{"key": KEYEXPR, "period": SECONDS}` on `plant/<run>/@cosim/viewer/<id>/rate`, holding the
liveliness token `plant/<run>/@cosim/viewer/<id>`; a slot goes out at the fastest rate asked for
a key expression that covers it (`run.bus.publish_period` where none does; a void slot at every
point it fires), and a viewer's requests end with its token. With `run.bus.publish: change` a slot
goes out at such a point only if its value differs from the last sample sent (byte for byte, as
encoded), so a value that holds costs nothing; its current value still goes out when its first
subscriber comes and when a viewer asks for a rate that covers it. A sample's payload is the raw
value (schemas/wire.md), its attachment the tick of its communication point (uint64, little-endian).

The step loop does not send: at a point where something is due it hands a copy of the values to
the sender thread (hub/bus/outbox.py), or skips the point when the sender is still busy with an
earlier one (counted in `skipped`); void slots that fired are kept for the next point sent. Then it
lends the sender its share of time: at most 2 % of the loop's wall time, however many watch.
"""
from __future__ import annotations

import fnmatch
import math
import time

from hub.bus import wire
from hub.bus.outbox import Outbox
from hub.bus.session import Bus, Inbox, key_intersects
from hub.bus.settings import BusSettings
from hub.core.slots import Direction, SlotType

POLL = 0.05          # s between two looks at which slots have subscribers (at most: see POLL_SHARE)
POLL_SHARE = 0.002   # of the wall time those looks may take (615 publishers: 60–90 µs a look)


class _Exposed:
    __slots__ = ("ref", "key", "index", "void", "pack", "put", "publisher", "component", "period", "due", "last")

    def __init__(self, ref, key, index, kind, publisher, component):
        self.ref, self.key, self.index = ref, key, index
        self.void = kind is SlotType.VOID
        self.pack = wire.value_packer(kind)
        self.publisher, self.put = publisher, publisher.put
        self.component = component      # the component that writes it (a source), else None
        self.period = 1                 # ticks between samples (set by the step loop's thread)
        self.due = 0                    # the sender's: the first tick of its next sample
        self.last = None                # the sender's: payload of the last sample sent (publish: change)


class DataPlane:
    def __init__(self, bus: Bus, run: str, plant, settings: BusSettings):
        self.rate = plant.scenario.run.physics_rate
        self.default_period = max(1, round(settings.publish_period * self.rate))
        self.on_change = settings.publish == "change"
        self.inbox = inbox = Inbox()
        self.skipped = 0          # points with something due that the sender was too busy to take
        self._missed = None       # the last of them, sent when the run closes if nothing newer went
        self._cold: list[_Exposed] = []   # watched from the next point on: computed only from its sense
        self.requests: dict[str, dict[str, int]] = {}    # viewer id → {key expression: period in ticks}
        self.viewers: set[str] = set()   # ids of the viewers holding a token: they share the sending budget
        owners = {(c.obj, c.name): c for c in plant.components}
        self.plant = plant
        self.exposed: list[_Exposed] = []
        self._matching = []      # (entry, its publisher's matching changes), polled every POLL s at most
        self._next_poll = 0.0
        for ref, index in plant.index.items():
            if not owners[(ref.obj, ref.component)].PUBLISHED:
                continue
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
            self._matching.append((entry, publisher.matching_changes()))
        self.live: list[_Exposed] = [e for e in self.exposed if e.publisher.matching]
        self.outbox = Outbox(self.on_change)
        self._split_live()
        self._refresh_needed()
        bus.subscribe(wire.control_key(run, "viewer", "*", "rate"), lambda m: inbox.put(("rate", m)))
        bus.watch_tokens(wire.control_key(run, "viewer", "*"), lambda m: inbox.put(("viewer", m)))

    @property
    def samples(self) -> int:
        """Data-plane samples sent so far."""
        return self.outbox.samples

    def publish(self, tick: int, signals) -> None:
        """Hand this point to the sender if something is due (the observe step of the step loop,
        hub/run/master.py); never waits for it."""
        if self._cold:   # they were computed at this point
            self.outbox.reset(self._cold)
            self._cold = []
            self._split_live()
        if not self.inbox.empty() or time.perf_counter() >= self._next_poll:
            self.update()
        if not self.live:
            return
        out = self.outbox
        fired = [e for e in self._voids if signals.fired(e.index)] if self._voids else ()
        if tick >= out.wanted:
            values = signals.values.copy()   # the values are immutable objects: a shallow copy is a snapshot
            if out.offer(tick, values, self._valued, fired):
                self._missed = None
            else:
                self.skipped += 1
                self._missed = (tick, values, self._valued)
        elif fired:
            out.offer(tick, None, (), fired)
        out.lend()

    def rebind(self, plant) -> None:
        """Publish `plant`, built again by a rewind (hub/run/rewind.py): the same slots on the same
        keys, computed by its components (what subscribers watch, they compute)."""
        owners = {(c.obj, c.name): c for c in plant.components}
        self.plant = plant
        for entry in self.exposed:
            if entry.component is not None:
                entry.component = owners[(entry.ref.obj, entry.ref.component)]
        self._refresh_needed()
        self.outbox.reset(self.live)   # what subscribers watch goes out at the next point, due or not

    def close(self) -> None:
        """Send what waits and the last point skipped, if none went out after it, and stop the
        sender (within a second or two: hub/bus/outbox.py)."""
        if self.outbox.close(self._missed):
            self.skipped -= 1   # it went out after all

    def update(self) -> None:
        """Take in subscribers that came or went and rate requests (between two points only)."""
        rates_changed = needs_changed = False
        asked_now = []   # key expressions of this update's rate requests: their slots go out afresh
        fresh = []       # entries whose current value goes out at the next point
        began = time.perf_counter()
        changes = [("match", e, m) for e, listener in self._matching if (m := listener.latest()) is not None]
        self._next_poll = time.perf_counter() + max(POLL, (time.perf_counter() - began) / POLL_SHARE)
        for kind, *rest in changes + self.inbox.drain():
            if kind == "match":
                entry, matching = rest
                if matching and entry not in self.live:
                    # A source its component computes only while watched holds a stale value until
                    # the next point's sense: it goes out from then on, not with this point's tick.
                    cold = entry.component is not None and entry.ref.slot not in entry.component.needed
                    (self._cold if cold else fresh).append(entry)
                    self.live.append(entry)
                elif not matching and entry in self.live:
                    self.live.remove(entry)
                    if entry in self._cold:
                        self._cold.remove(entry)
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
                viewer = message.key.rsplit("/", 1)[-1]
                if message.alive:
                    if viewer not in self.viewers:
                        self.outbox.welcome()
                    self.viewers.add(viewer)
                else:
                    self.viewers.discard(viewer)
                    rates_changed |= self.requests.pop(viewer, None) is not None
                self.outbox.share = max(1, len(self.viewers))
        if rates_changed:
            asked = [(k, p) for requests in self.requests.values() for k, p in requests.items()]
            for e in self.exposed:
                periods = [p for k, p in asked if key_intersects(k, e.key)]
                e.period = min(periods) if periods else self.default_period
                if self.on_change and any(key_intersects(k, e.key) for k in asked_now):
                    fresh.append(e)   # a viewer that asks gets the current values at the next point
        if fresh:
            self.outbox.reset(fresh)
        if needs_changed:
            self._split_live()
            self._refresh_needed()

    def _split_live(self) -> None:
        # The sender gets a tuple of its own: the loop may change `live` while it sends.
        cold = set(map(id, self._cold))
        self._valued = tuple(e for e in self.live if not e.void and id(e) not in cold)
        self._voids = tuple(e for e in self.live if e.void and id(e) not in cold)

    def _refresh_needed(self) -> None:
        """A component computes the sources a flow, the recording or a live subscriber reads."""
        watched: dict[int, set[str]] = {}
        for e in self.live:
            if e.component is not None:
                watched.setdefault(id(e.component), set()).add(e.ref.slot)
        for comp in {id(e.component): e.component for e in self.exposed if e.component is not None}.values():
            self.plant.watch(comp, watched.get(id(comp), ()))
