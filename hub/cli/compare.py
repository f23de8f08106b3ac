"""`planthub compare RUN REFERENCE`: a run folder judged against a golden one, a line per signal, exit 1 and a PNG per failure (the comparison itself: hub/reports/compare.py)."""
from __future__ import annotations

import argparse
import logging
import math
from fnmatch import fnmatchcase
from pathlib import Path

from hub.cli.exits import FAILED, OK, UsageError

# plot's reading of the command line (shared): the same run-folder errors, the same slot addressing and globs
from hub.cli.options import number_type, seconds_argument
from hub.cli.plot import is_glob, listed_names, match_slots, recording_of, slots_of_columns
from hub.core.registry import did_you_mean
from hub.reports.compare import DEFAULT_ATOL, DEFAULT_RTOL, Recorded, compare
from hub.reports.compare_plots import plot_failures, png_name

_log = logging.getLogger("planthub.compare")


def add_command(sub, parents=(), formatter=argparse.HelpFormatter, epilog: str = ""):
    """The `compare` subcommand; returns its handler."""
    command = sub.add_parser(
        "compare", parents=parents, formatter_class=formatter,
        help="judge a run folder against a reference run folder: a tolerance band per signal; exit 1 if one fails",
        description="Judge RUN against REFERENCE (two folders `planthub run --out` wrote), the FMI cross-check\n"
                    "way: each recorded signal of the reference in a band |run − ref| ≤ atol + rtol·|ref|\n"
                    "(+ range-tol·range of ref), on the reference's time grid (the run interpolated where its\n"
                    "grid differs); bools, counts and names exactly; each event of the reference matched by the\n"
                    "run's within ±time-shift. A line per signal and event slot, the tally, a PNG per failure.",
        epilog="example:\n  planthub compare runs/new runs/golden\n"
               "  planthub compare runs/new runs/golden --slots 'bottle.body.*' 'barrier.*' --time-shift 0.02 "
               "--rtol 1e-2\n\n" + epilog)
    command.add_argument("run", type=Path, metavar="RUN", help="the run folder to judge")
    command.add_argument("reference", type=Path, metavar="REFERENCE", help="the golden run folder it must match")
    command.add_argument("--rtol", type=_tolerance, default=DEFAULT_RTOL, metavar="R",
                         help=f"band: relative to |ref| at each point (default {DEFAULT_RTOL:g})")
    command.add_argument("--atol", type=_tolerance, default=DEFAULT_ATOL, metavar="A",
                         help=f"band: absolute, in the signal's units (default {DEFAULT_ATOL:g})")
    command.add_argument("--range-tol", type=_tolerance, default=0.0, metavar="F",
                         help="band: relative to the reference signal's range, max − min (default 0; the FMI "
                              "cross-check's is 0.1)")
    command.add_argument("--time-shift", type=_tolerance, default=0.0, metavar="S",
                         help="s: a run this much early or late still passes — the band spans the reference "
                              "over ±S, an event may be matched ±S away (default 0: at the same point)")
    command.add_argument("--slots", nargs="+", action="extend", metavar="SLOT",
                         help="only these: recorded slots (a vec3 with its components, or SLOT.x), event slots, "
                              "or globs of them ('bottle.body.*'); default: all the reference records and logs")
    command.add_argument("--from", dest="start", type=seconds_argument, metavar="T", help="s: judge from this time on")
    command.add_argument("--to", dest="end", type=seconds_argument, metavar="T", help="s: judge up to this time")
    command.add_argument("--out", type=Path, metavar="DIR",
                         help="folder for a PNG per failing signal (default: RUN/compare)")
    command.set_defaults(command_parser=command)
    return _compare


_tolerance = number_type("expected a number ≥ 0, got {text}", "expected a finite number ≥ 0, got {text}",
                         lambda v: math.isfinite(v) and v >= 0)


def _compare(args) -> int:
    for label, folder in (("RUN", args.run), ("REFERENCE", args.reference)):
        try:
            recording_of(folder)
        except UsageError as exc:
            raise UsageError(f"{label} {exc}") from None
    if args.start is not None and args.end is not None and args.start >= args.end:
        raise UsageError(f"--from {args.start:g} s is not before --to {args.end:g} s")
    out = args.out or args.run / "compare"
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out} is a file, not a folder for the PNGs")
    run, ref = Recorded.read(args.run), Recorded.read(args.reference)
    _check_window(args, ref)
    names = _chosen(args.slots, run, ref) if args.slots else None
    result = compare(run, ref, rtol=args.rtol, atol=args.atol, range_tol=args.range_tol, slots=names,
                     time_shift=args.time_shift, window=(args.start, args.end))
    for note in result.notes:
        _log.info(f"planthub compare: {note}")
    plots = {path.name: path for path in plot_failures(result, out)}

    band = f"{args.atol:g} + {args.rtol:g}·|ref|" + (f" + {args.range_tol:g}·range" if args.range_tol else "")
    grid = (f"; the run's {result.run_points} points interpolated onto the reference's {len(ref.times)}"
            if result.resampled else "")
    print(f"planthub compare {args.run} against {args.reference}  (t = {result.window[0]:g}–{result.window[1]:g} s; "
          f"band {band}; time shift {args.time_shift:g} s{grid})")
    for verdict in result.verdicts:
        print(f"  {'✓' if verdict.passed else '✗'} {verdict.name} — {verdict.message()}")
        path = plots.get(png_name(verdict.name))
        if path is not None:
            print(f"      plot: {path}")
    for problem in result.problems:
        print(f"  ✗ {problem}")
    failed = len(result.failed)
    trouble = f"; {len(result.problems)} problem{'s' if len(result.problems) != 1 else ''}" if result.problems else ""
    print(f"{len(result.verdicts) - failed} signals passed, {failed} failed{trouble}")
    return OK if result.passed else FAILED


def _check_window(args, ref: Recorded) -> None:
    recording = ref.folder / "recording.csv"
    first, last = float(ref.times[0]), float(ref.times[-1])
    if args.start is not None and args.start > last:
        raise UsageError(f"--from {args.start:g} s is after the end of the reference, {recording} ({last:g} s)")
    if args.end is not None and args.end < first:
        raise UsageError(f"--to {args.end:g} s is before the start of the reference, {recording} ({first:g} s)")


def _chosen(specs: list[str], run: Recorded, ref: Recorded) -> list[str]:
    """The exact names --slots picks: the reference's columns as `planthub plot` addresses them
    (a vec3 slot stands for its components), and the slots of either event log; every spec that
    picks nothing named at once, with a did-you-mean."""
    columns = list(ref.columns)
    slots = slots_of_columns(columns)
    logged = sorted(set(ref.event_slots) | set(run.event_slots))
    picked, unmatched = [], []
    for spec in specs:
        found = match_slots(spec, slots, columns) + [s for s in logged if s == spec or fnmatchcase(s, spec)]
        picked += [name for name in found if name not in picked]
        if not found:
            unmatched.append(spec)
    if unmatched:
        names = [*slots, *columns, *logged]
        lines = []
        for spec in unmatched:
            hint = did_you_mean(spec, names)
            hint = hint if hint.startswith(" (did you mean") else ""
            lines.append(f"no recorded or logged slot matches {spec!r}{hint}" if is_glob(spec)
                         else f"neither recorded nor logged: {spec!r}{hint}")
        recorded = listed_names(name for name in slots) or "nothing"
        events = f"; the event logs name {listed_names(logged)}" if logged else "; the event logs are empty"
        raise UsageError(f"--slots: {'; '.join(lines)}. {ref.folder / 'recording.csv'} records {recorded}{events}")
    return picked
