"""The `planthub view` process: the relay (bus side) and the web side on one asyncio loop, until SIGINT or SIGTERM.

    hub ── scene (query), bodies, events, figures, state, checkpoints (also a query), results, belt speeds
                                                                                     ──► relay ─► View ─► browsers
    hub ◄── command, rate requests ──────────────────────────────────────────────── relay ◄─ View ◄─ browsers
    hub ── @instructor: faults board, fault events, results ──► relay ─► View ─► an instructor's browsers
    hub ◄── @instructor/command (fault, repair, any other) ──── relay ◄─ View ◄─ an instructor's browsers

Its role is the view's, not the browser's: an instructor's view (a certificate named in
run.bus.access.instructor, or any view of a run without access control, unless started with
`--role trainee`) shows and injects faults; a trainee's subscribes to none of it, and refuses a
fault command from its page, named, before anything goes on the bus.

The master never waits for the view: the hub sends with congestion control drop, the relay's
callbacks only hand payloads to the loop (hub/view/bridge.py), and each browser has its own
bounded writer (hub/view/browser.py). Puts on the bus, which may block while Zenoh is congested,
run on one thread of their own, in order.
"""
from __future__ import annotations

import asyncio
import logging
import time
from collections import OrderedDict, deque
from concurrent.futures import ThreadPoolExecutor

from hub.bus import wire
from hub.core.errors import PlanthubError
from hub.view import frames
from hub.view.bridge import Bridge
from hub.view.browser import close_browsers
from hub.view.frames import FAULT_OPS
from hub.view.relay import SPEEDS_PERIOD, Relay, ViewError, slot_sample
from hub.view.scene import not_instructor, refusal

FAULT_SLOT = "@fault"   # the event rows of faults: an instructor's (hub/view/broadcast.py)
INSTRUCTOR, TRAINEE = "instructor", "trainee"

_log = logging.getLogger("planthub.view")

SCENE_ASK = 1.0          # s one query for the scene waits for an answer
SCENE_RETRY = 0.25       # s between two queries nobody answered
ANSWER_TIMEOUT = 10.0    # s a browser waits for the hub's answer to its command before it is told there is none
MAX_IN_FLIGHT = 64       # commands of all browsers waiting to go on the bus
MAX_PENDING = 256        # commands waiting for their answer (older ones are forgotten)
KEPT_EVENTS = 500        # event rows a browser that connects late is given
SLOTS_FLUSH = 0.05       # s the belt speeds of one point are gathered before they go to the browsers


