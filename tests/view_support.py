"""Helpers for the view's tests: a real hub (`planthub run … --listen`), a real recorded run, a real `planthub view` as processes, always stopped, and Debian's chromium driven by Playwright."""
from __future__ import annotations

import asyncio
import contextlib
import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from hub.bus.session import free_loopback_endpoint

from .helpers import ROOT

_URL = re.compile(r"at (http://\S+/)")


@dataclass
class Started:
    proc: subprocess.Popen
    out: Path       # its stdout, as a file (no pipe to fill up while nobody reads)
    err: Path

    def output(self) -> tuple[str, str]:
        return self.out.read_text(), self.err.read_text()


@contextlib.contextmanager
def planthub(folder: Path, name: str, *args):
    """`python -m hub ARGS…` with its output in `folder`/NAME.out and .err; ended (SIGTERM, then
    SIGKILL) and reaped whatever happens."""
    folder.mkdir(parents=True, exist_ok=True)
    out, err = folder / f"{name}.out", folder / f"{name}.err"
    with open(out, "w") as o, open(err, "w") as e:
        proc = subprocess.Popen([sys.executable, "-m", "hub", *map(str, args)], cwd=ROOT, stdout=o, stderr=e,
                                stdin=subprocess.DEVNULL, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        yield Started(proc, out, err)
    finally:
        end(proc)


def end(proc: subprocess.Popen, signum: int = signal.SIGTERM, timeout: float = 15.0) -> int:
    """Signal a process and wait for it (killed if it does not end within `timeout` s); its exit status."""
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(signum)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
    return proc.returncode


@contextlib.contextmanager
def hub(folder: Path, scenario: Path, *args, realtime: float = 1.0):
    """A real run on the bus, paced to the wall clock so it lasts; yields (Started, endpoint, run folder)."""
    endpoint = free_loopback_endpoint()
    out = folder / "run"
    with planthub(folder, "hub", "run", scenario, "--realtime", realtime, "--listen", endpoint, "--out", out,
                  *args) as started:
        yield started, endpoint, out


@contextlib.contextmanager
def view(folder: Path, run: str, endpoint: str, *args, name: str = "view-test", timeout: float = 60.0):
    """`planthub view RUN --connect ENDPOINT --port 0`, once it printed its address; yields (Started, url)."""
    with views(folder, run, endpoint, (name, args), timeout=timeout) as ((started, url),):
        yield started, url


@contextlib.contextmanager
def views(folder: Path, run: str, endpoint: str, *pages: tuple[str, tuple], timeout: float = 60.0):
    """Several `planthub view RUN --connect ENDPOINT --port 0` of one run, each (name, its own args),
    started side by side and waited for together; yields (Started, url) of each, in that order."""
    with contextlib.ExitStack() as stack:
        started = [stack.enter_context(planthub(folder, name, "view", run, "--connect", endpoint, "--port", 0,
                                                "--name", name, *args)) for name, args in pages]
        yield [(s, wait_for_url(s, timeout)) for s in started]


def record(folder: Path, scenario: Path, *args, timeout: float = 120.0) -> Path:
    """A recorded run: `planthub run SCENARIO --record-bodies --out FOLDER/recorded ARGS…`; its folder."""
    out = folder / "recorded"
    done = subprocess.run([sys.executable, "-m", "hub", "run", str(scenario), "--record-bodies", "--out", str(out),
                           *map(str, args)], cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    return out


@contextlib.contextmanager
def playback(folder: Path, run_dir: Path, *args, name: str = "playback", timeout: float = 60.0):
    """`planthub view RUN_DIR --port 0`, once it printed its address; yields (Started, url)."""
    with planthub(folder, name, "view", run_dir, "--port", 0, *args) as started:
        yield started, wait_for_url(started, timeout)


CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]
BUNDLE = ROOT / "build" / "view" / "index.html"


@contextlib.contextmanager
def browser_page(url: str, viewport=(960, 640)):
    """The page at `url` in headless chromium, once its socket is open; yields (page, page errors).
    The browser is closed whatever happens."""
    from playwright.sync_api import sync_playwright

    assert BUNDLE.is_file(), f"no {BUNDLE}: build the front-end with `make view-assets`"
    assert os.access(CHROMIUM, os.X_OK), f"no {CHROMIUM}: `make chromium` installs it"
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True, timeout=60_000)
        try:
            tab = browser.new_page(viewport={"width": viewport[0], "height": viewport[1]})
            errors: list[str] = []
            tab.on("pageerror", lambda exc: errors.append(str(exc)))
            tab.goto(url, timeout=60_000)
            tab.wait_for_function("window.planthub && window.planthub.connected", timeout=60_000)
            yield tab, errors
        finally:
            browser.close()


