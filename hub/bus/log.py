"""Zenoh's own log: RUST_LOG, or the level the command line asks for, set up once before the first session opens."""
from __future__ import annotations

import os

_level = "off"
_started = False


def set_level(level: str) -> None:
    """Zenoh's log level for this process when RUST_LOG is not set: off, error, warn, info, debug
    or trace (`planthub -vv` asks for info, `-vvv` for debug). Takes effect at the first session."""
    global _level
    _level = level


def start() -> None:
    """Start Zenoh's log as asked (hub/bus/session.py calls it before opening a session). Zenoh's
    logger is process-wide and the first set-up wins, so nothing is set up unless RUST_LOG or a
    level asks for it: a program that embeds the hub and sets up Zenoh's log itself keeps its own."""
    global _started
    if _started:
        return
    _started = True
    if _level == "off" and not os.environ.get("RUST_LOG"):
        return
    import zenoh

    zenoh.init_log_from_env_or(_level)   # RUST_LOG, when set, wins: Zenoh's own filter syntax
