"""Playback of a recorded run (`planthub view RUN_DIR`): a clock per browser over the recording — play, pause, speed, seek — and at its time what the bus would have brought: the bodies, the events so far, the recorded slots.

    RUN_DIR: bodies.arrows, scene.json, events.csv, recording.csv, summary.json ──► Playback ─► Session (clock) ─► browser

The page is the live view's (hub/view/web/), told by hello's `"mode": "playback"` to show its
playback bar instead of the operator panel. Each browser has a clock of its own, so two people
reviewing the same run scrub independently. Bodies frames go out at a wall-clock rate (one every
`period / speed` s, between MIN_FRAME and MAX_FRAME), each the recorded point at or before the
clock's tick; the page interpolates between them as it does between the hub's. After a seek the
state frame says `jump`, so the page does not interpolate across it. No bus here: everything comes
from the folder (hub/view/run_folder.py).

What a page is sent, in order: hello (`mode: "playback"`, `control: false` with the reason, the
recording's `start` and `end` in s, the physics `rate`), the scene, a state (`"recorded"`, how
the run ended), the run's final figures from summary.json (`final: true`: not recomputed at the
playback time), one "recording" frame (every numeric recorded slot over the whole run), then at
every change a "playback" frame {op, time, tick, playing, speed, jump} followed by what the new
time brings: the bodies (binary, as the bus carries them), "events" rows up to it (`reset: true`:
the page's log starts anew — the first frame, after a seek back or far ahead), "slots" (the
recording.csv row at it). A page asks {"type": "playback", "op": "play" | "pause" | "speed" |
"seek", "value": …} (hub/view/frames.py checks them); a "rate" frame sets the samples' period; a
command is refused: there is nothing to operate.
"""
from __future__ import annotations

import asyncio
import logging
import time

import numpy as np

from hub.bus.wire import pack
from hub.view import frames
from hub.view.browser import close_browsers
from hub.view.run_folder import IN_PLAY, RecordedRun

_log = logging.getLogger("planthub.view")

REASON = "a recorded run: nothing to operate"
VIEWER = "playback"
PERIOD = 0.05         # s of plant time between two bodies frames at 1× (the hub's default, 20 per s)
MIN_FRAME = 0.02      # s of wall time: at most 50 bodies frames per s, however fast it plays …
MAX_FRAME = 0.1       # … and at least 10 while playing, however slow
SLOTS_EVERY = 0.2     # s of wall time between two slots frames while playing (the live view's SPEEDS_PERIOD)
KEPT_EVENTS = 500     # event rows a page is given after a seek that skips more (as a live browser that comes late)
EVENTS_FRAME = 2000   # event rows in one frame at most
SERIES_POINTS = 2000  # points of one series in the recording frame at most (a chart is a few hundred px wide)


class Clock:
    """Plant time over a recording's span [start, end]: moved by the wall clock (`now`) times `speed`
    while playing, held while paused, set by a seek."""

    def __init__(self, start: float, end: float, now=time.monotonic):
        self.start, self.end = start, end
        self._now = now
        self._time, self._wall = start, now()
        self.playing = False
        self.speed = 1.0

    @property
    def time(self) -> float:
        if not self.playing:
            return self._time
        return min(self.end, self._time + self.speed * (self._now() - self._wall))

    @property
    def at_end(self) -> bool:
        return self.time >= self.end

    def _hold(self) -> None:
        self._time, self._wall = self.time, self._now()

    def play(self) -> bool:
        """Play on; from the start again when it stood at the end (True: it jumped there)."""
        self._hold()
        jumped = self._time >= self.end
        if jumped:
            self._time = self.start
        self.playing = True
        return jumped

    def pause(self) -> None:
        self._hold()
        self.playing = False

    def set_speed(self, speed: float) -> None:
        self._hold()
        self.speed = speed

    def seek(self, time: float) -> None:
        self._time, self._wall = min(self.end, max(self.start, time)), self._now()


class Playback:
    """The view of one recorded run for hub/view/http.py — attach, detach, receive, close, as the live
    View of hub/view/server.py — with a Session per browser."""

    def __init__(self, recorded: RecordedRun):
        self.recorded = r = recorded
        self.hello = frames.frame("hello", run=r.run, mode="playback", control=False, reason=REASON,
                                  viewer=VIEWER, start=r.start, end=r.end, rate=r.rate)
        self.scene = frames.frame("scene", scene=r.scene)
        self.state = frames.frame("state", state="recorded", tick=int(r.bodies.ticks[-1]), time=r.end,
                                  reason=r.ended() or f"recorded in {r.directory}")
        figures = r.figures()
        self.figures = None if figures is None else frames.frame("figures", figures)
        self.recording = frames.frame("recording", recording_series(r))
        self.sessions: dict = {}
        self._closed = False

    def attach(self, browser) -> None:
        for text in (self.hello, self.scene, self.state, self.figures, self.recording):
            if text is not None:
                browser.send(text)
        session = self.sessions[browser] = Session(self.recorded, browser)
        session.show(op="open", jump=True)

    def detach(self, browser) -> None:
        session = self.sessions.pop(browser, None)
        if session is not None:
            session.stop()

    def receive(self, browser, text) -> None:
        try:
            request = frames.parse(text)
        except frames.FrameError as exc:
            browser.send(frames.frame("error", error=str(exc)))
            return
        session = self.sessions.get(browser)
        if isinstance(request, frames.CommandRequest):
            browser.send(frames.frame("error", error=f"{REASON}: the command was not sent", op=request.op,
                                      slot=request.slot, ref=request.ref))
        elif session is not None and isinstance(request, frames.RateRequest):
            session.period = PERIOD if request.period is None else request.period
        elif session is not None:
            session.handle(request)

    async def close(self) -> None:
        """Stop every clock and close every browser's socket ("going away"); once."""
        if self._closed:
            return
        self._closed = True
        for session in self.sessions.values():
            session.stop()
        await close_browsers(self.sessions)


