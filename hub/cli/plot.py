"""`planthub plot`: a PNG of recorded slots over time, one panel each, from a run folder's recording.csv."""
from __future__ import annotations

import argparse
import csv
import logging
from dataclasses import dataclass, replace
from fnmatch import fnmatchcase
from pathlib import Path

from hub.cli.exits import OK, UsageError
from hub.cli.options import seconds_argument
from hub.core.csvfiles import body_rows, reading
from hub.core.errors import PlanthubError
from hub.core.registry import did_you_mean

_log = logging.getLogger("planthub.plot")

RUN_FILES = ("recording.csv", "events.csv", "summary.json")   # what `planthub run --out DIR` writes
WIDTH = 10.0          # inches at 100 dpi: the PNG is 1000 px wide …
PANEL_HEIGHT = 2.4    # … and 240 px tall per panel
MAX_PANELS = 40       # 9600 px: a glob that picks more is more likely a mistake than a wish
_COMPONENTS = ("x", "y", "z", "w")
_MARK_COLOURS = ("tab:red", "tab:purple", "tab:brown", "tab:olive", "tab:cyan", "tab:pink")
_LISTED = 30          # names listed in a message, at most


def add_command(sub, parents=(), formatter=argparse.HelpFormatter, epilog: str = ""):
    """The `plot` subcommand; returns its handler."""
    plot = sub.add_parser(
        "plot", parents=parents, formatter_class=formatter,
        help="draw recorded slots over time as a PNG, from a run folder's recording.csv",
        description="Draw recorded slots over time from RUN_DIR/recording.csv (the folder `planthub run --out`\n"
                    "wrote): one panel per slot on a shared time axis, a vec3 or quat slot's components in one\n"
                    "panel, bools, counts and names as steps. Prints the PNG's path. Given a campaign's folder\n"
                    "(`planthub campaign --out`), draws its figures (SLOT: a figure of cases.csv, or wall_s)\n"
                    "against the parameter --against KEY, a line per combination of the other parameters.",
        epilog="example:\n  planthub plot runs/stop_at_barrier bottle.body.position.x belt.drive.running "
               "--events 'barrier.*'\n  planthub plot runs/bottling_plant 'sink_*.count.total' --from 60 --to 120 "
               "--out sinks.png\n  planthub plot runs/speeds plant.delivered --against objects.belt.speed\n\n" + epilog)
    plot.add_argument("run", type=Path, metavar="RUN_DIR", help="a run folder: what `planthub run --out DIR` wrote")
    plot.add_argument("slots", nargs="+", metavar="SLOT",
                      help="a recorded slot, object.component.slot (a vec3's components together, or one: "
                           "SLOT.x), or a glob of them ('sink_*.count.total'); each gets a panel")
    plot.add_argument("--out", type=Path, metavar="FILE.png", help="the PNG to write (default: RUN_DIR/plot.png)")
    plot.add_argument("--from", dest="start", type=seconds_argument, metavar="T", help="s: draw from this time on")
    plot.add_argument("--to", dest="end", type=seconds_argument, metavar="T", help="s: draw up to this time")
    plot.add_argument("--against", metavar="KEY",
                      help="with a campaign's folder: the parameter along the x axis (a --set key of its matrix)")
    plot.add_argument("--events", action="append", default=[], metavar="PATTERN",
                      help="also mark the times of the events in events.csv whose slot matches, a name or a glob "
                           "('barrier.trigger.*'); repeatable")
    plot.set_defaults(command_parser=plot)
    return _plot


@dataclass
class Slot:
    """A recorded slot and the columns of it to draw (a vec3's x, y, z; or only the one asked for)."""
    name: str
    columns: list[str]


