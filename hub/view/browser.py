"""One browser's WebSocket: its text frames in order, and at most one bodies frame waiting behind the one being sent.

A browser that draws slowly (or a socket that backs up) must never make the view queue without
bound, nor hold up the others: each browser has its own writer task. A bodies frame that comes
while the previous one is still being sent waits in a one-frame box; a newer one replaces it and
the older is dropped (counted): a view wants the newest poses, not all of them. Text frames
(scene, state, events, results) are not dropped, so they have a limit instead: a browser that
lets MAX_TEXTS of them pile up is closed, and its page may connect again.
"""
from __future__ import annotations

import asyncio
import logging
from collections import deque

_log = logging.getLogger("planthub.view")

MAX_TEXTS = 512        # text frames waiting for one browser before it is closed as too slow
SEND_TIMEOUT = 10.0    # s one frame may take to go out before the browser is given up
TOO_SLOW = 1013        # WebSocket close code "try again later"
GOING_AWAY = 1001      # WebSocket close code of a server that stops
SHUTDOWN = 3.0         # s the sockets have to close at the end


class Browser:
    """Frames for one socket (aiohttp's WebSocketResponse); `write()` sends them until it closes."""

    def __init__(self, socket, peer: str = ""):
        self.socket = socket
        self.peer = peer
        self.dropped = 0             # bodies frames replaced before they went out
        self.closing = False
        self._texts: deque[str] = deque()
        self._bodies: bytes | None = None
        self._wake = asyncio.Event()

    def send(self, text: str) -> None:
        if self.closing:
            return
        if len(self._texts) >= MAX_TEXTS:
            self._give_up(f"{MAX_TEXTS} frames waiting")
            return
        self._texts.append(text)
        self._wake.set()

    def send_bodies(self, payload: bytes) -> None:
        if self.closing:
            return
        if self._bodies is not None:
            self.dropped += 1
        self._bodies = payload
        self._wake.set()

    async def write(self) -> None:
        """Send what comes, texts first, until the socket closes or a send takes too long."""
        socket = self.socket
        try:
            while not self.closing:
                await self._wake.wait()
                self._wake.clear()
                while self._texts and not self.closing:
                    await asyncio.wait_for(socket.send_str(self._texts.popleft()), SEND_TIMEOUT)
                if self._bodies is not None and not self.closing:
                    payload, self._bodies = self._bodies, None
                    await asyncio.wait_for(socket.send_bytes(payload), SEND_TIMEOUT)
        except TimeoutError:
            self._give_up(f"a frame took more than {SEND_TIMEOUT:g} s to go out")
        except (ConnectionError, RuntimeError):
            self.closing = True   # the browser went away (aiohttp raises these on a closed socket)

    def _give_up(self, why: str) -> None:
        if self.closing:
            return
        self.closing = True
        _log.warning("planthub view: closing the socket of %s: too slow (%s)", self.peer or "a browser", why)
        self._closer = asyncio.get_running_loop().create_task(self.socket.close(code=TOO_SLOW, message=b"too slow"))


async def close_browsers(browsers, timeout: float = SHUTDOWN) -> None:
    """Close every browser's socket ("going away"), waiting at most `timeout` s for them all."""
    browsers = list(browsers)
    for browser in browsers:
        browser.closing = True
    closing = [asyncio.ensure_future(b.socket.close(code=GOING_AWAY, message=b"the view stops")) for b in browsers]
    if closing:
        await asyncio.wait(closing, timeout=timeout)
