"""A run compared with a golden recording, the FMI cross-check way: a tolerance band around each reference signal, a verdict per signal and per event slot, a PNG of each failure.

What is compared. The reference folder says what: every column of its recording.csv (a vec3's
`.x/.y/.z` are three signals) and every slot in either folder's events.csv — an event log has no
header naming its slots, and a slot that fires only in the run is a deviation too. `slots` narrows
that to exact names (`planthub compare --slots` expands globs into them). A signal the reference
records and the run does not fails; one only the run records is not compared (told in `notes`).
The PNGs of failures are drawn by hub/reports/compare_plots.py.

Where. On the reference's time grid, in the window [start, end] when one is given. Where both grids
are equal (same points within 1 ns) values are compared point by point; elsewhere the run is
resampled onto the reference's points: reals linearly, bools, counts and names held from the run's
last point at or before (as the recorder means them). A run that does not cover the reference's
span (or the window) is a failure of its own (`problems`); its signals are judged where it does.

The band of a real signal. At each reference point, half-width w = atol + rtol·|ref| +
range_tol·(max ref − min ref) — numpy's isclose band, plus the FMI cross-check's tolerance relative
to the signal's range (fmpy's validate_result uses 10 % of the range and a few samples of time
shift, `range_tol=0.1`; the default here is 0, so the band is the point-wise one). With a time
shift S the band widens to the envelope of the reference's band over [t − S, t + S] (the grid points
in it and the interpolated values at its ends): a run up to S early or late stays in it. The run's
value must lie in the band (NaN equals only NaN). Bools, integers and names are compared exactly:
the run's value must be one the reference held within ±S of the point (S = 0: at the point).

Events. Each reference event must be matched by a run event of the same slot and detail within
±S seconds (S = 0: at the same time, the same tick at equal physics rates), one to one, in time
order; an unmatched reference event is missing, an unmatched run event extra, and either fails
its slot. Events are matched by time, not tick, so runs at different physics rates compare.

Verdicts carry the figures a benchmark takes as error metrics: a signal's largest |run − ref| at the
same time and when, its RMS, the points out of band and the first of them; an event slot's largest
time shift. Deviations are in the signal's own units; times in seconds.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hub.core.csvfiles import body_rows, reading
from hub.core.errors import PlanthubError
from hub.core.registry import did_you_mean

DEFAULT_RTOL = 1e-3
DEFAULT_ATOL = 1e-6
#: s: two times closer than this are one point. Times are tick / rate written with every digit, so
#: equal ticks give equal texts; 1 ns absorbs the rounding of tick / rate at different rates.
SAME_TIME = 1e-9
RECORDING, EVENTS = "recording.csv", "events.csv"
REAL, DISCRETE, TEXT = "real", "discrete", "text"   # a signal's kinds: compared in a band, exactly, exactly


@dataclass(frozen=True)
class Event:
    time: float
    slot: str
    detail: str


@dataclass
class Recorded:
    """A run folder read back: recording.csv's times and columns (as texts), events.csv's events
    (None without the file) and what reading had to work around."""
    folder: Path
    times: np.ndarray
    columns: dict[str, list[str]]
    events: list[Event] | None
    notes: list[str] = field(default_factory=list)

    @classmethod
    def read(cls, folder: Path) -> Recorded:
        folder = Path(folder)
        notes: list[str] = []
        times, columns = _recording(folder / RECORDING, notes)
        events = _events(folder / EVENTS, notes) if (folder / EVENTS).is_file() else None
        return cls(folder, times, columns, events, notes)

    @property
    def event_slots(self) -> list[str]:
        return sorted({e.slot for e in self.events or ()})


@dataclass
class Trace:
    """What a signal's verdict was judged on, for its plot: the reference's points, the run there,
    the band (reals) and which points are out of it."""
    times: np.ndarray
    reference: np.ndarray
    run: np.ndarray
    lower: np.ndarray | None
    upper: np.ndarray | None
    out: np.ndarray
    labels: list[str] | None = None   # a text signal's names, by code


@dataclass
class SignalVerdict:
    name: str
    kind: str                     # REAL, DISCRETE (bools, counts) or TEXT
    passed: bool
    points: int = 0               # reference points judged
    out_of_band: int = 0
    first_out: float | None = None
    max_deviation: float | None = None   # largest |run − ref| at the same time (None: names, or not judged)
    at_time: float | None = None
    rms: float | None = None
    excess: float | None = None   # how far the worst point lies outside its band (reals)
    problem: str = ""             # why it could not be judged (not in the run, no numbers there)
    trace: Trace | None = field(default=None, repr=False, compare=False)

    def message(self) -> str:
        """The verdict in a line, as `planthub compare` prints it after the signal's name."""
        if self.problem:
            return self.problem
        if self.kind == TEXT:
            return f"the same names ({self.points} points)" if self.passed else \
                f"{self.out_of_band} of {self.points} points differ from {self.first_out:g} s on"
        if self.max_deviation == 0:
            return f"equal at all {self.points} points"
        deviation = f"max deviation {self.max_deviation:.4g} at {self.at_time:g} s, rms {self.rms:.4g}"
        if self.passed:
            return f"{deviation} ({self.points} points)"
        where = "out of band" if self.kind == REAL else "differ"
        beyond = f", up to {self.excess:.4g} outside the band" if self.excess else ""
        return f"{self.out_of_band} of {self.points} points {where} from {self.first_out:g} s on; {deviation}{beyond}"


