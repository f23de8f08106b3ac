"""The hub's side of a view: the scene on a queryable, and — while someone subscribes — every body's
pose, the parts' state, the event log and the plant's figures (schemas/scene.schema.json `bodies_message`).

An observer (hub/core/observer.py) of the run, part of its bus link. What it sends is small and
goes out with congestion control *drop*, so a slow view loses messages, never holds the loop:

- `plant/<run>/@cosim/scene`: answered from bytes made at the start (a late joiner asks any time);
- `plant/<run>/@cosim/bodies`: one message per due point, all bodies in play in one array
  (150 bottles: about 6 kB), at most every `period` s of plant time (PERIOD, or the fastest a
  viewer asked for with a rate request on this key);
- `plant/<run>/@cosim/events`: the event-log rows since the last message, at the same points;
- `plant/<run>/@cosim/figures`: the contributed summary sections and the real-time factor, about
  every FIGURES_EVERY s of wall time, and once more when the run ends (`ended`: an exercise's
  score);
- `plant/<run>/@instructor/faults` and `…/@instructor/events`: what only an instructor sees —
  the faults' board (`faults_message`) and the event rows of faults (slot `@fault`), which the
  public events and figures leave out; so does an exercise's `recover_within` goal, whose
  measure names the faults, until the run ends.

Who subscribes is looked at every POLL s of wall time (Zenoh's matching status), as the data plane does.
"""
from __future__ import annotations

import math
import time

from hub.bus import wire
from hub.bus.session import Bus, Inbox, key_intersects
from hub.core.observer import BodyLook
from hub.view.scene import scene_bytes

PERIOD = 0.05          # s of plant time between two bodies messages by default (20 Hz)
FIGURES_EVERY = 1.0    # s of wall time between two figures messages
POLL = 0.05            # s of wall time between two looks at who subscribes
MAX_EVENTS = 4096      # event rows kept for the next message; beyond, the oldest are dropped (counted)
JSON = "application/json"
FAULT_SLOT = "@fault"  # the event rows of faults (hub/bus/commands.py): the instructor's only


