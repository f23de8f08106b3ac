"""A recorded run folder read back for playback (`planthub view RUN_DIR`): the body recording and its scene, and beside them what `planthub run --out` wrote — the event log, the recorded slots and the final summary.

The body recording is what playback needs; without it (or its scene) there is nothing to draw and
the folder is refused. The other files only add to the page: a folder without them (a run killed
before it wrote its summary) plays all the same, and `notes` says what is missing. What is there
but broken is refused, naming the file and line, as `planthub plot` does.
"""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pyarrow.compute as pc

from hub.core.csvfiles import body_rows, reading
from hub.core.errors import PlanthubError
from hub.view.bodies_file import NAME, SCENE, BodyRecording
from hub.view.scene import read_scene

EVENTS, RECORDING, SUMMARY = "events.csv", "recording.csv", "summary.json"
EVENT_COLUMNS = ["time", "tick", "slot", "detail"]
#: the keys of summary.json that are the run's own; every other one is a section an observer contributed
RUN_KEYS = {"scenario", "file", "ended", "simulated", "wall", "events", "files"}
IN_PLAY = "bodies in play"   # the series of how many bodies were on stage, from bodies.arrows


class RecordedRun:
    """Everything a playback shows of the run in `directory`, read once (PlanthubError when the body
    recording or its scene is missing or broken, or another file is broken)."""

    def __init__(self, directory: Path):
        self.directory = directory = Path(directory)
        self.bodies = BodyRecording(directory)
        if not len(self.bodies):
            raise PlanthubError(f"{directory / NAME}: no recorded point (the run was killed before its first "
                                "batch was written)")
        self.scene = _scene(directory / SCENE)
        self.rate: int = self.scene["physics_rate"]
        self.run: str = self.scene.get("run") or directory.name
        self.start = int(self.bodies.ticks[0]) / self.rate
        self.end = int(self.bodies.ticks[-1]) / self.rate
        self.notes: list[str] = []   # what the folder lacks, or had to be read around
        self.events = EventLog.read(directory / EVENTS, self.notes)
        self.slots = Recording.read(directory / RECORDING, self.rate, self.notes)
        self.summary = _summary(directory / SUMMARY, self.notes)

    def tick_at(self, time: float) -> int:
        """The tick at `time` s (a time the page shows, so rounding must not step back a tick)."""
        return math.floor(time * self.rate + 1e-6)

    def in_play(self) -> tuple[np.ndarray, np.ndarray]:
        """(ticks, bodies in play at each recorded point)."""
        counts = pc.list_value_length(self.bodies.table.column("rows")).to_numpy(zero_copy_only=False)
        return self.bodies.ticks, np.asarray(counts, np.float64)

    def figures(self) -> dict | None:
        """The run's final figures as the hub's figures message has them (hub/view/broadcast.py), from
        summary.json; None without one."""
        s = self.summary
        if s is None:
            return None
        simulated, wall = s.get("simulated") or {}, s.get("wall") or {}
        ticks = simulated.get("ticks")
        return {"tick": ticks, "time": simulated.get("seconds"), "wall": wall.get("seconds"),
                "rtf": wall.get("realtime_factor"), "final": True,
                "sections": {k: v for k, v in s.items() if k not in RUN_KEYS}}

    def ended(self) -> str:
        """How the run ended, as summary.json says ("" without one)."""
        ended = (self.summary or {}).get("ended") or {}
        return ended.get("reason", "") if isinstance(ended, dict) else ""


class EventLog:
    """events.csv as the rows the page's log takes, [tick, slot, detail], in tick order."""

    def __init__(self, ticks: np.ndarray, rows: list):
        self.ticks = ticks
        self.rows = rows

    @classmethod
    def read(cls, path: Path, notes: list[str]) -> EventLog:
        if not path.is_file():
            notes.append(f"no {path}: the event log stays empty")
            return cls(np.zeros(0, np.int64), [])
        rows, ticks = [], []
        for line, row in _rows(path, EVENT_COLUMNS, notes, "an event log"):
            if line == 1:
                continue   # the header
            try:
                tick = int(row[1])
            except ValueError:
                raise PlanthubError(f"{path}:{line}: the tick {row[1]!r} is not a whole number") from None
            ticks.append(tick)
            rows.append([tick, row[2], row[3]])
        order = np.argsort(np.asarray(ticks, np.int64), kind="stable")
        return cls(np.asarray(ticks, np.int64)[order], [rows[i] for i in order])

    def count_to(self, tick: int) -> int:
        """How many events happened at or before `tick`."""
        return int(np.searchsorted(self.ticks, tick, side="right"))