def _plot(args) -> int:
    from hub.cli.campaign_plot import is_campaign, plot_campaign
    from hub.reports.plots import Line, Panel, draw

    if is_campaign(args.run):
        return plot_campaign(args)
    if args.against is not None:
        raise UsageError(f"--against {args.against}: {args.run} is no campaign's folder (it has no campaign.json)")
    recording = recording_of(args.run)
    out = args.out or args.run / "plot.png"
    if out.suffix.lower() != ".png":
        raise UsageError(f"--out {out}: planthub plot writes a PNG, so name a .png file")
    if args.start is not None and args.end is not None and args.start >= args.end:
        raise UsageError(f"--from {args.start:g} s is not before --to {args.end:g} s")
    header = _header(recording)
    slots = _select(args.slots, header, recording)
    if len(slots) > MAX_PANELS:
        raise UsageError(f"{len(slots)} slots picked from {recording} ({listed_names(s.name for s in slots)}): at most "
                         f"{MAX_PANELS} panels fit in one plot; name fewer")
    wanted = [c for slot in slots for c in slot.columns]
    times, values = _read(recording, header, wanted, args.start, args.end)
    window = (args.start if args.start is not None else times[0], args.end if args.end is not None else times[-1])
    marks = _marks(args.run, args.events, *window)

    panels = []
    for i, slot in enumerate(slots):
        lines, whole = [], True
        for column in slot.columns:
            y, held, integers = _series(values[column])
            whole &= integers
            lines.append(Line(times, y, label=column if len(slot.columns) > 1 else "", steps=held))
        title = slot.columns[0] if len(slot.columns) == 1 else slot.name
        panels.append(Panel(title, "time (s)", "", lines, integers=whole,
                            marks=marks if i == 0 else [_unlabelled(m) for m in marks]))
    folder = next((p for p in out.parents if p.exists()), None)
    if folder is not None and not folder.is_dir():
        raise UsageError(f"--out {out}: {folder} is a file, not a folder")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        draw(out, panels, width=WIDTH, height_each=PANEL_HEIGHT, share_x=True,
             xlim=window if window[0] < window[1] else None)
    except OSError as exc:
        raise PlanthubError(f"cannot write {out}: {exc.strerror or exc}") from None
    _log.info(f"planthub plot: {_count(len(panels), 'panel')} ({listed_names(s.name for s in slots)}), "
              f"t = {window[0]:g}–{window[1]:g} s, {_count(len(times), 'point')}")
    print(out)
    return OK


def recording_of(run: Path) -> Path:
    """RUN_DIR/recording.csv, or an error that says what RUN_DIR is instead."""
    if not run.exists():
        raise UsageError(f"{run}: no such folder (give the run folder `planthub run --out DIR` wrote)")
    if not run.is_dir():
        hint = f": give its folder, {run.parent}" if run.name == "recording.csv" else \
            " (give the run folder `planthub run --out DIR` wrote)"
        raise UsageError(f"{run} is a file, not a run folder{hint}")
    recording = run / "recording.csv"
    if recording.is_file():
        return recording
    present = [name for name in RUN_FILES if (run / name).is_file()]
    if present:
        raise UsageError(f"{recording}: no such file (the run folder holds only {', '.join(present)})")
    inside = sorted(str(d) for d in run.iterdir() if d.is_dir() and (d / "recording.csv").is_file())
    where = f"; run folders in it: {listed_names(inside)}" if inside else ""
    raise UsageError(f"{run} is not a run folder: it holds none of {', '.join(RUN_FILES)} "
                     f"(what `planthub run --out DIR` writes){where}")


def _header(recording: Path) -> list[str]:
    with reading(recording) as handle:
        header = next(csv.reader(handle), None)
    if not header:
        raise PlanthubError(f"{recording} is empty: not even its header (the run wrote nothing)")
    if header[0] != "time":
        raise PlanthubError(f"{recording} is not a planthub recording: its first column is {header[0]!r}, "
                            "not 'time'")
    return header


def slots_of_columns(columns: list[str]) -> dict[str, list[str]]:
    """Slot name → its columns, in the recording's order: a vec3 or quat slot's .x, .y, .z(, .w) under
    its own name. A slot's address has three parts, so `a.b.x` is a slot, not a component."""
    present = set(columns)
    slots: dict[str, list[str]] = {}
    for column in columns:
        base, _, part = column.rpartition(".")
        vector = part in _COMPONENTS and base.count(".") >= 2 and all(f"{base}.{c}" in present for c in "xyz")
        slots.setdefault(base if vector else column, []).append(column)
    return slots


def _select(specs: list[str], header: list[str], recording: Path) -> list[Slot]:
    """The panels the SLOT arguments ask for, in their order; every problem named at once."""
    columns = header[1:]
    slots = slots_of_columns(columns)
    of_column = {c: name for name, cs in slots.items() for c in cs}
    if not columns:
        raise PlanthubError(f"{recording} records no slot, only the time: the scenario has no `record:` list")
    picked: dict[str, list[str]] = {}
    problems = []
    for spec in specs:
        found = match_slots(spec, slots, columns)
        if not found:
            problems.append(spec)
        for column in found:
            chosen = picked.setdefault(of_column[column], [])
            if column not in chosen:
                chosen.append(column)
    if problems:
        listed = listed_names(f"{name} ({', '.join(c.rpartition('.')[2] for c in cs)})" if cs != [name] else name
                        for name, cs in slots.items())
        names = [*slots, *columns]
        lines = []
        for spec in problems:
            hint = did_you_mean(spec, names)
            kind = "no recorded slot matches" if is_glob(spec) else "not recorded:"
            lines.append(f"{kind} {spec!r}{hint if hint.startswith(' (did you mean') else ''}")
        raise UsageError(f"{recording}: {'; '.join(lines)}. It records: {listed}")
    return [Slot(name, [c for c in slots[name] if c in chosen]) for name, chosen in picked.items()]