class View:
    """What every browser is told and what they ask for, between one Relay and the browsers' sockets."""

    def __init__(self, relay: Relay, *, control: bool = True, reason: str = "", role: str = INSTRUCTOR,
                 role_reason: str = ""):
        self.relay = relay
        self.run = relay.run
        self.loop = asyncio.get_running_loop()
        self.browsers: set = set()
        self.control = control
        self.why_not = "" if control else reason   # why the panel is off (a command is refused with it)
        self.role = role
        self.role_reason = "" if role == INSTRUCTOR else role_reason   # why this is a trainee's view
        self.faults = None   # the last faults frame (an instructor's view)
        self._hello()
        self.scene: str | None = None          # the scene frame, once the hub answered
        self.state = self.figures = None      # the last frames of each, for a browser that comes late
        self.checkpoints = None               # the last checkpoints frame: the panel's timeline
        self._checkpoints_heard = 0           # checkpoints messages the hub published (a query's answer may be older)
        self.stopped: str | None = None       # why the run stopped, once its state said so
        self.bodies: bytes | None = None
        self.events: deque = deque(maxlen=KEPT_EVENTS)
        self.hub_alive = self._hub_seen = False
        self.bodies_period: float | None = None   # the last rate a browser asked for
        self._pending: OrderedDict[str, tuple] = OrderedDict()   # command id → (browser, op, slot, ref)
        self._count = 0
        self._in_flight = 0
        self._slots: dict = {}
        self._slots_tick = None
        self._flush = None
        self._puts = ThreadPoolExecutor(1, thread_name_prefix="planthub-view-bus")
        self._tasks: set = set()
        self._malformed: set[str] = set()
        self._closed = False
        self.skipped = 0   # bodies frames not sent to a browser that was still busy with the one before

    # --- from the bus (via the bridge, on the loop) ---------------------------------------
    def deliver(self, kind: str, item) -> None:
        try:
            getattr(self, f"_on_{kind}")(item)
        except PlanthubError as exc:   # a WireError: junk on a key of the run must not end the view
            if kind not in self._malformed:
                self._malformed.add(kind)
                _log.warning("planthub view: a malformed %s message from the bus (%s); such messages are dropped",
                             kind, exc)

    def _on_bodies(self, payload: bytes) -> None:
        self.bodies = payload
        for browser in self.browsers:
            browser.send_bodies(payload)

    def _hello(self) -> None:
        self.hello = frames.frame("hello", run=self.run, control=self.control, reason=self.why_not,
                                  viewer=self.relay.name, role=self.role, role_reason=self.role_reason)

    def _on_figures(self, payload: bytes) -> None:
        figures = self._map(payload, "figures")
        if self.role != INSTRUCTOR and isinstance(figures.get("sections"), dict):
            figures["sections"].pop("faults", None)   # the hub leaves it out; a trainee's page never has it
        self.figures = self._broadcast("figures", figures)

    def _on_faults(self, payload: bytes) -> None:
        if self.role == INSTRUCTOR:
            self.faults = self._broadcast("faults", self._map(payload, "faults"))

    def _on_fault_events(self, payload: bytes) -> None:
        if self.role == INSTRUCTOR:
            self._on_events(payload, faults=True)

    def _on_state(self, payload: bytes) -> None:
        state = self._map(payload, "state")
        self.stopped = state.get("reason", "") if state.get("state") == "stopped" else None
        self.state = self._broadcast("state", state)

    def _on_checkpoints(self, payload: bytes) -> None:
        self._checkpoints_heard += 1
        self._take_checkpoints(payload)

    def _take_checkpoints(self, payload: bytes) -> None:
        """The checkpoints a rewind may go back to (schemas/wire.md `checkpoints`), for the panel's timeline."""
        message = self._map(payload, "checkpoints")
        ticks, rate = message.get("checkpoints"), message.get("rate")
        if not isinstance(ticks, list) or not all(isinstance(t, int) and not isinstance(t, bool) and t >= 0
                                                  for t in ticks):
            raise wire.WireError(f"checkpoints: expected an array of ticks, got {ticks!r:.80}")
        if not isinstance(rate, (int, float)) or isinstance(rate, bool) or not rate > 0:
            raise wire.WireError(f"checkpoints: expected a positive rate, got {rate!r:.80}")
        self.checkpoints = self._broadcast("checkpoints", message)

    async def _ask_checkpoints(self) -> None:
        """A view that joins a run already going has missed its last checkpoints message: ask for it.
        One the hub publishes meanwhile is newer than the answer, which is then dropped."""
        heard = self._checkpoints_heard
        try:
            payload = await asyncio.to_thread(self.relay.ask_checkpoints, SCENE_ASK)
        except PlanthubError as exc:
            _log.warning("planthub view: %s", exc)
            return
        if payload is not None and heard == self._checkpoints_heard:
            self.deliver("asked_checkpoints", payload)

    def _on_asked_checkpoints(self, payload: bytes) -> None:
        self._take_checkpoints(payload)

    def _on_events(self, payload: bytes, faults: bool = False) -> None:
        rows = wire.unpack(payload)
        if not isinstance(rows, list):
            raise wire.WireError(f"events: expected an array of rows, got {type(rows).__name__}")
        if not faults:   # the public rows hold none (hub/view/broadcast.py); an older hub's are dropped here
            rows = [r for r in rows if not (isinstance(r, list) and len(r) > 1 and r[1] == FAULT_SLOT)]
            if not rows:
                return
        self.events.extend(rows)
        self._broadcast("events", {"rows": rows})

    def _on_result(self, payload: bytes) -> None:
        result = self._map(payload, "command result")
        ident = result.get("id")
        sent = self._pending.pop(ident, None) if isinstance(ident, str) else None
        extra = {"op": sent[1], "slot": sent[2], "ref": sent[3]} if sent else {}
        self._broadcast("result", {**result, **extra})

    def _on_slot(self, message) -> None:
        name, value, tick = slot_sample(message)
        if self._slots and tick != self._slots_tick:
            self._flush_slots()
        self._slots[name], self._slots_tick = value, tick
        if self._flush is None:
            self._flush = self.loop.call_later(SLOTS_FLUSH, self._flush_slots)

    def _flush_slots(self) -> None:
        if self._flush is not None:
            self._flush.cancel()
            self._flush = None
        if self._slots:
            self._broadcast("slots", {"tick": self._slots_tick, "values": self._slots})
            self._slots = {}

    def _on_hub(self, alive: bool) -> None:
        if alive == self.hub_alive:
            return
        self.hub_alive = alive
        self._broadcast("hub", {"alive": alive})
        if not alive:
            if self.stopped is not None:   # it said so before it left: no surprise
                _log.info("planthub view: the run %r stopped (%s); waiting for another", self.run, self.stopped)
            else:
                _log.warning("planthub view: the hub of run %r went away (%s); waiting for it", self.run,
                             self.relay.where)
            return
        # The hub declares its subscribers before its token: a rate request put now reaches it.
        self._put(self.relay.rate, self.relay.speeds, SPEEDS_PERIOD)
        if self.bodies_period is not None:
            self._put(self.relay.rate, wire.control_key(self.run, "bodies"), self.bodies_period)
        self._spawn(self._ask_checkpoints())
        if self._hub_seen:   # it came back: maybe another run of the same name, with another scene
            _log.warning("planthub view: the hub of run %r is back", self.run)
            self._spawn(self._refetch())
        self._hub_seen = True

    async def _refetch(self) -> None:
        try:
            scene = await fetch_scene(self.relay, 10.0, lambda: self.hub_alive)
        except ViewError as exc:
            _log.warning("planthub view: %s", exc)
            return
        self.take_scene(scene, broadcast=True)

    def take_scene(self, scene: dict, broadcast: bool = False) -> None:
        """The scene the hub answered; under its access control (the scene's `access`), a view whose
        certificate may only watch greys its panel out and says why (hub/view/scene.py)."""
        why = refusal(scene, self.relay.common_name)
        if why and self.control:
            self.control, self.why_not = False, why
        if self.role == INSTRUCTOR:
            not_one = not_instructor(scene, self.relay.common_name)
            if not_one:
                self.role, self.role_reason = TRAINEE, not_one
                _log.warning("planthub view: a trainee's view: %s", not_one)
            else:
                self.relay.instruct()
        self._hello()
        if broadcast:
            self.scene = self._broadcast("scene", {"scene": scene})
        else:
            self.scene = frames.frame("scene", scene=scene)

    # --- from the browsers ---------------------------------------------------------------
    def attach(self, browser) -> None:
        self.browsers.add(browser)
        browser.send(self.hello)
        if self.scene is not None:
            browser.send(self.scene)
        browser.send(frames.frame("hub", alive=self.hub_alive))
        for text in (self.state, self.figures, self.checkpoints, self.faults if self.role == INSTRUCTOR else None):
            if text is not None:
                browser.send(text)
        if self.events:
            browser.send(frames.frame("events", rows=list(self.events)))
        if self.bodies is not None:
            browser.send_bodies(self.bodies)

    def detach(self, browser) -> None:
        self.browsers.discard(browser)
        self.skipped += browser.dropped

    def receive(self, browser, text) -> None:
        try:
            request = frames.parse(text)
        except frames.FrameError as exc:
            browser.send(frames.frame("error", error=str(exc)))
            return
        if isinstance(request, frames.RateRequest):
            self.bodies_period = request.period
            if self.hub_alive:
                self._put(self.relay.rate, wire.control_key(self.run, "bodies"), request.period)
            return
        if isinstance(request, frames.PlaybackRequest):
            browser.send(frames.frame("error", op=request.op, error=f"this view shows the run {self.run!r} live: "
                                      "playback is for a recorded run (`planthub view RUN_DIR`)"))
            return
        self._command(browser, request)

    def _command(self, browser, request: frames.CommandRequest) -> None:
        def refuse(why: str) -> None:
            browser.send(frames.frame("error", error=why, op=request.op, slot=request.slot, ref=request.ref))

        if request.op in FAULT_OPS and self.role != INSTRUCTOR:
            return refuse(f"{request.op}: this is a trainee's view ({self.role_reason}): faults are an instructor's; "
                          "the command was not sent")
        if not self.control:
            return refuse(f"this view only watches ({self.why_not}): the command was not sent")
        if not self.hub_alive:
            return refuse(f"the hub of run {self.run!r} is not there ({self.relay.where}): the command was not sent")
        if self._in_flight >= MAX_IN_FLIGHT:
            return refuse(f"{MAX_IN_FLIGHT} commands are still waiting to go out: the command was not sent")
        self._count += 1
        ident = f"{self.relay.name}-{self._count}"
        self._pending[ident] = (browser, request.op, request.slot, request.ref)
        while len(self._pending) > MAX_PENDING:
            self._pending.popitem(last=False)
        self._put(self.relay.command, request.op, request.slot, request.value, ident, self.role == INSTRUCTOR,
                  failed=lambda exc: refuse(f"the command could not be sent: {exc}"))
        self.loop.call_later(ANSWER_TIMEOUT, self._unanswered, ident)

    def _unanswered(self, ident: str) -> None:
        sent = self._pending.pop(ident, None)
        if sent is not None:
            browser, op, slot, ref = sent
            browser.send(frames.frame("error", id=ident, op=op, slot=slot, ref=ref,
                                      error=f"no answer from the hub of run {self.run!r} within "
                                            f"{ANSWER_TIMEOUT:g} s (is the run going?)"))

    # --- helpers ----------------------------------------------------------------------------
    def _broadcast(self, kind: str, body: dict) -> str:
        text = frames.frame(kind, body)
        for browser in self.browsers:
            browser.send(text)
        return text

    @staticmethod
    def _map(payload: bytes, what: str) -> dict:
        message = wire.unpack(payload)
        if not isinstance(message, dict):
            raise wire.WireError(f"{what}: expected a map, got {type(message).__name__}")
        return message

    def _put(self, function, *args, failed=None) -> None:
        """`function(*args)` on the bus thread, in order; `failed(exc)` on the loop if it raised."""
        self._in_flight += 1
        future = self.loop.run_in_executor(self._puts, function, *args)

        def done(f) -> None:
            self._in_flight -= 1
            if f.cancelled():
                return
            exc = f.exception()
            if exc is not None:
                _log.warning("planthub view: %s", exc)
                if failed is not None:
                    failed(exc)
        future.add_done_callback(done)

    def _spawn(self, coroutine) -> None:
        task = self.loop.create_task(coroutine)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def close(self) -> None:
        """Close every browser's socket ("going away") and stop sending (once; again does nothing)."""
        if self._closed:
            return
        self._closed = True
        for task in list(self._tasks):
            task.cancel()
        await close_browsers(self.browsers)
        self._puts.shutdown(wait=False, cancel_futures=True)
        skipped = self.skipped + sum(b.dropped for b in self.browsers)
        if skipped:
            _log.info("planthub view: %d bodies frames skipped for browsers still busy with the one before", skipped)


