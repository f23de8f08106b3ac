"""A protocol server (OPC UA, Modbus, S7, EtherNet/IP) in its own thread with its own asyncio event
loop: the plant's steps call into it with a limit on every wait, and it is stopped with the gateway."""
from __future__ import annotations

import asyncio
import concurrent.futures
import socket
import threading

from hub.core.errors import PlanthubError
from hub.gateway.image import ProcessImage

START_LIMIT = 20.0   # s for a server to bind its endpoint and build its address space
CALL_LIMIT = 5.0     # s for anything else asked of it


def refuse_taken(host: str, port: int, failed: str) -> None:
    """Raise PlanthubError("{failed}: cause (…)") when the endpoint is taken: a server that binds with
    SO_REUSEPORT (snap7) would share it silently. A stopped gateway's TIME_WAIT is no owner."""
    with socket.socket() as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host, port))
        except OSError as exc:
            raise PlanthubError(f"{failed}: {exc.strerror or exc} (another gateway or server holds the port?)") from None


async def hold(image: ProcessImage) -> None:
    """A PLC's read of `cycle` held (`ProcessImage.hold`) in a thread of the running loop's pool: the
    loop goes on serving other clients meanwhile."""
    await asyncio.get_running_loop().run_in_executor(None, image.hold)


class ServerThread:
    """Runs `protocol` (an object with async start(), publish(changed) and stop()) in a thread.
    `publish` is a coroutine run in the loop where the server's state is the loop's alone (asyncua),
    or a plain method run in the plant's thread where the server guards its state itself or answers
    from the process image (snap7's area locks, Modbus, EtherNet/IP)."""

    def __init__(self, protocol, what: str):
        self.protocol, self.what = protocol, what
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, name=what, daemon=True)

    def __enter__(self):
        self.thread.start()
        try:
            self.call(self.protocol.start(), START_LIMIT, "start")
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc):
        self.close()

    def call(self, coroutine, limit: float = CALL_LIMIT, doing: str = "answer"):
        future = asyncio.run_coroutine_threadsafe(coroutine, self.loop)
        try:
            return future.result(limit)
        except concurrent.futures.TimeoutError:
            future.cancel()
            raise PlanthubError(f"the {self.what} did not {doing} within {limit:g} s") from None
        except OSError as exc:
            raise PlanthubError(f"the {self.what} could not {doing}: {exc}") from exc

    def publish(self, changed: dict) -> None:
        if not changed:
            return
        if asyncio.iscoroutinefunction(self.protocol.publish):
            self.call(self.protocol.publish(changed), doing="publish the plant's values")
        else:   # no hop into the loop and back: it cost 0.2-0.6 ms a scan while the loop served the PLC's polls
            self.protocol.publish(changed)

    def close(self) -> None:
        if self.thread.is_alive():
            try:
                self.call(self.protocol.stop(), doing="stop")
            except PlanthubError:
                pass   # it is being torn down with its loop anyway
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(CALL_LIMIT)
        if not self.thread.is_alive():
            self.loop.close()
