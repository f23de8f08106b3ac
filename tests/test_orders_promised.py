"""`run.orders` is a promise: a run that reaches its duration before its orders fails under
`planthub test` and says so in its summary; one that delivers them passes that line."""
from __future__ import annotations

import json
import subprocess
import sys

from .helpers import ROOT

SCENE = ROOT / "scenarios" / "source_sink.yaml"


def planthub_test(tmp_path, *sets):
    args = [a for s in sets for a in ("--set", s)]
    return subprocess.run([sys.executable, "-m", "hub", "test", str(SCENE), "--out", str(tmp_path / "out"), *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)


def test_orders_not_reached_by_the_duration_fail_the_test_and_are_said(tmp_path):
    proc = planthub_test(tmp_path, "run.orders=6", "run.duration=4.0", 'expect=[{jams: none}]')
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "✗ the run ends with its 6 orders out (run.orders) — the run ended at t = 4 s with" in proc.stdout
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["orders"] == {"wanted": 6, "out": 1, "rejected": 0, "met": False}
    run = subprocess.run([sys.executable, "-m", "hub", "run", str(SCENE), "--out", str(tmp_path / "run"),
                          "--set", "run.orders=6", "--set", "run.duration=4.0"],
                         capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert "  orders       1 of 6 out: the run ended before its orders (run.orders)" in run.stdout


def test_orders_delivered_pass(tmp_path):
    proc = planthub_test(tmp_path, "run.orders=6", 'expect=[{jams: none}]')
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "✓ the run ends with its 6 orders out (run.orders) — 6 out" in proc.stdout
