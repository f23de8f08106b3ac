"""What a campaign leaves: DIR/campaign.json, DIR/cases.csv (a row per case: parameters, verdict, figures), one JUnit file, and the printed table."""
from __future__ import annotations

import csv
import json
import socket
from datetime import datetime
from pathlib import Path

from hub.campaign.case import NOT_RUN, PASSED
from hub.campaign.runner import Outcome
from hub.core.files import written
from hub.run.junit import TestCase, write_suite

#: Fields that differ between equal campaigns (where and how fast a case ran); everything else is
#: the same for the same campaign file, whatever the number of workers.
VARYING = ("wall_seconds", "host")


def write_results(outcome: Outcome, junit: Path | None, started: datetime) -> None:
    out = outcome.out
    out.mkdir(parents=True, exist_ok=True)
    data = {"campaign": outcome.campaign.name, "file": str(outcome.campaign.path),
            "started": started.isoformat(timespec="seconds"), "cluster": outcome.cluster, "ended": outcome.ended,
            "passed": outcome.passed, "interrupted": outcome.interrupted, "broken": outcome.broken,
            "wall_seconds": outcome.wall_seconds, "counts": outcome.counts, "cases": outcome.records}
    with written(out / "campaign.json", encoding="utf-8") as file:
        file.write(json.dumps(data, indent=1, ensure_ascii=False) + "\n")
    _write_table(out / "cases.csv", outcome.records)
    if junit is not None:
        write_junit(junit, outcome, started)


def _write_table(path: Path, records: list[dict]) -> None:
    keys = list(dict.fromkeys(k for r in records for k in r["parameters"]))
    figures = list(dict.fromkeys(k for r in records for k in r["figures"]))
    with written(path, newline="", encoding="utf-8") as file:
        writer = csv.writer(file)
        writer.writerow(["case", "scenario", *keys, "verdict", "failed", "wall_s", *figures, "reason", "folder"])
        for r in records:
            failed = sum(o["result"] in ("failure", "error") for o in r["outcomes"])
            writer.writerow([r["index"], r["name"], *(json.dumps(r["parameters"][k]) if k in r["parameters"] else ""
                                                       for k in keys),
                             r["verdict"], failed, r["wall_seconds"] if r["wall_seconds"] is not None else "",
                             *(r["figures"].get(k, "") for k in figures), r["reason"].splitlines()[0] if r["reason"] else "",
                             r["folder"]])


def table(outcome: Outcome) -> list[str]:
    """The printed summary: a line per case, then the tally and how the campaign ended."""
    lines = [f"planthub campaign {outcome.campaign.name}  ({outcome.campaign.path}; {outcome.cluster})"]
    width = max((len(r["label"]) for r in outcome.records), default=0)
    for r in outcome.records:
        wall = f"{r['wall_seconds']:7.1f} s" if r["wall_seconds"] is not None else " " * 9
        reason = f"  {r['reason'].splitlines()[0]}" if r["verdict"] != PASSED and r["reason"] else ""
        lines.append(f"  {r['index']:>3} {r['label']:<{width}}  {r['verdict']:<8}{wall}{reason}")
    counts = ", ".join(f"{n} {verdict}" for verdict, n in sorted(outcome.counts.items()))
    lines.append(f"{len(outcome.records)} cases: {counts or 'none'}; {outcome.ended}; "
                 f"{outcome.wall_seconds:.1f} s wall")
    lines.append(f"  results      {outcome.out / 'campaign.json'}, {outcome.out / 'cases.csv'}")
    return lines


def write_junit(path: Path, outcome: Outcome, started: datetime) -> None:
    """One <testsuite> for the campaign: a <testcase> per case and expectation, named
    `expectation [case label]`; a case without expectations, or whose run failed before any could
    be judged, or that was not run, is one case `the run [label]`. A campaign that went wrong itself
    (interrupted, never started, left without workers) adds a failed case `the campaign`."""
    suite_name = f"campaign {outcome.campaign.name}"
    cases = []
    for r in outcome.records:
        judged = [o for o in r["outcomes"] if o["name"] != "the run"]
        for o in judged:
            cases.append((r["name"], f"{o['name']} [{r['label']}]", o["result"], o["message"], r))
        if r["verdict"] == NOT_RUN:
            cases.append((r["name"], f"the run [{r['label']}]", "skipped", r["reason"], r))
        elif r["verdict"] != PASSED and not any(o["result"] in ("failure", "error") for o in judged):
            cases.append((r["name"], f"the run [{r['label']}]", "error", r["reason"], r))
        elif not judged:
            cases.append((r["name"], f"the run [{r['label']}]", "passed", "", r))
    if outcome.broken is not None:
        cases.append(("campaign", "the campaign", "failure", outcome.ended, None))
    suite = [TestCase(classname, name, result, message.splitlines()[0] if message else "",
                      message if result != "passed" else None,
                      r["wall_seconds"] / sum(c[4] is r for c in cases) if r and r["wall_seconds"] is not None else None,
                      f"run folder: {outcome.out / r['folder']}" if r and r["folder"] else None)
             for classname, name, result, message, r in cases]
    write_suite(path, suite_name, suite, outcome.wall_seconds, timestamp=started, hostname=socket.gethostname(),
                properties=[("file", str(outcome.campaign.path)), ("cluster", outcome.cluster),
                            ("ended", outcome.ended)])