@dataclass
class EventVerdict:
    slot: str
    passed: bool
    reference: int                # events of the slot in the reference (in the window)
    matched: int
    missing: list[Event] = field(default_factory=list)   # in the reference, not in the run within ±shift
    extra: list[Event] = field(default_factory=list)     # in the run, matching none of the reference's
    max_shift: float | None = None    # run − reference, the largest in magnitude among the matched
    at_time: float | None = None      # the reference event's time of it
    run_times: list[float] = field(default_factory=list, repr=False)   # for the plot
    reference_times: list[float] = field(default_factory=list, repr=False)

    @property
    def name(self) -> str:
        return self.slot

    def message(self) -> str:
        if not self.matched:
            shift = ""
        elif abs(self.max_shift) <= SAME_TIME:
            shift = " at the same time" if self.matched == 1 else ", each at the same time"
        else:
            late = "later" if self.max_shift > 0 else "earlier"
            shift = f", the largest shift {abs(self.max_shift):.4g} s {late} in the run (the reference's at {self.at_time:g} s)"
        text = f"{self.matched} of {self.reference} reference event{'s' if self.reference != 1 else ''} matched{shift}"
        if self.missing:
            text += f"; missing: {_listed(self.missing)}"
        if self.extra:
            text += f"; extra in the run: {_listed(self.extra)}"
        return text


@dataclass
class Comparison:
    run: Path
    reference: Path
    rtol: float
    atol: float
    range_tol: float
    time_shift: float
    window: tuple[float, float]        # the span judged, s
    signals: list[SignalVerdict]
    events: list[EventVerdict]
    problems: list[str]                # failures of the whole run: not covering the span, no event log
    resampled: bool                    # the run's grid differs from the reference's
    run_points: int
    notes: list[str] = field(default_factory=list)   # what was not compared, what reading worked around

    @property
    def verdicts(self) -> list:
        return [*self.signals, *self.events]

    @property
    def failed(self) -> list:
        return [v for v in self.verdicts if not v.passed]

    @property
    def passed(self) -> bool:
        return not self.failed and not self.problems

    def signal(self, name: str) -> SignalVerdict:
        for verdict in self.signals:
            if verdict.name == name:
                return verdict
        raise KeyError(f"{name!r}: no signal of that name compared{did_you_mean(name, [s.name for s in self.signals])}")