async def fetch_scene(relay: Relay, timeout: float, hub_seen=lambda: False) -> dict:
    """The scene, asked for until the hub answers (ViewError after `timeout` s; `hub_seen()` tells
    whether the hub's token is there, for the message)."""
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        scene = await asyncio.to_thread(relay.ask_scene, max(0.1, min(SCENE_ASK, left)))
        if scene is not None:
            return scene
        if time.monotonic() >= deadline:
            why = ("its hub is there but answers no scene query (a planthub older than this view?)" if hub_seen()
                   else "is `planthub run` going there (--listen on that endpoint), and is the run named "
                        f"{relay.run!r} (its scenario's name)?")
            raise ViewError(f"no scene from the hub of run {relay.run!r} at {relay.where} within {timeout:g} s: {why}")
        await asyncio.sleep(min(SCENE_RETRY, max(0.0, deadline - time.monotonic())))


async def serve(relay: Relay, *, host: str, port: int, bundle, control: bool = True, reason: str = "",
                timeout: float = 30.0, announce=print, opened=None, role: str = INSTRUCTOR,
                role_reason: str = "") -> int:
    """Join the run, serve the browsers until SIGINT or SIGTERM; the exit status (130, 143).
    `announce(url)` tells where to open the page once it is served, `opened(url)` may open it."""
    from hub.view.http import serve_page, signal_stop

    loop = asyncio.get_running_loop()
    with signal_stop(loop) as stop:
        view = None
        try:
            view = View(relay, control=control, reason=reason, role=role, role_reason=role_reason)
            relay.join(Bridge(loop, view.deliver))
            fetching = loop.create_task(fetch_scene(relay, timeout, lambda: view.hub_alive))
            await asyncio.wait({fetching, stop}, return_when=asyncio.FIRST_COMPLETED)
            if stop.done():
                fetching.cancel()
                await asyncio.gather(fetching, return_exceptions=True)
                return 128 + stop.result()
            view.take_scene(fetching.result())
            return await serve_page(view, stop, host=host, port=port, bundle=bundle, announce=announce,
                                    opened=opened)
        finally:
            if view is not None:
                await view.close()
