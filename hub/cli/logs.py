"""Where the command line's diagnostics go: the project's loggers on stderr, as loud as -q/-v ask, and Zenoh's own log."""
from __future__ import annotations

import logging
import os
import sys
from contextlib import contextmanager

from hub.bus import log as zenoh_log  # imports no Zenoh: the level is applied when a session opens

_OURS = ("hub", "modules", "planthub")   # module loggers (hub.bus.lockstep …) and named ones (planthub.logic)
_LEVELS = {-1: logging.WARNING, 0: logging.INFO}
# Zenoh's log from -vv on: at warn, Zenoh warns at every session that gossip is off, as planthub has it.
_ZENOH = {-1: "off", 0: "off", 1: "off", 2: "info"}   # more: debug; RUST_LOG, when set, wins


class _Prefixed(logging.Formatter):
    """`planthub: message`, as the command's own errors have always read. A message that names its
    speaker already (`planthub participant 'drive': …`, `planthub: warning: …`) is left as it is:
    some are written so for a process that sets up no logging, where Python prints the bare text."""

    def format(self, record: logging.LogRecord) -> str:
        text = super().format(record)
        return text if text.startswith("planthub") else f"planthub: {text}"


@contextmanager
def diagnostics(verbosity: int):
    """Diagnostics for one command: WARNING and up with -q, INFO by default, DEBUG with -v. Only
    the project's loggers: -v should not bring out every library's debug lines. Restored when the
    command ends, so `main` can be called again in one process (tests, a wrapper)."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_Prefixed("%(message)s"))
    saved = []
    for name in _OURS:
        logger = logging.getLogger(name)
        saved.append((logger, logger.level, logger.propagate))
        logger.addHandler(handler)
        logger.setLevel(_LEVELS.get(verbosity, logging.DEBUG))
        logger.propagate = False   # a root handler someone else set up would print each line twice
    level = _ZENOH.get(verbosity, "debug")
    zenoh_log.set_level(level)
    try:
        with _stdout_kept_apart(level != "off" or bool(os.environ.get("RUST_LOG"))):
            yield
    finally:
        for logger, level, propagate in saved:
            logger.removeHandler(handler)
            logger.setLevel(level)
            logger.propagate = propagate
        handler.flush()


@contextmanager
def _stdout_kept_apart(zenoh_logs: bool):
    """Zenoh writes its log to file descriptor 1, where the command's own output (a summary, a
    verdict) goes. While Zenoh may log, descriptor 1 is made stderr and `sys.stdout` writes to a
    copy of the real stdout, so `planthub run … > summary.txt` keeps the summary clean."""
    try:
        ours = zenoh_logs and sys.stdout.fileno() == 1
    except (AttributeError, OSError, ValueError):   # no real stdout (captured, closed): nothing to keep apart
        ours = False
    if not ours:
        yield
        return
    sys.stdout.flush()
    copy = os.dup(1)
    os.dup2(2, 1)
    saved = sys.stdout
    sys.stdout = open(copy, "w", encoding=saved.encoding, errors=saved.errors, closefd=False,
                      buffering=1 if saved.isatty() else -1)
    try:
        yield
    finally:
        sys.stdout.flush()
        sys.stdout = saved
        os.dup2(copy, 1)
        os.close(copy)