def compare(run, reference, *, rtol: float = DEFAULT_RTOL, atol: float = DEFAULT_ATOL, range_tol: float = 0.0,
            slots=None, time_shift: float = 0.0, window: tuple[float | None, float | None] | None = None) -> Comparison:
    """`run` against `reference` (run folders, or what Recorded.read made of them), as the module
    docstring says. `slots`: exact column or event-slot names (default: everything);
    `window`: (start, end) in s, either None for the reference's own."""
    for name, value in (("rtol", rtol), ("atol", atol), ("range_tol", range_tol), ("time_shift", time_shift)):
        if not (math.isfinite(value) and value >= 0):
            raise PlanthubError(f"{name} must be a finite number ≥ 0, not {value!r}")
    if isinstance(slots, str):
        slots = [slots]
    run = run if isinstance(run, Recorded) else Recorded.read(run)
    ref = reference if isinstance(reference, Recorded) else Recorded.read(reference)
    columns, event_slots = _chosen(slots, run, ref)
    start, end = window or (None, None)
    start = ref.times[0] if start is None else start
    end = ref.times[-1] if end is None else end
    inside = (ref.times >= start - SAME_TIME) & (ref.times <= end + SAME_TIME)
    if not inside.any():
        raise PlanthubError(f"no point of {ref.folder / RECORDING} between {start:g} and {end:g} s (it has "
                            f"{ref.times[0]:g} to {ref.times[-1]:g} s)")

    problems, notes = [], [*(f"reference: {n}" for n in ref.notes), *(f"run: {n}" for n in run.notes)]
    covered = (ref.times >= run.times[0] - SAME_TIME) & (ref.times <= run.times[-1] + SAME_TIME)
    first, last = ref.times[inside][[0, -1]]
    if run.times[0] > first + SAME_TIME:
        problems.append(f"the run starts at {run.times[0]:g} s, after the reference's {first:g} s")
    if run.times[-1] < last - SAME_TIME:
        problems.append(f"the run ends at {run.times[-1]:g} s, before the reference's {last:g} s: "
                        "its signals are judged up to there")
    judged = inside & covered
    at = aligned(run.times, ref.times[judged])
    only_run = [c for c in run.columns if c not in ref.columns]
    if only_run and slots is None:
        notes.append(f"not compared, recorded by the run only: {', '.join(only_run)}")

    signals = []
    for name in columns:
        if name not in run.columns:
            signals.append(SignalVerdict(name, _kind(ref.columns[name]), False,
                                         problem=f"not in the run's recording ({run.folder / RECORDING})"))
            continue
        signals.append(_signal(name, ref, run, judged, at, rtol=rtol, atol=atol, range_tol=range_tol,
                               shift=time_shift))

    events = []
    if event_slots:
        if ref.events is not None and run.events is None:
            problems.append(f"{run.folder / EVENTS}: no such file, so the reference's events cannot be matched")
        elif ref.events is None:
            notes.append(f"{ref.folder / EVENTS}: no such file, so no event is compared")
        else:
            # Events after the run's end are not missing: that end is a problem of its own.
            span = max(start, run.times[0]), min(end, run.times[-1])
            events = [_event_slot(slot, ref.events, run.events, *span, time_shift) for slot in event_slots]
            events = [v for v in events if v.reference or v.extra]   # not a slot silent in the window
    return Comparison(run.folder, ref.folder, rtol, atol, range_tol, time_shift, (float(start), float(end)),
                      signals, events, problems, at is None, len(run.times), notes)


def _chosen(slots, run: Recorded, ref: Recorded) -> tuple[list[str], list[str]]:
    """(columns, event slots) to compare: all of them, or the names in `slots`; unknown names raise."""
    logged = sorted(set(ref.event_slots) | set(run.event_slots))
    if slots is None:
        return list(ref.columns), logged
    unknown = [s for s in slots if s not in ref.columns and s not in logged]
    if unknown:
        names = [*ref.columns, *logged]
        raise PlanthubError("; ".join(f"{s!r} is neither a column of {ref.folder / RECORDING} nor a slot of the "
                                      f"event logs{did_you_mean(s, names)}" for s in unknown))
    return [s for s in ref.columns if s in slots], [s for s in logged if s in slots]


# --- signals ------------------------------------------------------------------------------------