class Broadcast:
    def __init__(self, bus: Bus, run: str, plant, *, looks=(), figures=lambda: [], faults=None):
        self.run, self.plant, self.world = run, plant, plant.world
        self.looks = [look for look in looks if isinstance(look, BodyLook)]
        self.figures = figures            # () → the contributed observers with a summary section now
        self.faults = faults              # the instructor's board (hub/run/faults.py Board: version, board()), or None
        self.rate = self.world.rate
        self.default_period = max(1, round(PERIOD * self.rate))
        self.period = self.default_period
        self.requests: dict[str, int] = {}   # viewer id → ticks between bodies messages it asked for
        self.events_lost = 0
        self.sent = 0                        # bodies messages sent
        self._events: list = []
        self._due = 0
        self._next_poll = 0.0
        self._next_figures = 0.0
        self._started = None                 # (wall, tick) at the first point
        self._scene = scene_bytes(plant, run)
        self.key = wire.control_key(run, "bodies")
        self._bodies = bus.publisher(self.key, wire.MSGPACK, lossy=True, express=False)
        self._event_pub = bus.publisher(wire.control_key(run, "events"), wire.MSGPACK, lossy=True, express=False)
        self._figure_pub = bus.publisher(wire.control_key(run, "figures"), wire.MSGPACK, lossy=True)
        self._watched = self._events_watched = self._figures_watched = False
        self._fault_rows: list = []
        self._board_pub = self._fault_event_pub = None
        self._board_watched = self._fault_events_watched = False
        self._board_version = None
        self._next_board = 0.0
        self._tick = 0
        if faults is not None:
            self._board_pub = bus.publisher(wire.instructor_key(run, "faults"), wire.MSGPACK, lossy=True)
            self._fault_event_pub = bus.publisher(wire.instructor_key(run, "events"), wire.MSGPACK, lossy=True,
                                                  express=False)
        self.inbox = inbox = Inbox()
        bus.answer(wire.control_key(run, "scene"), lambda: self._scene, JSON)
        bus.subscribe(wire.control_key(run, "viewer", "*", "rate"), lambda m: inbox.put(("rate", m)))
        bus.watch_tokens(wire.control_key(run, "viewer", "*"), lambda m: inbox.put(("viewer", m)))

    def rebind(self, plant, *, looks=(), faults=None) -> None:
        """Feed `plant`, built again by a rewind (hub/run/rewind.py), with its contributed `looks`
        and the instructor's board `faults`. The scene (the plant's structure, the same for a plant
        built again), the publishers and the viewers with their rate requests stay; the clock starts
        again: the bodies at the next point, the real-time factor from there, the board at once."""
        self.plant, self.world, self.faults = plant, plant.world, faults
        self.looks = [look for look in looks if isinstance(look, BodyLook)]
        self._due, self._started = 0, None
        self._board_version = None

    def observe(self, tick: int, signals, events) -> None:
        now = time.perf_counter()
        if self._started is None:
            self._started = (now, tick)
        if now >= self._next_poll:
            self._poll(now)
        self._tick = tick
        if events and any(e[1] == FAULT_SLOT for e in events):
            if self._fault_events_watched:
                self._fault_rows.extend(e for e in events if e[1] == FAULT_SLOT)
            events = [e for e in events if e[1] != FAULT_SLOT]
        if self._events_watched and events:
            self._events.extend(events)
            if len(self._events) > MAX_EVENTS:
                self.events_lost += len(self._events) - MAX_EVENTS
                del self._events[:len(self._events) - MAX_EVENTS]
        if tick >= self._due and (self._watched or self._events):
            self._due = tick + self.period
            if self._watched:
                self._bodies.put(wire.pack(self.message(tick)))
                self.sent += 1
            if self._events:
                self._event_pub.put(wire.pack([list(e) for e in self._events]))
                self._events = []
        if self._fault_rows:
            self._fault_event_pub.put(wire.pack([list(e) for e in self._fault_rows]))
            self._fault_rows = []
        if self._figures_watched and now >= self._next_figures:
            self._next_figures = now + FIGURES_EVERY
            self._figure_pub.put(wire.pack(self.figures_message(tick, now)))
        if self._board_watched and self.faults is not None:
            self._send_board(tick, now)

    def idle(self, tick: int) -> None:
        """The run is held at `tick`: a view that joins meanwhile gets the bodies, about every POLL s."""
        now = time.perf_counter()
        if now >= self._next_poll:
            watched = self._watched
            self._poll(now)
            if self._watched and (not watched or self._due <= tick):   # a newcomer: _due was reset
                self._bodies.put(wire.pack(self.message(tick)))
                self.sent += 1
                self._due = tick + self.period

    def close(self, reason: str = "") -> None:
        """The figures once more, marked `ended`: the run's last word on them (an exercise's score),
        and the instructor's board as it ends. A view that missed it still has the run's state."""
        try:
            now = time.perf_counter()
            if self._started is not None and self._figure_pub.matching:
                self._figure_pub.put(wire.pack({**self.figures_message(self._tick, now, ended=True), "ended": True}))
            if self._board_pub is not None and self._board_pub.matching:
                self._board_version = None
                self._send_board(self._tick, now)
        except Exception:   # the run is ending anyway: a view misses its last figures, nothing more
            pass

    def _send_board(self, tick: int, now: float) -> None:
        """The board when a fault began or ended, and about every FIGURES_EVERY s of wall time."""
        version = self.faults.version
        if version != self._board_version or now >= self._next_board:
            self._board_version, self._next_board = version, now + FIGURES_EVERY
            self._board_pub.put(wire.pack({"tick": tick, "time": tick / self.rate, **self.faults.board()}))

    def message(self, tick: int) -> dict:
        """The bodies message of this point (schemas/scene.schema.json `bodies_message`)."""
        state = self.world.scene_state()
        out = {"tick": tick, "time": tick / self.rate, "rows": state.rows.astype("<u2").tobytes(),
               "poses": state.poses.astype("<f4").tobytes(), "parts": state.parts.tobytes(),
               "moving": state.moving.astype("<f4").tobytes(), "triggers": state.triggers.tobytes(),
               "arms": state.arms.astype("<f4").tobytes()}
        rows = state.rows.tolist()
        for look in self.looks:
            out.update(look.look(rows))
        return out

    def figures_message(self, tick: int, now: float, ended: bool = False) -> dict:
        wall0, tick0 = self._started
        wall = now - wall0
        simulated = (tick - tick0) / self.rate
        rtf = simulated / wall if wall > 0 else None
        sections = {s.key: s.as_dict() for s in (f.section() for f in self.figures())}
        sections.pop("faults", None)   # an instructor's (the board): a trainee watches this key
        exercise = sections.get("exercise")
        if exercise is not None and not ended:
            for goal in exercise["goals"]:
                if goal["goal"] == "recover_within":   # its measure names the faults: judged at the end
                    goal["met"], goal["measured"] = None, "judged when the run ends"
        return {"tick": tick, "time": tick / self.rate, "wall": wall,
                "rtf": rtf if rtf is None or math.isfinite(rtf) else None, "sections": sections}

    def _poll(self, now: float) -> None:
        self._next_poll = now + POLL
        self._watched = self._bodies.matching
        self._events_watched = self._event_pub.matching
        watched = self._figure_pub.matching
        if watched and not self._figures_watched:
            self._next_figures = now   # a newcomer gets the figures at once
        self._figures_watched = watched
        if not self._events_watched:
            self._events = []
        if self._board_pub is not None:
            board = self._board_pub.matching
            if board and not self._board_watched:
                self._board_version = None   # a newcomer gets the board at once
            self._board_watched = board
            self._fault_events_watched = self._fault_event_pub.matching
        changed = False
        for kind, message in self.inbox.drain():
            viewer = message.key.split("/")[-2 if kind == "rate" else -1]
            if kind == "viewer":
                if not message.alive:
                    changed |= self.requests.pop(viewer, None) is not None
                else:
                    self._due = 0   # a newcomer gets the bodies at once (also while the run is held)
                continue
            try:
                request = wire.unpack(message.payload)
                key, period = request["key"], request.get("period")
                covers = key_intersects(key, self.key)
            except Exception:
                continue   # a malformed request changes nothing (as on the data plane)
            if not covers:
                continue
            if isinstance(period, (int, float)) and not isinstance(period, bool) and math.isfinite(period) \
                    and period >= 0:
                self.requests[viewer] = max(1, round(period * self.rate))
            else:
                self.requests.pop(viewer, None)
            changed = True
        if changed:
            self.period = min(self.requests.values(), default=self.default_period)
            self._due = 0
