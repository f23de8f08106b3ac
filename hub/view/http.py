"""The view's web side (aiohttp): the built front-end, the robot's files from pybullet_data, and a WebSocket per browser on /ws.

Files are served only from inside their folder: a path that leaves it (`..`, an absolute path, a
link pointing out) is not found, like a file that is not there. The WebSocket takes only pages of
its own origin — another site open in the same browser must not command the plant — and, while
the view listens on loopback, only requests addressed to a loopback name (a page of another site
whose name was made to point at 127.0.0.1 sends its own name).
"""
from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import signal
from pathlib import Path
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

from hub.core import resources
from hub.core.errors import PlanthubError
from hub.view.browser import SHUTDOWN, Browser
from hub.view.frames import MAX_FRAME, frame

_log = logging.getLogger("planthub.view")

#: the front-end, as `make view-assets` builds it from hub/view/web/
BUNDLE = resources.ROOT / "build" / "view"
HEARTBEAT = 10.0   # s between pings: a browser that went away without closing is noticed within two
WRITER_LIMIT = 64 * 1024   # bytes aiohttp buffers for a socket before a send waits (and the next bodies frame waits)


def missing_bundle(bundle: Path) -> str | None:
    """What to do when the front-end is not built, or None when it is."""
    if (bundle / "index.html").is_file():
        return None
    return (f"the view's front-end is not built (no {bundle / 'index.html'}): build it with `make view-assets` "
            "(cd hub/view/web && npm ci && npm run build), then reload the page")


def application(view, bundle: Path = BUNDLE, *, loopback: bool = True) -> web.Application:
    """The web application of `view` (hub/view/server.py's View), its front-end read from `bundle`."""
    import pybullet_data  # a folder of robot and mesh files: the URDF the scene names (no pybullet call)

    data = Path(pybullet_data.getDataPath())
    app = web.Application()

    async def index(request: web.Request) -> web.StreamResponse:
        problem = missing_bundle(bundle)
        if problem:
            return web.Response(status=503, text=f"planthub view: {problem}\n")
        return web.FileResponse(bundle / "index.html", headers={"Cache-Control": "no-cache"})

    async def assets(request: web.Request) -> web.StreamResponse:
        return _inside(bundle / "assets", request.match_info["path"])

    async def robots(request: web.Request) -> web.StreamResponse:
        return _inside(data, request.match_info["path"])

    async def socket(request: web.Request) -> web.StreamResponse:
        refused = _refused(request, loopback)
        if refused:
            raise web.HTTPForbidden(text=f"planthub view: {refused}\n")
        ws = web.WebSocketResponse(heartbeat=HEARTBEAT, max_msg_size=MAX_FRAME, compress=False,
                                   writer_limit=WRITER_LIMIT)
        await ws.prepare(request)
        browser = Browser(ws, request.remote or "")
        writer = asyncio.get_running_loop().create_task(browser.write())
        view.attach(browser)
        try:
            async for message in ws:
                if message.type is WSMsgType.TEXT:
                    view.receive(browser, message.data)
                elif message.type is WSMsgType.BINARY:
                    browser.send(frame("error", error="expected a JSON text frame, got a binary one"))
        finally:
            view.detach(browser)
            browser.closing = True
            writer.cancel()
            await asyncio.gather(writer, return_exceptions=True)
        return ws

    async def no_icon(request: web.Request) -> web.StreamResponse:
        return web.Response(status=204)   # a browser asks for it whatever the page says

    app.router.add_get("/", index)
    app.router.add_get("/favicon.ico", no_icon)
    app.router.add_get("/index.html", index)
    app.router.add_get("/assets/{path:.+}", assets)
    app.router.add_get("/pybullet_data/{path:.+}", robots)
    app.router.add_get("/ws", socket)
    return app


@contextlib.contextmanager
def signal_stop(loop: asyncio.AbstractEventLoop):
    """A future that the first SIGINT or SIGTERM completes with its number, while in the block."""
    stop: asyncio.Future = loop.create_future()
    for signum in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(signum, lambda s=signum: stop.done() or stop.set_result(s))
    try:
        yield stop
    finally:
        for signum in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(signum)


async def serve_page(view, stop: asyncio.Future, *, host: str, port: int, bundle: Path = BUNDLE, announce=print,
                     opened=None) -> int:
    """Serve `view`'s page and socket (the live View or a recorded run's Playback) on host:port until
    `stop` has a signal number; 128 + that number. `announce(url)` once it is served, `opened(url)`
    may open it in a browser; `view.close()` at the end."""
    problem = missing_bundle(bundle)
    if problem:
        _log.warning("planthub view: warning: %s", problem)
    runner = web.AppRunner(application(view, bundle, loopback=is_loopback(host)), access_log=None,
                           handle_signals=False)
    await runner.setup()
    try:
        site = web.TCPSite(runner, host, port, shutdown_timeout=SHUTDOWN)
        try:
            await site.start()
        except OSError as exc:
            raise PlanthubError(f"cannot serve on {host}:{port}: {exc.strerror or exc}"
                                + (" (another view? --port picks another)" if port else "")) from None
        bound = runner.addresses[0][1]
        shown = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host   # every address: this machine's is one
        url = f"http://{'[' + shown + ']' if ':' in shown else shown}:{bound}/"
        announce(url)
        if opened is not None:
            asyncio.get_running_loop().run_in_executor(None, opened, url)
        signum = await stop
    finally:
        await view.close()
        await runner.cleanup()
    return 128 + signum


def _inside(root: Path, relative: str) -> web.StreamResponse:
    """The file at `relative` under `root`, or 404 when it is not there or not inside."""
    try:
        base = root.resolve(strict=True)
        path = (base / relative).resolve(strict=True)
    except (OSError, RuntimeError, ValueError):   # missing, a link loop, a NUL byte
        raise web.HTTPNotFound() from None
    if not path.is_relative_to(base) or not path.is_file():
        raise web.HTTPNotFound()
    return web.FileResponse(path)


_LOOPBACK_NAMES = {"localhost", "localhost."}


def is_loopback(host: str) -> bool:
    host = host.strip("[]")
    if host.lower() in _LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _refused(request: web.Request, loopback: bool) -> str | None:
    """Why this WebSocket request is refused (another site's page), or None."""
    host = request.headers.get("Host", "")
    origin = request.headers.get("Origin")
    try:
        named = urlsplit(f"//{host}").hostname or ""
        came_from = urlsplit(origin).netloc.lower() if origin is not None else None
    except ValueError:   # a malformed Host or Origin ("[::1"): no page of this view sends one
        return f"malformed Host {host[:80]!r} or Origin {(origin or '')[:80]!r}"
    if loopback and not is_loopback(named):
        return f"this view answers requests for 127.0.0.1 or localhost, not for {host[:80]!r}"
    if came_from is not None and came_from != host.lower():
        return f"a page of {origin[:80]!r} may not use this view's WebSocket (its origin is http://{host[:80]})"
    return None
