"""The exception family: bad input is a ScenarioError, a failure while running a SimulationError."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file: where it is and what is wrong."""

    file: str
    line: int | None
    path: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line else self.file
        return f"{where}: {self.path}: {self.message}" if self.path else f"{where}: {self.message}"


def format_path(path: tuple) -> str:
    """`('flows', 2, 'from')` → `flows[2].from`."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


class PlanthubError(Exception):
    """Base of every error planthub raises on purpose."""


class ScenarioError(PlanthubError):
    """A scenario (or a file it names) is invalid; carries every problem found, not just the first."""

    def __init__(self, problems: list[Problem]):
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        count = len(self.problems)
        super().__init__(f"{count} problem{'s' if count != 1 else ''} in scenario:\n{lines}")


class SimulationError(PlanthubError):
    """Something failed while a scenario was running."""


class CheckpointError(PlanthubError):
    """A run's state could not be saved or put back: a part that cannot save (named), a snapshot
    that does not fit the plant, a file that is truncated, corrupt or of another scenario."""