@contextlib.contextmanager
def two_pages(*urls):
    """One chromium, a tab per url once its socket is open; yields the tabs and the page errors
    (the browser is closed whatever happens)."""
    from playwright.sync_api import sync_playwright

    assert BUNDLE.is_file(), f"no {BUNDLE}: build the front-end with `make view-assets`"
    assert os.access(CHROMIUM, os.X_OK), f"no {CHROMIUM}: `make chromium` installs it"
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True, timeout=60_000)
        try:
            tabs, errors = [], []
            for url in urls:
                tab = browser.new_page(viewport={"width": 1100, "height": 700})
                tab.on("pageerror", lambda exc: errors.append(str(exc)))
                tab.goto(url, timeout=60_000)
                tab.wait_for_function("window.planthub && window.planthub.connected", timeout=60_000)
                tabs.append(tab)
            yield tabs, errors
        finally:
            browser.close()


def talk(url, conversation, **headers):
    """Run `conversation(ws)` against the view's WebSocket (aiohttp's client); its result."""
    import aiohttp

    async def main():
        async with aiohttp.ClientSession(timeout=aiohttp.ClientTimeout(total=90)) as session:
            async with session.ws_connect(f"{url}ws", headers=headers, heartbeat=None) as ws:
                return await conversation(ws)
    return asyncio.run(main())


def wait_for_url(started: Started, timeout: float) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = _URL.search(started.out.read_text())
        if found:
            return found.group(1)
        if started.proc.poll() is not None:
            break
        time.sleep(0.1)
    out, err = started.output()
    raise AssertionError(f"planthub view printed no address within {timeout:g} s "
                         f"(exit {started.proc.poll()}):\n{out}\n{err}")


def command_rows(run_dir: Path, timeout: float = 10.0, until=lambda rows: bool(rows)) -> list[dict]:
    """The rows of the run's commands.csv once `until(rows)` holds (the recorder flushes it about every second)."""
    deadline = time.monotonic() + timeout
    rows: list[dict] = []
    while time.monotonic() < deadline:
        path = run_dir / "commands.csv"
        if path.exists():
            with open(path, newline="") as f:
                rows = list(csv.DictReader(f))
            if until(rows):
                return rows
        time.sleep(0.2)
    raise AssertionError(f"commands.csv within {timeout:g} s: {rows}")


async def receive(ws, timeout: float = 10.0):
    """The next frame: a dict for a text frame, bytes for a binary one (fails after `timeout` s)."""
    import aiohttp

    message = await asyncio.wait_for(ws.receive(), timeout)
    if message.type is aiohttp.WSMsgType.TEXT:
        return json.loads(message.data)
    if message.type is aiohttp.WSMsgType.BINARY:
        return message.data
    raise AssertionError(f"the socket closed: {message.type.name} {message.data!r} {message.extra!r}")


async def wait_for(ws, predicate, timeout: float = 15.0, what: str = "a frame"):
    """The first frame for which `predicate(frame)` holds within `timeout` s."""
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise AssertionError(f"no {what} within {timeout:g} s")
        try:
            item = await receive(ws, left)
        except TimeoutError:
            raise AssertionError(f"no {what} within {timeout:g} s") from None
        if predicate(item):
            return item


def bodies(payload: bytes, scene: dict) -> tuple[int, dict[str, tuple]]:
    """A bodies message (msgpack, as the hub sent it) → (tick, id → (x, y, z)) of the bodies in play."""
    import struct

    import msgpack

    message = msgpack.unpackb(payload)
    count = len(message["rows"]) // 2
    rows = struct.unpack(f"<{count}H", message["rows"])
    poses = struct.unpack(f"<{7 * count}f", message["poses"])
    assert len(message["flags"]) == count and len(message["destinations"]) == count, sorted(message)
    ids = {b["row"]: b["id"] for b in scene["bodies"]}
    return message["tick"], {ids[row]: poses[7 * i:7 * i + 3] for i, row in enumerate(rows)}
