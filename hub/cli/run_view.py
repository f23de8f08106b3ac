"""`planthub run --view`: the run's view beside it — `planthub view RUN --connect ENDPOINT` as a child process that dies with the hub and is stopped at the end of the run."""
from __future__ import annotations

import argparse
import logging
import os
import re
import signal
import subprocess
import sys
import threading
import time

from hub.cli.view import port_number
from hub.core.errors import PlanthubError
from hub.core.lifetime import guarded

_log = logging.getLogger(__name__)

DEFAULT_PORT = 8765
STARTUP = 60.0   # s the view has to join the run and serve its page (it asks the hub for the scene first)
STOP = 5.0       # s it has to end after SIGTERM before it is killed
_URL = re.compile(r" at (http://\S+/)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    view = parser.add_argument_group("view (--view opens the bus on loopback, as --bus does)")
    view.add_argument("--view", action="store_true",
                      help="also serve the run's view in the browser (`planthub view`, started beside the run and "
                           "ended with it); prints the address to open")
    view.add_argument("--view-port", type=port_number, default=DEFAULT_PORT, metavar="PORT",
                      help=f"the view's web port (default {DEFAULT_PORT}; 0: any free one)")


class RunView:
    """The view of run `run`, started on the open hub bus by `start(bus)`; `wait()` for its address.

    An observer of the run (hub/core/observer.py) that only closes: the master closes its observers
    in reverse order of plugging in, so this one, plugged in after the bus link, stops the view
    before the hub leaves the bus — the view never sees its hub go away."""

    def __init__(self, run: str, *, port: int = DEFAULT_PORT):
        self.run = run
        self.port = port
        self.process: subprocess.Popen | None = None
        self.url: str | None = None
        self._found = threading.Event()
        self._reader: threading.Thread | None = None

    def start(self, bus) -> None:
        from hub.bus.session import local_endpoint
        from hub.bus.tls import environment

        settings = bus.settings
        # Where a process on this machine reaches the hub: its listeners, or the router it is a client of.
        endpoints = [local_endpoint(e) for e in bus.endpoints] or list(settings.connect)
        mode = "peer" if bus.endpoints else "client"
        command = [sys.executable, "-m", "hub", "view", self.run, *(x for e in endpoints for x in ("--connect", e)),
                   "--mode", mode, "--port", str(self.port), "--timeout", f"{STARTUP:g}"]
        env = {**os.environ, **environment(settings.tls, loopback=True), "PYTHONUNBUFFERED": "1"}
        try:
            # guarded: the kernel kills it if the hub dies without stopping it (kill -9); its own process
            # group, so a Ctrl-C at the terminal is the hub's to handle (it ends the run, then the view).
            self.process = subprocess.Popen(guarded(command), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                            env=env, process_group=0, text=True, errors="replace")
        except OSError as exc:
            raise PlanthubError(f"cannot start the view ({' '.join(command)}): {exc.strerror or exc}") from None
        self._reader = threading.Thread(target=self._read, name="planthub-run-view", daemon=True)
        self._reader.start()

    def observe(self, tick: int, signals, events) -> None:
        """Nothing: the view sees the run over the bus."""

    def close(self, reason: str = "") -> None:
        self.stop()

    @property
    def pid(self) -> int:
        return self.process.pid

    def _read(self) -> None:
        """The view's stdout: its address line, once; anything else it prints goes on to ours."""
        for line in self.process.stdout:
            found = _URL.search(line) if self.url is None else None
            if found:
                self.url = found.group(1)
                self._found.set()
            else:
                sys.stdout.write(line)
        self._found.set()   # it ended: nobody waits for an address that will not come

    def wait(self, timeout: float = STARTUP) -> str:
        """Its address, once it serves the page; PlanthubError if it ended first or took longer."""
        deadline = time.monotonic() + timeout
        while self.url is None and time.monotonic() < deadline:
            if self._found.wait(min(0.5, max(0.0, deadline - time.monotonic()))) and self.url is None:
                code = self.process.wait(5.0)
                raise PlanthubError(f"the run's view ended before it served its page (exit {code}; its message "
                                    "above): the run was not started")
        if self.url is None:
            raise PlanthubError(f"the run's view served no page within {timeout:g} s: the run was not started")
        return self.url

    def stop(self) -> None:
        """End it (SIGTERM, then SIGKILL) and reap it; said when it had ended by itself with an error.
        Again, or before it started: nothing."""
        if self.process is None or self.process.returncode is not None:
            return
        code = self.process.poll()
        if code is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(STOP)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(STOP)
        elif code not in (0, 128 + signal.SIGTERM) and self.url is not None:   # before: wait() said so
            _log.warning("planthub run: warning: the run's view ended early (exit %d; its message above)", code)
        if self._reader is not None:
            self._reader.join(STOP)

