"""The watchdog of FMUs stepped in the hub's own process: a C call cannot be interrupted, so one that hangs past its `step_timeout` ends the process — after the run's files are complete and its summary says why."""
from __future__ import annotations

import logging
import os
import shutil
import threading
import time
import weakref

from hub.core import scratch

log = logging.getLogger("planthub.logic")

#: exit status of a hub ended by the watchdog: the run failed (hub/cli/README.md, "Exit codes")
EXIT_HUNG = 1
POLL = 0.25   # s between two looks; a hang is noticed within its limit plus this


class Watchdog:
    """Watches the slaves that are inside a step (`busy_since` set) and ends the process when one
    stays longer than its limit. What must happen first — the recording flushed, summary.json
    written — is registered with `on_hang`; nothing else runs (the stuck thread holds the FMU)."""

    def __init__(self):
        self._slaves: weakref.WeakSet = weakref.WeakSet()
        self._handlers: dict[int, object] = {}
        self._lock = threading.Lock()
        self._thread = None

    def watch(self, slave) -> None:
        """Watch `slave`: it has `busy_since` (time.monotonic() while in a step, else None),
        `step_timeout`, `time`, `instance`, a `_dir` to remove, and `describe()`."""
        with self._lock:
            self._slaves.add(slave)
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, name="planthub-watchdog", daemon=True)
                self._thread.start()

    def on_hang(self, handler) -> int:
        """Call `handler(message)` before the process ends for a hung step; returns a key for `forget`."""
        with self._lock:
            key = id(handler)
            self._handlers[key] = handler
            return key

    def forget(self, key: int) -> None:
        with self._lock:
            self._handlers.pop(key, None)

    def _after_fork(self) -> None:
        """In a forked child (a campaign's case: hub/campaign/zygote.py): the parent's thread is not
        here and its lock may have been held at the fork: a new lock, and the child's own thread
        started at its first FMU."""
        self._lock = threading.Lock()
        self._thread = None

    def _loop(self) -> None:
        while True:
            time.sleep(POLL)
            now = time.monotonic()
            for slave in list(self._slaves):
                since = slave.busy_since
                if since is not None and now - since > slave.step_timeout:
                    self._hung(slave, now - since)

    def _hung(self, slave, seconds: float) -> None:
        message = (f"FMU instance {slave.instance!r} ({slave.interface.path.name}) at t = {slave.time:.9g} s: its step "
                   f"has not returned for {seconds:.1f} s (step_timeout {slave.step_timeout:g} s); an FMU in the hub's "
                   f"process cannot be interrupted, so planthub ends here (run it with `runs: child` to have only "
                   f"its worker killed); the recording so far is kept")
        with self._lock:
            handlers = list(self._handlers.values())
        for handler in handlers:
            try:
                handler(message)
            except Exception:   # the files matter more than a clean report of this failure
                log.exception("while ending a hung run")
        log.critical("planthub: %s", message)
        for other in list(self._slaves):
            shutil.rmtree(getattr(other, "_dir", ""), ignore_errors=True)
        scratch.remove()   # os._exit runs no atexit clean-up
        logging.shutdown()
        os._exit(EXIT_HUNG)


WATCHDOG = Watchdog()
os.register_at_fork(after_in_child=WATCHDOG._after_fork)
