"""The data plane's sender: a thread that puts the points the step loop hands it, in slices of time the loop lends it.

The step loop offers a point (its tick, a copy of the values, the void slots that fired) when
something is due: the sender takes it if it has finished the last one, otherwise the point is
skipped and counted, and its events wait for the next point taken (at most MAX_EVENTS of them).
The loop then lends the sender the time it has earned, BUDGET of the loop's wall time shared
among the viewers holding a token, in slices of at least MIN_LEND and at most MOST_LEND: it waits
for the sender that long at most, whatever the sender or Zenoh are doing, and a sender stuck in a
put is lent nothing more. So watching costs the loop at most BUDGET of its time, however many
watch, and a point takes as many slices as it needs: a viewer gets fewer points, never a late loop.
Shared, because every put goes to every viewer: with twenty, each put is twenty deliveries for
them to take in (about 40–80 µs each for a hub.live.Viewer in Python), and on a shared machine
their work is the plant's loss. When a viewer comes, the point under way and the next are lent the
whole budget: the first put on a key after its subscribers changed costs Zenoh the most (35–85 µs
instead of 5–13), and a viewer that joins should not wait the longest for its first values.

Why lend instead of letting the thread run beside the loop: a Zenoh put releases the GIL, and the
loop, which holds it while it steps pybullet, takes it back at once, so a thread putting beside a
busy loop gets the GIL again only when the interpreter's switch interval (5 ms) forces the loop to
hand it over: one sample per 5 ms, each costing the thread 100–500 µs of CPU in context switches
(measured in the bottling plant, perf). While the loop waits for a lent slice the thread has the
GIL to itself, and a put costs what it costs alone: about 3–6 µs with one viewer process on
loopback, about 13 µs with twenty, so each viewer's share shrinks with their number and the
samples all of them take in together stay about the same (tests/bench_bus.py).
"""
from __future__ import annotations

import logging
import threading
import time

from hub.bus import wire

_log = logging.getLogger(__name__)

BUDGET = 0.02      # the share of the loop's wall time lent to sending, among all viewers (tests/bench_bus.py)
MIN_LEND = 0.001   # s: a slice shorter than this would mostly pay for the two thread switches
MOST_LEND = 0.005  # s: the longest the loop waits in one point
MAX_EVENTS = 4096  # fired void slots kept for the next point taken; beyond, they are counted as lost
NEVER = 1 << 62    # `wanted` when no watched slot has a value to send (only events)


