"""Helpers for the view's tests: a real hub (`planthub run … --listen`) and a real `planthub view` as processes, always stopped."""
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
    with planthub(folder, name, "view", run, "--connect", endpoint, "--port", 0, "--name", name, *args) as started:
        yield started, wait_for_url(started, timeout)


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
        except asyncio.TimeoutError:
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