def _signal(name, ref: Recorded, run: Recorded, judged, at, *, rtol, atol, range_tol, shift) -> SignalVerdict:
    kind = _kind(ref.columns[name])
    t = ref.times
    if kind == TEXT:
        codes = {text: i for i, text in enumerate(dict.fromkeys(ref.columns[name] + run.columns[name]))}
        y_ref = np.asarray([codes[c] for c in ref.columns[name]], np.float64)
        y_run = np.asarray([codes[c] for c in run.columns[name]], np.float64)
        labels = list(codes)
    else:
        y_ref = _numbers(ref.columns[name])
        y_run = _numbers(run.columns[name])
        labels = None
        if y_run is None:
            bad = next(c for c in run.columns[name] if not _is_number(c))
            return SignalVerdict(name, kind, False, problem=f"the run records {bad!r} in {run.folder / RECORDING}, "
                                                            "not a number as the reference does")
    if not judged.any():
        return SignalVerdict(name, kind, False, problem="no point of the reference within the run's span to judge")
    if at is None:
        y_run = resample(run.times, y_run, t, held=kind != REAL)
    else:   # the run has each judged point of the reference: its own values there, no interpolation
        picked = np.full(len(t), np.nan)
        picked[judged] = y_run[at]
        y_run = picked
    if kind == REAL:
        span = y_ref[judged]
        finite = span[np.isfinite(span)]
        extent = float(finite.max() - finite.min()) if finite.size else 0.0
        lower, upper = band(t, y_ref, rtol=rtol, atol=atol + range_tol * extent, shift=shift)
        same = (y_run == y_ref) | (np.isnan(y_run) & np.isnan(y_ref))
        out = ~(same | ((y_run >= lower) & (y_run <= upper)))
    else:
        lower = upper = None
        out = ~held_within(t, y_ref, y_run, shift)
    out &= judged
    times, out_j = t[judged], out[judged]
    verdict = SignalVerdict(name, kind, not out_j.any(), points=int(judged.sum()), out_of_band=int(out_j.sum()),
                            first_out=float(times[out_j][0]) if out_j.any() else None)
    if kind != TEXT and verdict.points:
        deviation = np.abs(y_run[judged] - y_ref[judged])
        deviation[np.isnan(y_run[judged]) & np.isnan(y_ref[judged])] = 0.0
        deviation[np.isnan(deviation)] = np.inf
        worst = int(np.argmax(deviation))
        verdict.max_deviation, verdict.at_time = float(deviation[worst]), float(times[worst])
        verdict.rms = float(np.sqrt(np.mean(deviation ** 2)))
        if kind == REAL and out_j.any():
            y = y_run[judged][out_j]
            beyond = np.maximum(lower[judged][out_j] - y, y - upper[judged][out_j])
            verdict.excess = float(np.nanmax(np.where(np.isnan(beyond), np.inf, beyond)))
    verdict.trace = Trace(times, y_ref[judged], y_run[judged], None if lower is None else lower[judged],
                          None if upper is None else upper[judged], out_j, labels)
    return verdict


def band(t: np.ndarray, y: np.ndarray, *, rtol: float, atol: float, shift: float = 0.0):
    """(lower, upper) at each point t of the reference y: y ± (atol + rtol·|y|), and with a `shift`
    the envelope of that over [t − shift, t + shift] — the grid points in it and y interpolated at
    its two ends."""
    w = atol + rtol * np.abs(y)
    lower, upper = y - w, y + w
    if shift <= 0 or len(t) < 2:
        return lower, upper
    a = np.searchsorted(t, t - shift - SAME_TIME, side="left")
    b = np.searchsorted(t, t + shift + SAME_TIME, side="right")
    lower, upper = window_min(lower, a, b), -window_min(-upper, a, b)
    for end in (t - shift, t + shift):
        y_end = np.interp(end, t, y)
        w_end = atol + rtol * np.abs(y_end)
        lower, upper = np.fmin(lower, y_end - w_end), np.fmax(upper, y_end + w_end)
    return lower, upper