class Session:
    """One browser's playback: its clock, what of the recording it was sent, the task that plays."""

    def __init__(self, recorded: RecordedRun, browser):
        self.recorded = recorded
        self.browser = browser
        self.clock = Clock(recorded.start, recorded.end)
        self.period = PERIOD
        self.shown = -1          # the recorded point last sent
        self.events: int | None = None   # event rows sent: the first so many (None: none yet)
        self.slots_row = -1      # the recording row last sent
        self._slots_due = 0.0
        self._task: asyncio.Task | None = None

    def handle(self, request: frames.PlaybackRequest) -> None:
        clock, jump = self.clock, False
        if request.op == "play":
            jump = clock.play()
        elif request.op == "pause":
            clock.pause()
        elif request.op == "speed":
            clock.set_speed(request.value)
        else:
            r = self.recorded
            if not r.start - 1e-9 <= request.value <= r.end + 1e-9:
                self.browser.send(frames.frame("error", error=f"seek to {request.value:g} s: the recording spans "
                                                              f"{r.start:g} to {r.end:g} s", op="seek"))
                return
            clock.seek(request.value)
            jump = True
        self.show(op=request.op, jump=jump)
        if clock.playing and self._task is None:
            self._task = asyncio.get_running_loop().create_task(self._play())

    def show(self, *, op: str = "", jump: bool = False) -> None:
        """Send the page what it lacks at the clock's time: the state (first, when `op` says what
        changed it), the bodies, the events, the recorded slots."""
        r, browser = self.recorded, self.browser
        now = time.monotonic()
        t = self.clock.time
        tick = r.tick_at(t)
        if op:
            browser.send(frames.frame("playback", op=op, time=t, tick=tick, playing=self.clock.playing,
                                      speed=self.clock.speed, jump=jump))
        i = r.bodies.index_at(tick)
        if i != self.shown or jump:
            self.shown = i
            browser.send_bodies(pack(r.bodies.message(i, r.rate)))
        count = r.events.count_to(tick)
        if self.events is None or count < self.events or count - self.events > KEPT_EVENTS:
            # the first, back, or far ahead: the page's log starts anew
            browser.send(frames.frame("events", rows=r.events.rows[max(0, count - KEPT_EVENTS):count], reset=True))
            self.events = count
        while self.events < count:
            upto = min(count, self.events + EVENTS_FRAME)
            browser.send(frames.frame("events", rows=r.events.rows[self.events:upto]))
            self.events = upto
        row = r.slots.index_at(tick)
        if row is not None and row != self.slots_row and (op or now >= self._slots_due):
            self.slots_row, self._slots_due = row, now + SLOTS_EVERY
            browser.send(frames.frame("slots", tick=int(r.slots.ticks[row]), values=r.slots.values(row)))

    def interval(self) -> float:
        """Wall s until the next bodies frame while playing."""
        return min(MAX_FRAME, max(MIN_FRAME, self.period / self.clock.speed))

    async def _play(self) -> None:
        try:
            while self.clock.playing and not self.browser.closing:
                await asyncio.sleep(self.interval())
                if not self.clock.playing:
                    break
                if self.clock.at_end:
                    self.clock.pause()
                    self.show(op="end")
                    break
                self.show()
        finally:
            self._task = None

    def stop(self) -> None:
        self.clock.pause()
        if self._task is not None:
            self._task.cancel()


def recording_series(recorded: RecordedRun) -> dict:
    """The "recording" frame's body: every numeric recorded slot over the whole run, for the page's
    plots — {rate, start, end, slots: {slot: [column, …]}, series: {column: {ticks, values}}} — a
    series of more than SERIES_POINTS points thinned to each stretch's lowest and highest."""
    rec = recorded.slots
    series = {name: _thin(rec.ticks, values) for name, values in rec.numbers.items()}
    slots: dict[str, list[str]] = {}
    for name in rec.names:
        if name not in rec.numbers:
            continue
        base, _, part = name.rpartition(".")
        vector = part in ("x", "y", "z", "w") and base.count(".") >= 2 and f"{base}.x" in rec.numbers
        slots.setdefault(base if vector else name, []).append(name)
    ticks, counts = recorded.in_play()
    series[IN_PLAY] = _thin(ticks, counts)
    slots[IN_PLAY] = [IN_PLAY]
    return {"rate": recorded.rate, "start": recorded.start, "end": recorded.end, "points": len(rec),
            "slots": slots, "series": series}


def _thin(ticks: np.ndarray, values: np.ndarray, limit: int = SERIES_POINTS) -> dict:
    n = len(ticks)
    if n <= limit:
        keep = np.arange(n)
    else:
        edges = np.linspace(0, n, limit // 2 + 1).astype(np.int64)
        picked = {0, n - 1}
        for a, b in zip(edges[:-1], edges[1:]):
            if b > a:
                part = values[a:b]
                picked.update((a + int(np.argmin(part)), a + int(np.argmax(part))))
        keep = np.asarray(sorted(picked))
    return {"ticks": ticks[keep].tolist(), "values": values[keep].tolist()}
