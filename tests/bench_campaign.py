"""`make bench`, campaigns: 16 cases of the bottling plant's first 60 s (seeds 0–15) on a LocalCluster of 2 workers against the same cases one after another through the same case runner, in one run.

Both sides run each case the way a campaign does (hub/campaign/case.py): a child process per case,
forked by a warm zygote (hub/campaign/zygote.py) — one in this process for the cases one after
another, one per worker for the campaign — so the speed-up is what the cluster adds, and the
zygote's start is paid on both sides (once here, once per worker there). The speed-up is the
sequential wall time over the campaign's, the cluster's start included. The overhead per case is
what a case costs beyond its run's steps: Dask's part (the campaign's worker-time, wall × cases at
once, less the time its cases took: scheduling, handing a case over, the result back, the
cluster's and the zygotes' start, a worker between cases) and the child's part (a case's wall
time less its run's own, from its summary.json: the fork, the scenario's check and build, its
files written); for comparison, the child's part of two cases started as fresh Pythons
(PLANTHUB_CAMPAIGN_FRESH=1, the way before the warm start). The routing logic runs in the hub
(`objects.control.runs: hub`, the same results) so that no case starts a participant process of
its own beside its run. Run alone: `python -m tests.bench_campaign`.
"""
from __future__ import annotations

import json
import os
import statistics
import tempfile
import time
from pathlib import Path

from hub.campaign.case import FRESH, run_case
from hub.campaign.cluster import Cluster
from hub.campaign.plan import load_campaign
from hub.campaign.runner import run_campaign, spec
from hub.campaign.zygote import close_zygote

from .helpers import ROOT

CASES = 16
SECONDS = 60
WORKERS = 2
FRESH_CASES = 2
FILE = f"""\
planthub: 1
name: bottling_plant_seeds
scenarios: [{ROOT / 'scenarios' / 'bottling_plant.yaml'}]
matrix:
  run.duration: [{SECONDS}]
  objects.control.runs: [hub]
seeds: {CASES}
time_limit: 600
"""


def one_after_another(cases, folder: Path) -> list[dict]:
    """Each case through the campaign's case runner, in this process, one after another."""
    return [run_case(spec(case, folder)) for case in cases]


def started(result: dict, folder: Path) -> float:
    """A case's wall time less its run's steps (summary.json's wall): the child's start and end."""
    summary = json.loads((folder / "summary.json").read_text())
    return result["wall_seconds"] - summary["wall"]["seconds"]


def campaign() -> None:
    with tempfile.TemporaryDirectory(prefix="planthub-bench-campaign-") as scratch:
        folder = Path(scratch)
        (folder / "campaign.yaml").write_text(FILE)
        plan = load_campaign(folder / "campaign.yaml")
        load = os.getloadavg()[0]
        began = time.perf_counter()
        sequential = one_after_another(plan.cases, folder / "sequential")
        total = time.perf_counter() - began
        close_zygote()
        os.environ[FRESH] = "1"
        try:
            fresh = one_after_another(plan.cases[:FRESH_CASES], folder / "fresh")
        finally:
            del os.environ[FRESH]
        began = time.perf_counter()
        with Cluster(None, WORKERS) as cluster:
            start = time.perf_counter() - began
            outcome = run_campaign(plan, folder / "campaign", cluster, progress=lambda line: None)
        wall = time.perf_counter() - began
        load_after = os.getloadavg()[0]
        child = statistics.median(started(r, folder / "campaign" / c.folder) for r, c in zip(outcome.records, plan.cases))
        child_here = statistics.median(started(r, folder / "sequential" / c.folder)
                                       for r, c in zip(sequential[1:], plan.cases[1:]))   # the first starts the zygote
        child_fresh = statistics.median(started(r, folder / "fresh" / c.folder) for r, c in zip(fresh, plan.cases))
        run = statistics.median(r["wall_seconds"] - started(r, folder / "sequential" / c.folder)
                                for r, c in zip(sequential, plan.cases))
        same = all(a["figures"] == b["figures"] and a["verdict"] == b["verdict"]
                   for a, b in zip(sequential, outcome.records))
    children = [r["wall_seconds"] for r in outcome.records]
    dask = (outcome.wall_seconds * WORKERS - sum(children)) / CASES
    print(f"\n## Campaigns: {CASES} cases of the bottling plant's first {SECONDS} s, {WORKERS} workers against one "
          "after another\n")
    print("| figure | value |")
    print("|---|---:|")
    for name, value in (("cases", f"{CASES}"),
                        ("one after another through the case runner, its zygote's start included (s)", f"{total:.1f}"),
                        (f"campaign on a LocalCluster of {WORKERS} workers, its start included (s)", f"{wall:.1f}"),
                        ("of it the cluster's start (s)", f"{start:.2f}"),
                        ("speed-up", f"{total / wall:.2f}×"),
                        ("overhead per case, Dask's part: scheduling, hand-over, result, starts (s)", f"{dask:.3f}"),
                        ("overhead per case, the child's part in the campaign, median (s)", f"{child:.3f}"),
                        ("overhead per case, both parts (s)", f"{dask + child:.3f}"),
                        ("the child's part one after another, median (s)", f"{child_here:.3f}"),
                        (f"the child's part started afresh, no zygote, median of {FRESH_CASES} (s)", f"{child_fresh:.3f}"),
                        ("a case's run's own steps, median (s)", f"{run:.2f}"),
                        ("the same verdicts and figures both ways", "yes" if same else "NO"),
                        ("load average before, after (1 min)", f"{load:.1f}, {load_after:.1f}")):
        print(f"| {name} | {value} |")
    print(f"\nVerdicts of the campaign's cases: {dict(outcome.counts)} (the plant's expectations are set for its whole "
          "run with seed 0; here they only show that every case ran).")


if __name__ == "__main__":
    campaign()
