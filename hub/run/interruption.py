"""SIGINT and SIGTERM end a run cleanly: at the next communication point as a stop condition, or — when the point does not come because a step is stuck — from a helper thread that completes the files and ends the process."""
from __future__ import annotations

import logging
import os
import select
import signal
import threading
import time

from hub.core import scratch
from hub.core.observer import Stop

log = logging.getLogger("planthub.run")

#: s a signalled run has to reach its next communication point before it is ended from outside
GRACE = 3.0
SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interruption:
    """A stop condition fed by the signals: the first SIGINT or SIGTERM ends the run at the next
    point (`stop`), with the exit status 128 + the signal's number (130, 143). If the run is stuck
    (a step inside a C call does not return, a wait) for GRACE seconds, or a second signal comes,
    `emergency(reason)` runs on a helper thread — the run's files closed complete, its summary
    written — then each of `reporters(reason)`, and the process ends with that status.

    Python runs a signal handler only in the main thread and only between two bytecodes, so a
    thread stuck in an FMU would never see it; the wakeup file descriptor below is written by the
    C-level handler, which runs at once, and wakes the helper thread."""

    def __init__(self, rate: int, emergency):
        self.rate = rate
        self.emergency = emergency
        self.reporters = []   # more to do with the reason once the files are complete (`planthub test`'s verdicts)
        self.interrupted = False   # a signal ended the run (at a point, or from the helper thread)
        self.signum: int | None = None
        self._ended = threading.Event()
        self._previous = {}
        self._wakeup = None
        self._read = self._write = None

    def install(self) -> Interruption:
        if threading.current_thread() is not threading.main_thread():
            return self   # only the main thread can take signals; nothing to do elsewhere
        self._read, self._write = os.pipe()
        os.set_blocking(self._write, False)
        self._wakeup = signal.set_wakeup_fd(self._write, warn_on_full_buffer=False)
        for signum in SIGNALS:
            self._previous[signum] = signal.signal(signum, self._handle)
        threading.Thread(target=self._watch, name="planthub-signals", daemon=True).start()
        return self

    @property
    def exit_status(self) -> int | None:
        return None if self.signum is None else 128 + self.signum

    def _handle(self, signum, frame) -> None:
        if self.signum is None:
            self.signum = signum
            log.warning("planthub: %s: the run stops at the next communication point", signal.Signals(signum).name)

    def _watch(self) -> None:
        first = None   # the first signal's number, once it came
        deadline = None
        while not self._ended.is_set():
            wait = None if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                ready, _, _ = select.select([self._read], [], [], min(wait, 0.1) if wait is not None else 0.1)
                data = os.read(self._read, 16) if ready else b""
            except (OSError, ValueError):
                break
            signums = [b for b in data if b in SIGNALS]
            if signums and first is not None:
                self._end(first, "a second signal came")   # an impatient Ctrl-C: end now
            if signums and first is None:
                first, deadline = signums[0], time.monotonic() + GRACE
            if deadline is not None and time.monotonic() >= deadline and not self._ended.is_set():
                self._end(first, f"the run did not reach its next communication point within {GRACE:g} s "
                                 "(a step is stuck)")
        os.close(self._read)

    def _end(self, signum: int, why: str) -> None:
        reason = f"interrupted by {signal.Signals(signum).name}; {why}, so it ends here"
        if self.signum is None:
            self.signum = signum   # a main thread stuck in a C call never ran the Python handler
        self.interrupted = True
        try:
            self.emergency(reason)
            for report in self.reporters:
                try:
                    report(reason)
                except Exception:   # the process ends all the same; the files are complete
                    log.exception("while reporting an interrupted run")
        finally:
            scratch.remove()   # os._exit runs no atexit clean-up
            logging.shutdown()
            os._exit(128 + signum)

    def stop(self, tick: int) -> Stop | None:
        if self.signum is None:
            return None
        self.interrupted = True
        return Stop(f"interrupted by {signal.Signals(self.signum).name} at t = {tick / self.rate:.9g} s")

    def close(self, reason: str = "") -> None:
        """The run ended: restore the signal handlers and the wakeup descriptor (the helper thread
        closes its end of the pipe when it sees the run ended)."""
        self._ended.set()
        if self._write is None:
            return
        signal.set_wakeup_fd(self._wakeup if self._wakeup is not None else -1)
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        os.close(self._write)
        self._write = None
