"""A campaign's cases handed to its cluster and collected as they finish, with progress; an interruption stops it and keeps what finished."""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from hub.campaign.case import LOST, NOT_RUN, OUTPUT, PASSED, STOPPED, STOPPING, command
from hub.campaign.cluster import ClusterError
from hub.campaign.plan import Campaign, Case

TICK = 1.0   # s between looks at the cluster while nothing finishes
NO_WORKERS = 60.0   # s a campaign waits for a cluster without workers to get one


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled as a Ctrl-C is: the campaign stops and writes what it has."""


@dataclass
class Outcome:
    """How a campaign went: a record per case, in case order (hub/campaign/case.py's result and
    what the campaign knows of the case), and how it ended."""

    campaign: Campaign
    out: Path
    cluster: str
    records: list[dict]
    ended: str
    interrupted: str | None = None     # "SIGINT" or "SIGTERM"
    broken: str | None = None          # why the campaign itself went wrong (interrupted, no cluster, no worker)
    wall_seconds: float = 0.0
    counts: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.broken is None and all(r["verdict"] == PASSED for r in self.records)


def spec(case: Case, out: Path) -> dict:
    """What a worker needs of a case: plain data, with absolute paths (the workers share the files)."""
    return {"scenario": str(case.scenario), "out": str((out / case.folder).resolve()), "judge": bool(case.expect),
            "overrides": case.overrides(), "resume": str(case.resume) if case.resume else None,
            "time_limit": case.time_limit}


def record(case: Case, out: Path, result: dict | None, *, verdict: str | None = None, reason: str = "",
           attempts: int = 0) -> dict:
    line = command(spec(case, out))
    found = {"index": case.index, "label": case.label, "scenario": str(case.scenario), "name": case.scenario_name,
             "parameters": dict(case.parameters), "folder": case.folder, "command": line,
             "attempts": attempts, "verdict": verdict, "reason": reason, "wall_seconds": None, "host": None,
             "exit_code": None, "outcomes": [], "figures": {}, "ended": ""}
    if result is not None:
        found.update(result)
        if attempts > 1:
            found["reason"] = (found["reason"] + "; " if found["reason"] else "") + \
                f"run again after its worker died (attempt {attempts})"
    return found


def run_campaign(campaign: Campaign, out: Path, cluster, progress=None, no_workers: float = NO_WORKERS) -> Outcome:
    """Every case on `cluster` (hub/campaign/cluster.py, entered); `progress(line)` hears of each
    finished case with the campaign's counts. A KeyboardInterrupt (Ctrl-C, Terminated), a cluster
    that fails (a ClusterError: its scheduler lost, …) or a cluster without a worker for
    `no_workers` s stops the running cases, keeps what finished and marks the rest not run."""
    progress = progress or (lambda line: print(line, file=sys.stderr, flush=True))
    started = time.monotonic()
    cases = {case.index: case for case in campaign.cases}
    records: dict[int, dict] = {}
    outcome = Outcome(campaign, out, cluster.where(), [], "every case ran")
    try:
        outcome.cluster = cluster.describe()
        for case in campaign.cases:
            (out / case.folder / OUTPUT).unlink(missing_ok=True)   # an earlier campaign's: this one's tells a case began
            cluster.submit(case.index, spec(case, out))
        alone = None   # since when the cluster has had no worker
        while len(records) < len(cases):
            for done in cluster.finished(TICK):
                case = cases[done.index]
                if done.result is None:
                    records[done.index] = record(case, out, None, verdict=LOST, reason=done.lost, attempts=done.attempt)
                else:
                    records[done.index] = record(case, out, done.result, attempts=done.attempt)
                progress(_line(records[done.index], records, len(cases), cluster, started))
            alone = (alone or time.monotonic()) if cluster.slots() == 0 else None
            if alone is not None and time.monotonic() - alone > no_workers:
                outcome.broken = f"no worker in the cluster for {no_workers:g} s"
                break
    except KeyboardInterrupt as exc:
        outcome.interrupted = interruption(exc)
        outcome.broken = f"interrupted ({outcome.interrupted})"
    except ClusterError as exc:
        outcome.broken = str(exc)
    if outcome.broken is not None:
        progress(f"campaign: {outcome.broken}: stopping the running cases (up to {STOPPING:.0f} s)")
        try:
            stopped = cluster.stop_cases(STOPPING)
        except KeyboardInterrupt as exc:   # a Ctrl-C or SIGTERM between stop_cases' own waits
            outcome.interrupted = outcome.interrupted or interruption(exc)
            stopped = None
        if stopped is not None and stopped.trouble is not None:
            progress(f"campaign: {stopped.trouble}")
        if stopped is not None and stopped.signal is not None:
            outcome.interrupted = outcome.interrupted or interruption(stopped.signal)
        for done in stopped.ended if stopped is not None else ():
            if done.result is not None:
                records[done.index] = record(cases[done.index], out, done.result, attempts=done.attempt)
        for index, case in cases.items():
            if index in records:
                continue
            if (out / case.folder / OUTPUT).is_file():   # it began, was stopped, and its result did not come back
                records[index] = record(case, out, None, verdict=STOPPED,
                                        reason=f"stopped: {outcome.broken}; its result did not come back")
            else:
                records[index] = record(case, out, None, verdict=NOT_RUN, reason=f"not run: {outcome.broken}")
        ran = sum(r["verdict"] not in (NOT_RUN, STOPPED) for r in records.values())
        outcome.ended = f"{outcome.broken} after {ran} of {len(cases)} cases"
    outcome.records = [records[i] for i in sorted(records)]
    outcome.wall_seconds = round(time.monotonic() - started, 3)
    outcome.counts = _counts(outcome.records)
    return outcome


def interruption(exc: KeyboardInterrupt) -> str:
    """The signal a KeyboardInterrupt stands for."""
    return "SIGTERM" if isinstance(exc, Terminated) else "SIGINT"


def not_run(campaign: Campaign, out: Path, where: str, why: str, interrupted: str | None = None) -> Outcome:
    """A campaign that could not start (its cluster unreachable, a signal while it started): every
    case not run, saying why."""
    records = [record(case, out, None, verdict=NOT_RUN, reason=f"not run: {why}") for case in campaign.cases]
    return Outcome(campaign, out, where, records, f"not started: {why}", interrupted=interrupted,
                   broken=f"not started: {why}", counts=_counts(records))


def _counts(records) -> dict:
    found: dict[str, int] = {}
    for r in records:
        found[r["verdict"]] = found.get(r["verdict"], 0) + 1
    return found


def _line(last: dict, records: dict, total: int, cluster, started: float) -> str:
    """`[ 3/16] ✓ label  2.1 s — 3 done, 1 failed, 2 running, 11 left, about 40 s to go`."""
    done = len(records)
    failed = sum(r["verdict"] != PASSED for r in records.values())
    elapsed = time.monotonic() - started
    left = total - done
    rest = f", about {elapsed / done * left:.0f} s to go" if left else ""
    try:
        running = cluster.running()
    except Exception:   # noqa: BLE001 — the count is for show; the cluster's trouble surfaces elsewhere
        running = "?"
    mark = "✓" if last["verdict"] == PASSED else "✗"
    wall = f"{last['wall_seconds']:.1f} s" if last["wall_seconds"] is not None else last["verdict"]
    said = f" — {last['verdict']}: {last['reason'].splitlines()[0]}" if last["verdict"] != PASSED and last["reason"] else ""
    return (f"[{done:>{len(str(total))}}/{total}] {mark} {last['label']}  {wall}{said}\n"
            f"    campaign: {done} done, {failed} failed, {running} running, {left} left{rest}")
