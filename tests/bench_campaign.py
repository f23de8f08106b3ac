"""`make bench`, campaigns: 16 cases of the bottling plant's first 60 s (seeds 0–15) on a LocalCluster of 2 workers against the same cases one after another in one process, as the sweeps of the report run today.

The speed-up is the sequential wall time over the campaign's (cluster start included). The
overhead per case is what a case costs beyond its run: the campaign's worker-time (wall × cases
at once) less the time the cases' child processes took, per case (scheduling, handing the case
over, the result back, a worker between cases); and the child's own start (a fresh Python that
imports the hub: the child's wall less the same run's in one process). The routing logic runs
in the hub (`objects.control.runs: hub`, the same results) so that no case starts a
participant process of its own beside its run. Run alone: `python -m tests.bench_campaign`.
"""
from __future__ import annotations

import os
import statistics
import tempfile
import time
from pathlib import Path

from hub.campaign.cluster import Cluster
from hub.campaign.plan import load_campaign
from hub.campaign.runner import run_campaign
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT

CASES = 16
SECONDS = 60
WORKERS = 2
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


def one_after_another(cases, folder: Path) -> list[float]:
    """Each case's wall time, run in this process one after another (files written, as a case's are)."""
    walls = []
    for case in cases:
        scenario = load_scenario(case.scenario, case.overrides())
        began = time.perf_counter()
        run = Run(scenario, out=folder / case.folder)
        with run:
            result = run.run()
            run.close(result.stopped_by or "the run reached its end")
        walls.append(time.perf_counter() - began)
    return walls


def campaign() -> None:
    with tempfile.TemporaryDirectory(prefix="planthub-bench-campaign-") as scratch:
        folder = Path(scratch)
        (folder / "campaign.yaml").write_text(FILE)
        plan = load_campaign(folder / "campaign.yaml")
        load = os.getloadavg()[0]
        sequential = one_after_another(plan.cases, folder / "sequential")
        began = time.perf_counter()
        with Cluster(None, WORKERS) as cluster:
            started = time.perf_counter() - began
            outcome = run_campaign(plan, folder / "campaign", cluster, progress=lambda line: None)
        wall = time.perf_counter() - began
        load_after = os.getloadavg()[0]
    children = [r["wall_seconds"] for r in outcome.records]
    verdicts = {v: n for v, n in outcome.counts.items()}
    total = sum(sequential)
    overhead = (outcome.wall_seconds * WORKERS - sum(children)) / CASES
    child_start = statistics.median(c - s for c, s in zip(children, sequential))
    print(f"\n## Campaigns: {CASES} cases of the bottling plant's first {SECONDS} s, {WORKERS} workers against one "
          "after another\n")
    print("| figure | value |")
    print("|---|---:|")
    for name, value in (("cases", f"{CASES}"),
                        ("one after another, in one process (s)", f"{total:.1f}"),
                        (f"campaign on a LocalCluster of {WORKERS} workers, its start included (s)", f"{wall:.1f}"),
                        ("of it the cluster's start (s)", f"{started:.2f}"),
                        ("speed-up", f"{total / wall:.2f}×"),
                        ("overhead per case: scheduling, hand-over, result (s)", f"{overhead:.3f}"),
                        ("child process start per case, median (s)", f"{child_start:.3f}"),
                        ("a case's run in one process, median (s)", f"{statistics.median(sequential):.2f}"),
                        ("load average before, after (1 min)", f"{load:.1f}, {load_after:.1f}")):
        print(f"| {name} | {value} |")
    print(f"\nVerdicts of the campaign's cases: {verdicts} (the plant's expectations are set for its whole run "
          "with seed 0; here they only show that every case ran).")


if __name__ == "__main__":
    campaign()