class Recording:
    """recording.csv: the recorded slots' columns at each point, numbers where every value is one."""

    def __init__(self, ticks: np.ndarray, columns: dict[str, list]):
        self.ticks = ticks
        self.numbers: dict[str, np.ndarray] = {}
        self.whole: set[str] = set()             # columns of integers (counts, bools)
        self.texts: dict[str, list[str]] = {}    # columns that are not numbers (ids, names)
        for name, cells in columns.items():
            try:
                values = np.asarray([float(c) for c in cells], np.float64)
            except ValueError:
                self.texts[name] = cells
                continue
            self.numbers[name] = values
            if all(c.lstrip("-").isdigit() for c in cells):
                self.whole.add(name)
        self.names = list(columns)

    @classmethod
    def read(cls, path: Path, rate: int, notes: list[str]) -> Recording:
        if not path.is_file():
            notes.append(f"no {path}: no recorded slots to plot")
            return cls(np.zeros(0, np.int64), {})
        rows = list(_rows(path, None, notes, "a recording"))
        header = rows.pop(0)[1] if rows else []
        ticks = []
        for line, row in rows:
            try:
                ticks.append(round(float(row[0]) * rate))
            except (ValueError, OverflowError):   # not a number, or not a finite one
                raise PlanthubError(f"{path}:{line}: the time {row[0]!r} is not a finite number") from None
        columns = {name: [row[i] for _, row in rows] for i, name in enumerate(header) if i}
        return cls(np.asarray(ticks, np.int64), columns)

    def __len__(self) -> int:
        return len(self.ticks)

    def index_at(self, tick: int) -> int | None:
        """The last recorded row at or before `tick` (None before the first)."""
        i = int(np.searchsorted(self.ticks, tick, side="right")) - 1
        return i if i >= 0 else None

    def values(self, i: int) -> dict:
        """Row `i` as slot column → value (an int, a float or a text)."""
        out = {}
        for name in self.names:
            if name in self.numbers:
                v = float(self.numbers[name][i])
                out[name] = int(v) if name in self.whole else v
            else:
                out[name] = self.texts[name][i]
        return out


def _scene(path: Path) -> dict:
    if not path.is_file():
        raise PlanthubError(f"{path}: no such file: the scene of the body recording beside it (`planthub run "
                            "--record-bodies` writes both)")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise PlanthubError(f"cannot read {path}: {exc.strerror or exc}") from None
    return read_scene(data, str(path), " (the scene `planthub run --record-bodies` writes)")


def _summary(path: Path, notes: list[str]) -> dict | None:
    if not path.is_file():
        notes.append(f"no {path} (a run killed outright writes none): no figures")
        return None
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise PlanthubError(f"{path} is not JSON: {exc}") from None
    if not isinstance(summary, dict):
        raise PlanthubError(f"{path} is not a planthub run summary (a JSON object)")
    return summary


def _rows(path: Path, header: list[str] | None, notes: list[str], what: str):
    """(line, row) of a CSV file planthub wrote, its header first (line 1); a last line cut short (a
    run killed while writing it) is left out with a note. `header`: what the header must be."""
    with reading(path) as handle:
        reader = csv.reader(handle)
        first = next(reader, None)
        if not first:
            raise PlanthubError(f"{path} is empty: not even its header")
        if header is not None and first[:len(header)] != header:
            raise PlanthubError(f"{path} is not {what} planthub wrote: its header is {', '.join(first)!r}, "
                                f"not {', '.join(header)!r}")
        if header is None and first[0] != "time":
            raise PlanthubError(f"{path} is not {what} planthub wrote: its first column is {first[0]!r}, not 'time'")
        yield 1, first
        yield from body_rows(reader, path, len(first), lambda text: notes.append(f"{text}; played without it"))
