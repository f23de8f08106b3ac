"""The PNGs of `planthub compare`: each failing signal against its band (and its deviation), each
failing event slot's reference and run times with their ±shift spans. The comparison itself is
hub/reports/compare.py."""
from __future__ import annotations

import re
from pathlib import Path

from hub.core.errors import PlanthubError
from hub.reports.compare import REAL, Comparison, EventVerdict, SignalVerdict


def plot_failures(comparison: Comparison, out_dir: Path) -> list[Path]:
    """A PNG per failing signal and event slot in `out_dir`, named after it; the paths. A PNG left
    there by an earlier comparison for a signal that passes now is removed, so the folder shows the
    failures of this one only."""
    from hub.reports.plots import _pyplot

    out_dir = Path(out_dir)
    written = []
    for verdict in comparison.verdicts:
        path = out_dir / png_name(verdict.name)
        if verdict.passed:
            if path.is_file():
                path.unlink()
            continue
        if isinstance(verdict, SignalVerdict) and verdict.trace is None:
            continue   # not judged (not in the run): nothing to draw
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
            plt = _pyplot()
            if isinstance(verdict, SignalVerdict):
                figure = _signal_figure(plt, verdict, comparison)
            else:
                figure = _event_figure(plt, verdict, comparison)
            figure.savefig(path, dpi=100, metadata={"Software": None})   # the same numbers, the same file
            plt.close(figure)
        except OSError as exc:
            raise PlanthubError(f"cannot write {path}: {exc.strerror or exc}") from None
        written.append(path)
    return written


def png_name(name: str) -> str:
    """The file name of a signal's or event slot's plot."""
    return re.sub(r"[^A-Za-z0-9._-]", "_", name) + ".png"


def _signal_figure(plt, verdict: SignalVerdict, comparison: Comparison):
    tr = verdict.trace
    real = verdict.kind == REAL
    figure, axes = plt.subplots(2 if real else 1, 1, figsize=(10, 6.4 if real else 3.6), sharex=True, squeeze=False)
    ax = axes[0, 0]
    steps = "default" if real else "steps-post"
    if real:
        ax.fill_between(tr.times, tr.lower, tr.upper, color="tab:blue", alpha=0.25, linewidth=0, label="band")
    ax.plot(tr.times, tr.reference, color="tab:blue", linewidth=1.2, drawstyle=steps, label="reference")
    ax.plot(tr.times, tr.run, color="tab:orange", linewidth=1.2, linestyle="--", drawstyle=steps, label="run")
    ax.plot(tr.times[tr.out], tr.run[tr.out], "x", color="tab:red", markersize=4,
            label=f"out of band ({verdict.out_of_band})" if real else f"differs ({verdict.out_of_band})")
    if tr.labels is not None:
        ax.set_yticks(range(len(tr.labels)), [t if t else "''" for t in tr.labels])
    elif not real:
        from matplotlib.ticker import MaxNLocator

        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_title(_title(verdict), fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    if real:   # the band is narrow beside the signal: its deviation shows where and by how much
        low = axes[1, 0]
        low.fill_between(tr.times, tr.lower - tr.reference, tr.upper - tr.reference, color="tab:blue", alpha=0.25,
                         linewidth=0, label="band − reference")
        low.plot(tr.times, tr.run - tr.reference, color="tab:orange", linewidth=1.0, label="run − reference")
        low.plot(tr.times[tr.out], (tr.run - tr.reference)[tr.out], "x", color="tab:red", markersize=4)
        low.set_ylabel("deviation")
        low.legend(fontsize=8)
        low.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel(f"time (s) — run {comparison.run} against {comparison.reference}")
    figure.tight_layout()
    return figure


def _title(verdict) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(f"{verdict.name}: {verdict.message()}", 150))


def _event_figure(plt, verdict: EventVerdict, comparison: Comparison):
    figure, ax = plt.subplots(figsize=(10, 2.6))
    shift = comparison.time_shift
    if shift > 0:
        for i, t in enumerate(verdict.reference_times):
            ax.axvspan(t - shift, t + shift, 0.5, 1, color="tab:blue", alpha=0.15, linewidth=0,
                       label=f"±{shift:g} s" if i == 0 else None)
    ax.vlines(verdict.reference_times, 0.5, 1, color="tab:blue", label="reference")
    ax.vlines(verdict.run_times, 0, 0.5, color="tab:orange", label="run")
    off = [e.time for e in verdict.missing]
    ax.plot(off, [0.75] * len(off), "x", color="tab:red", markersize=7, label=f"missing ({len(off)})")
    extra = [e.time for e in verdict.extra]
    ax.plot(extra, [0.25] * len(extra), "+", color="tab:red", markersize=9, label=f"extra ({len(extra)})")
    ax.set_yticks([0.25, 0.75], ["run", "reference"])
    ax.set_ylim(0, 1)
    ax.set_xlim(*comparison.window)
    ax.set_title(_title(verdict), fontsize=9)
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=8, loc="upper left")
    figure.tight_layout()
    return figure
