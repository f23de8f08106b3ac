"""From the bus's threads to the view's asyncio loop: a bounded queue, and a one-item box for what only its latest matters.

A Zenoh callback here appends to a deque under a lock and, when the loop has nothing pending,
wakes it once (hub/bus/session.py: a callback that did real work would starve). Everything else
— decoding, relaying to the browsers — runs on the loop. While the loop lags, the queue holds at
most `limit` items (then counts the rest as dropped) and a box holds one item (a newer replaces it):
the bodies message, 20 per s, of which only the newest is worth drawing.
"""
from __future__ import annotations

import asyncio
import threading
from collections import deque


class Bridge:
    """`put(kind, item)` and `latest(kind, item)` from any thread; `deliver(kind, item)` runs on `loop`."""

    def __init__(self, loop: asyncio.AbstractEventLoop, deliver, limit: int = 4096):
        self._loop = loop
        self._deliver = deliver
        self._limit = limit
        self._queue: deque = deque()
        self._boxes: dict[str, object] = {}
        self._lock = threading.Lock()
        self._woken = False
        self.dropped = 0      # queue items that found the queue full
        self.replaced = 0     # box items replaced by a newer one before the loop took them

    def put(self, kind: str, item) -> None:
        with self._lock:
            if len(self._queue) >= self._limit:
                self.dropped += 1
                return
            self._queue.append((kind, item))
            wake, self._woken = not self._woken, True
        if wake:
            self._wake()

    def latest(self, kind: str, item) -> None:
        with self._lock:
            if kind in self._boxes:
                self.replaced += 1
            self._boxes[kind] = item
            wake, self._woken = not self._woken, True
        if wake:
            self._wake()

    def _wake(self) -> None:
        try:
            self._loop.call_soon_threadsafe(self._drain)
        except RuntimeError:
            pass   # the loop is closed: the view is ending, and what came is of no use now

    def _drain(self) -> None:
        with self._lock:
            items, self._queue = self._queue, deque()
            boxes, self._boxes = self._boxes, {}
            self._woken = False
        for kind, item in items:
            self._deliver(kind, item)
        for kind, item in boxes.items():
            self._deliver(kind, item)
