"""Helpers for data-plane tests: a run whose every point goes out, and the hub taking in its subscribers."""
from __future__ import annotations

import contextlib

from hub.bus.session import wait_until

from .bus_support import hub


class EveryPoint:
    """An observer after the bus link that waits, at each point, until the data plane's sender has
    sent it: the run goes at the sender's pace, so a test sees every point. The step loop itself
    never waits for the sender (tests/test_watchers.py); this is the test's own choice."""

    def __init__(self):
        self.run = None   # the Run, set once it exists

    def observe(self, tick, signals, events) -> None:
        assert self.run.dataplane.outbox.flush(5.0), f"the data plane did not send tick {tick} within 5 s"

    def close(self, reason: str) -> None:
        pass


@contextlib.contextmanager
def every_point(path, out=None, overrides=None, **options):
    """`bus_support.hub` with an EveryPoint observer."""
    waiting = EveryPoint()
    with hub(path, out, overrides, observers=[waiting], **options) as run:
        waiting.run = run
        yield run


def settle(master, condition):
    """Let the hub take in what arrived (subscribers, requests) until `condition` holds."""
    def check():
        master.dataplane.update()
        return condition()
    assert wait_until(check, 5.0)