class Outbox:
    """The hand-over from the step loop to the sending thread: one point at a time.

    The loop calls `offer` and `lend`, and reads `wanted`; the sender runs only inside a lent
    slice (and in `flush` and `close`, which lend until it is done), so the two share no data
    while both run, but for the lock that `offer` and taking a point hold for a few lines.
    """

    def __init__(self, on_change: bool):
        self.on_change = on_change
        self.wanted = 0          # the first tick at which a watched slot is due again (read by the loop)
        self.share = 1           # viewers holding a token: BUDGET is shared among them
        self.samples = 0         # data-plane samples sent
        self.events_lost = 0     # fired void slots dropped because MAX_EVENTS waited already
        self.sent_tick = -1      # the tick of the last point sent completely
        self._lock = threading.Lock()
        self._pending = None     # (tick, values, entries) handed over, not taken yet
        self._latest = ()        # the entries of the last point offered, taken or skipped
        self._current = None     # [tick, values, entries, position]: the point being sent
        self._welcome = 0        # points still to send for viewers that came: lent the whole budget
        self._events: list = []  # (tick, entry) of void slots that fired, not sent yet
        self._resets: list = []  # entries whose next value goes out whatever it is (a new subscriber)
        self._credit = 0.0       # s of lending earned and not lent yet
        self._last = None        # perf_counter of the loop's last `lend`
        self._go, self._back = threading.Event(), threading.Event()
        self._deadline = 0.0
        self._waiting = False    # the sender waits for a slice (False while it works, or is stuck in a put)
        self._closing = False
        self._thread = threading.Thread(target=self._run, name="planthub data plane", daemon=True)
        self._thread.start()

    # --- the step loop's side ------------------------------------------------------------
    @property
    def welcoming(self) -> bool:
        """Points for viewers that came are still under way (lent the whole budget)."""
        return self._welcome > 0

    @property
    def busy(self) -> bool:
        return self._current is not None or self._pending is not None or bool(self._events)

    def offer(self, tick: int, values, entries, fired) -> bool:
        """Hand over a point if the sender has finished the last one (True); else keep its
        events and skip it. `values` None: only the events."""
        with self._lock:
            if fired:
                room = max(MAX_EVENTS - len(self._events), 0)
                if room < len(fired):
                    self.events_lost += len(fired) - room
                    fired = fired[:room]
                self._events.extend((tick, e) for e in fired)
            if values is not None:
                # What is due next follows the entries watched now, not those of the point under
                # way: a point skipped here may hold entries the one being sent did not have (a
                # slot that was cold at that point), and they must not wait for ever.
                self._latest = entries
            if values is None or self._current is not None or self._pending is not None:
                return values is None
            self._pending = (tick, values, entries)
            return True

    def reset(self, entries) -> None:
        """Send these entries' values at the next point taken, due or not, changed or not."""
        with self._lock:
            self._resets.extend(entries)
            self.wanted = 0
        self.welcome()

    def welcome(self) -> None:
        """A viewer came: the point under way and the next are lent the whole budget, not a share."""
        self._welcome = 2

    def lend(self) -> None:
        """Earn BUDGET / share of the wall time since the last call, and lend it if the sender has work."""
        now = time.perf_counter()
        if self._last is not None:
            share = 1 if self._welcome > 0 else self.share
            self._credit = min(MOST_LEND, self._credit + BUDGET / share * (now - self._last))
        self._last = now
        if self._credit >= MIN_LEND and self.busy:
            self._credit -= self._slice(self._credit)
            self._last = time.perf_counter()   # the slice itself earns nothing

    def flush(self, timeout: float) -> bool:
        """Lend the sender up to `timeout` s to send all it was handed (tests, closing)."""
        deadline = time.monotonic() + timeout
        while self.busy:
            left = deadline - time.monotonic()
            if left <= 0 or not self._thread.is_alive():
                return False
            self._slice(min(left, 0.1))
            if self.busy and not self._waiting:
                time.sleep(0.001)   # stuck in a put: give it the GIL, but no slice
        return True

    def close(self, last=None, timeout: float = 1.0) -> bool:
        """Send what waits, then `last` (a point the loop skipped, or None), each within `timeout`
        s, and stop the sender. Returns whether `last` went out."""
        sent = self.flush(timeout) and last is not None and self.offer(*last, ()) and self.flush(timeout)
        self._closing = True
        self._go.set()
        self._thread.join(timeout)
        return bool(sent)

    def _slice(self, seconds: float) -> float:
        """Let the sender work for at most `seconds`; the loop waits no longer. Returns the time lent."""
        if not self._waiting:
            return 0.0   # still in a put from an earlier slice: lending now would only be waiting
        began = time.perf_counter()
        self._deadline = began + seconds
        self._back.clear()
        self._go.set()
        self._back.wait(seconds)
        return time.perf_counter() - began

    # --- the sender ----------------------------------------------------------------------------
    def _run(self) -> None:
        try:
            while not self._closing:
                self._waiting = True
                if not self._go.wait(1.0):   # the timeout only bounds the wait; closing sets it too
                    continue
                self._waiting = False
                self._go.clear()
                if self._closing:
                    return
                try:
                    self._work(self._deadline)
                finally:
                    self._back.set()
        except Exception:   # the session closed under it, or a bug: the run goes on, unwatched
            self._waiting = False
            _log.debug("planthub: the data plane's sender stopped", exc_info=True)

    def _work(self, deadline: float) -> None:
        clock = time.perf_counter
        while clock() < deadline:
            if self._current is None:
                with self._lock:
                    point, self._pending = self._pending, None
                    events, self._events = self._events, []
                    resets, self._resets = self._resets, []
                for e in resets:
                    e.due, e.last = 0, None
                for at, e in events:
                    e.put(b"", attachment=wire.TICK.pack(at))
                    self.samples += 1
                if point is None:
                    return
                self._current = [*point, 0]
            if self._send(self._current, deadline):
                tick, values, entries, _ = self._current
                with self._lock:
                    self._current = None
                    self._welcome = max(0, self._welcome - 1)
                    self.sent_tick = tick
                    wanted = min((e.due for e in self._latest), default=NEVER)
                    self.wanted = 0 if self._resets else wanted

    def _send(self, current, deadline: float) -> bool:
        """Send the point's due values from where the last slice stopped; True once all are out."""
        tick, values, entries, position = current
        if values is None:
            return True
        clock, on_change, attachment = time.perf_counter, self.on_change, wire.TICK.pack(tick)
        for i in range(position, len(entries)):
            if clock() >= deadline:
                current[3] = i
                return False
            e = entries[i]
            if tick < e.due:
                continue
            payload = e.pack(values[e.index])
            if on_change:
                if payload == e.last:
                    continue   # still due: a change goes out at the first point it shows
                e.last = payload
            e.put(payload, attachment=attachment)
            e.due = tick + e.period
            self.samples += 1
        return True