def window_min(values: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """min(values[a[i]:b[i]]) for every i (each window non-empty), from a sparse table: O(n log n),
    where a recording at every tick and a shift of seconds would make a window of thousands."""
    lengths = b - a
    levels = [values]
    while 2 ** len(levels) <= lengths.max():
        half = 2 ** (len(levels) - 1)
        levels.append(np.fmin(levels[-1][:-half], levels[-1][half:]))
    level = np.floor(np.log2(lengths)).astype(np.int64)
    out = np.empty_like(values)
    for k in np.unique(level):
        i = np.flatnonzero(level == k)
        out[i] = np.fmin(levels[k][a[i]], levels[k][b[i] - 2 ** k])
    return out


def held_within(t: np.ndarray, y_ref: np.ndarray, y_run: np.ndarray, shift: float) -> np.ndarray:
    """Whether each run value equals a value the reference held within ±shift of its point (the
    reference's values held from one point to the next, as bools, counts and names are)."""
    if shift <= 0:
        return y_run == y_ref
    # The reference as runs of one value: a window covers the runs from the one held at t − shift to
    # the one at t + shift, usually one or two, so the loop below goes round a few times.
    change = np.concatenate(([True], y_ref[1:] != y_ref[:-1]))
    run_of = np.cumsum(change) - 1
    values = y_ref[change]
    a = np.maximum(np.searchsorted(t, t - shift + SAME_TIME, side="right") - 1, 0)
    b = np.searchsorted(t, t + shift + SAME_TIME, side="right") - 1
    first, last = run_of[a], run_of[b]
    ok = np.zeros(len(t), bool)
    for step in range(int((last - first).max()) + 1):
        k = np.minimum(first + step, len(values) - 1)
        ok |= (values[k] == y_run) & (first + step <= last)
    return ok


def aligned(t_run: np.ndarray, t_ref: np.ndarray) -> np.ndarray | None:
    """The index of the run's point at each of the reference's times t_ref, or None when the run
    lacks one (within SAME_TIME): then the grids differ and the run is resampled."""
    if not len(t_ref):
        return None
    i = np.clip(np.searchsorted(t_run, t_ref - SAME_TIME), 0, len(t_run) - 1)
    return i if bool(np.all(np.abs(t_run[i] - t_ref) <= SAME_TIME)) else None


def resample(t_from: np.ndarray, y: np.ndarray, t_to: np.ndarray, *, held: bool) -> np.ndarray:
    """y (at t_from) at the times t_to: linear between points, or held from the last point at or
    before (`held`); clamped to the ends (points outside t_from are not judged)."""
    if held:
        i = np.searchsorted(t_from, t_to + SAME_TIME, side="right") - 1
        return y[np.maximum(i, 0)]
    return np.interp(t_to, t_from, y)


def _kind(texts: list[str]) -> str:
    """The recorder writes reals with every digit (`0.0`), counts and bools as whole numbers."""
    if all(_whole(c) for c in texts):
        return DISCRETE
    return REAL if all(_is_number(c) for c in texts) else TEXT


def _whole(text: str) -> bool:
    return text.lstrip("-").isdigit()


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _numbers(texts: list[str]) -> np.ndarray | None:
    try:
        return np.asarray([float(c) for c in texts], np.float64)
    except ValueError:
        return None


# --- events ---------------------------------------------------------------------------------------

def _event_slot(slot: str, ref_events: list[Event], run_events: list[Event], start, end, shift) -> EventVerdict:
    """The slot's events matched detail by detail."""
    ref = [e for e in ref_events if e.slot == slot and start - SAME_TIME <= e.time <= end + SAME_TIME]
    run = [e for e in run_events if e.slot == slot and start - shift - SAME_TIME <= e.time <= end + shift + SAME_TIME]
    verdict = EventVerdict(slot, True, len(ref), 0, reference_times=[e.time for e in ref],
                           run_times=[e.time for e in run])
    shifts = []
    for detail in dict.fromkeys(e.detail for e in ref + run):
        mine = [e for e in ref if e.detail == detail]
        theirs = [e for e in run if e.detail == detail]
        pairs, missing, extra = match_events([e.time for e in mine], [e.time for e in theirs], shift)
        shifts += [(theirs[j].time - mine[i].time, mine[i].time) for i, j in pairs]
        verdict.missing += [mine[i] for i in missing]
        verdict.extra += [theirs[j] for j in extra if start - SAME_TIME <= theirs[j].time <= end + SAME_TIME]
    verdict.matched = len(shifts)
    if shifts:
        verdict.max_shift, verdict.at_time = max(shifts, key=lambda s: abs(s[0]))
    verdict.missing.sort(key=lambda e: e.time)
    verdict.extra.sort(key=lambda e: e.time)
    verdict.passed = not verdict.missing and not verdict.extra
    return verdict


def match_events(reference: list[float], run: list[float], shift: float):
    """(pairs (i, j), unmatched i, unmatched j) of two sorted lists of times, one to one within ±shift.
    Taking for each reference time the earliest run time not too early for it matches as many as
    any assignment can (both lists sorted, every tolerance the same width)."""
    pairs, missing, j = [], [], 0
    taken = set()
    for i, t in enumerate(reference):
        while j < len(run) and run[j] < t - shift - SAME_TIME:
            j += 1
        if j < len(run) and run[j] <= t + shift + SAME_TIME:
            pairs.append((i, j))
            taken.add(j)
            j += 1
        else:
            missing.append(i)
    return pairs, missing, [j for j in range(len(run)) if j not in taken]


def _listed(events: list[Event], most: int = 3) -> str:
    shown = ", ".join(f"{e.time:g} s ({e.detail})" if e.detail else f"{e.time:g} s" for e in events[:most])
    return shown + (f", … ({len(events)} in all)" if len(events) > most else "")


# --- reading --------------------------------------------------------------------------------------

def _recording(path: Path, notes: list[str]) -> tuple[np.ndarray, dict[str, list[str]]]:
    if not path.is_file():
        raise PlanthubError(f"{path}: no such file (a run folder holds what `planthub run --out DIR` wrote)")
    with reading(path) as handle:
        rows = csv.reader(handle)
        header = next(rows, None)
        if not header:
            raise PlanthubError(f"{path} is empty: not even its header (the run wrote nothing)")
        if header[0] != "time":
            raise PlanthubError(f"{path} is not a planthub recording: its first column is {header[0]!r}, not 'time'")
        times, cells = [], []
        for line, row in body_rows(rows, path, len(header), lambda text: notes.append(f"{text}; compared without it")):
            try:
                t = float(row[0])
            except ValueError:
                raise PlanthubError(f"{path}:{line}: the time {row[0]!r} is not a number") from None
            if not math.isfinite(t) or (times and t < times[-1]):
                raise PlanthubError(f"{path}:{line}: the time {row[0]!r} is "
                                    + ("not finite" if not math.isfinite(t) else f"before the last one, {times[-1]!r}"))
            times.append(t)
            cells.append(row[1:])
    if not times:
        raise PlanthubError(f"{path} is empty: its header, but no recorded point (the run ended before its first "
                            "communication point)")
    columns = {name: [row[i] for row in cells] for i, name in enumerate(header[1:])}
    return np.asarray(times, np.float64), columns


def _events(path: Path, notes: list[str]) -> list[Event]:
    with reading(path) as handle:
        rows = csv.reader(handle)
        header = next(rows, None)
        if not header:
            raise PlanthubError(f"{path} is empty: not even its header")
        if header[:4] != ["time", "tick", "slot", "detail"]:
            raise PlanthubError(f"{path} is not a planthub event log: its header is {','.join(header)!r}, "
                                "not 'time,tick,slot,detail'")
        events = []
        for line, row in body_rows(rows, path, len(header), lambda text: notes.append(f"{text}; compared without it")):
            try:
                events.append(Event(float(row[0]), row[2], row[3]))
            except ValueError:
                raise PlanthubError(f"{path}:{line}: the time {row[0]!r} is not a number") from None
    return sorted(events, key=lambda e: e.time)
