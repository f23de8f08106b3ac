"""How a run ended — its duration, a stop condition, an operator, its owner, a failure — for the summary's first line and summary.json's `ended`."""
from __future__ import annotations

from dataclasses import dataclass

from hub.core.observer import Stop

#: kind → the word the printed summary opens the line with
WORDS = {"duration": "ended", "completed": "ended", "stopped": "stopped", "closed": "closed", "failed": "failed"}


@dataclass(frozen=True)
class Ending:
    """`kind`: `duration` (it reached run.duration), `completed` (a stop condition ended it as
    planned: its orders out), `stopped` (an operator's stop, Ctrl-C), `closed` (its owner
    closed it before its end: a Simulation), `failed` (an error ended it); `reason` says it in words,
    with the time."""

    kind: str
    reason: str

    def line(self) -> str:
        return f"  {WORDS[self.kind]:<12} {self.reason}"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "reason": self.reason}


def ending(stop: Stop | None, tick: int, end_tick: int, rate: int, *, closed: bool,
           failure: BaseException | None = None) -> Ending | None:
    """How the run at `tick` ended, or None while it goes on (a summary taken mid-run)."""
    at = f"at t = {tick / rate:.9g} s"
    if failure is not None:
        if isinstance(failure, KeyboardInterrupt):
            return Ending("stopped", f"interrupted (Ctrl-C) {at}")
        # The first line: a participant's failure goes on with the tail of its output.
        first = str(failure).strip().splitlines()
        return Ending("failed", f"failed {at}" + (f": {first[0]}" if first else f" ({type(failure).__name__})"))
    if stop is not None:
        return Ending("completed" if stop.ended else "stopped", stop.reason)
    if tick >= end_tick:
        return Ending("duration", f"reached its duration {at} (run.duration)")
    if closed:
        return Ending("closed", f"closed {at}, before its duration ({end_tick / rate:.9g} s)")
    return None