def match_slots(spec: str, slots: dict[str, list[str]], columns: list[str]) -> list[str]:
    if spec in slots:
        return slots[spec]
    if spec in columns:
        return [spec]
    if is_glob(spec):
        hits = {c for name, cs in slots.items() if fnmatchcase(name, spec) for c in cs}
        hits |= {c for c in columns if fnmatchcase(c, spec)}
        return [c for c in columns if c in hits]
    obj, dot, slot = spec.partition(".")
    if dot and "." not in slot:   # object.slot, as a scenario may write it where the slot's name is unique
        named = [name for name in slots if name.split(".")[0] == obj and name.split(".")[-1] == slot]
        if len(named) == 1:
            return slots[named[0]]
    return []


def is_glob(text: str) -> bool:
    return any(c in text for c in "*?[")


def _read(recording: Path, header: list[str], wanted: list[str], start, end):
    """The times in [start, end] and the wanted columns' texts there."""
    index = {name: i for i, name in enumerate(header)}
    times, texts = [], {c: [] for c in wanted}
    first = last = None
    def cut(text):   # a run killed while the recorder wrote its last line
        _log.warning(f"planthub plot: warning: {text}; drawn without it")

    with reading(recording) as handle:
        rows = csv.reader(handle)
        next(rows)
        for line, row in body_rows(rows, recording, len(header), cut):
            try:
                t = float(row[0])
            except ValueError:
                raise PlanthubError(f"{recording}:{line}: the time {row[0]!r} is not a number") from None
            first = t if first is None else first
            last = t
            if (start is None or t >= start) and (end is None or t <= end):
                times.append(t)
                for column in wanted:
                    texts[column].append(row[index[column]])
    if first is None:
        raise PlanthubError(f"{recording} is empty: its header, but no recorded point (the run ended before "
                            "its first communication point)")
    if start is not None and start > last:
        raise UsageError(f"--from {start:g} s is after the end of {recording} ({last:g} s)")
    if end is not None and end < first:
        raise UsageError(f"--to {end:g} s is before the start of {recording} ({first:g} s)")
    if not times:
        raise UsageError(f"no recorded point between --from {start:g} s and --to {end:g} s in {recording} "
                         f"(points from {first:g} to {last:g} s)")
    return times, texts


def _series(texts: list[str]):
    """(values, held, integers): numbers where every text is one, else the texts (a string slot's
    names, categories on the y axis). A bool, a count or a name holds from one point to the next,
    so it is drawn as steps; integers get whole-number ticks."""
    try:
        numbers = [float(t) for t in texts]
    except ValueError:
        return [t if t else "''" for t in texts], True, False
    integers = all(t.lstrip("-").isdigit() for t in texts)
    return numbers, integers, integers


def _marks(run: Path, patterns: list[str], first: float, last: float):
    from hub.reports.plots import Marks

    if not patterns:
        return []
    log = run / "events.csv"
    if not log.is_file():
        raise UsageError(f"{log}: no such file, so --events has no events to mark")
    with reading(log) as handle:
        reader = csv.DictReader(handle)
        if reader.fieldnames is None:
            raise PlanthubError(f"{log} is empty: not even its header")
        if not {"time", "slot"} <= set(reader.fieldnames):
            raise PlanthubError(f"{log} is not a planthub event log: its header names no time and slot columns")
        events = []
        for line, row in enumerate(reader, start=2):
            try:
                events.append((float(row["time"]), row["slot"]))
            except (TypeError, ValueError):
                raise PlanthubError(f"{log}:{line}: the time {row['time']!r} is not a number") from None
    logged = sorted({slot for _, slot in events})
    marks = []
    for i, pattern in enumerate(patterns):
        times = [t for t, slot in events if slot == pattern or fnmatchcase(slot, pattern)]
        if not times:
            hint = did_you_mean(pattern, logged)
            known = f"; it logs {listed_names(logged)}" if logged else "; it logs no event"
            _log.warning(f"planthub plot: warning: --events {pattern!r}: no event in {log} matches"
                         f"{hint if hint.startswith(' (did you mean') else ''}{known}")
            continue
        shown = [t for t in times if first <= t <= last]
        marks.append(Marks(shown, label=f"{pattern} ({len(shown)})", color=_MARK_COLOURS[i % len(_MARK_COLOURS)]))
    return marks



def _unlabelled(marks):
    return replace(marks, label="")


def _count(n: int, thing: str) -> str:
    return f"{n} {thing}{'s' if n != 1 else ''}"


def listed_names(names) -> str:
    names = list(names)
    shown = ", ".join(names[:_LISTED])
    return shown + (f", … ({len(names)} in all)" if len(names) > _LISTED else "")
