"""Helpers for tests: run a scenario file end to end."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

ROOT = Path(__file__).resolve().parent.parent


def run_scenario(path, out: Path | None = None, overrides: dict | None = None, **options):
    """Load, build and run a scenario (`options`: those of hub.run.assembly.Run, e.g. `replay`);
    return (scenario, recorder, result)."""
    scenario = load_scenario(path, overrides)
    with Run(scenario, out=out, **options) as run:
        result = run.run()
    return scenario, run.recorder, result


def planthub_run(scenario, out: Path, *sets: str):
    """`planthub run SCENARIO --out OUT --set …` in a process of its own; (stdout, summary.json)."""
    args = [a for s in sets for a in ("--set", s)]
    proc = subprocess.run([sys.executable, "-m", "hub", "run", str(scenario), "--out", str(out), *args],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout, json.loads((out / "summary.json").read_text())


def planthub(capsys, *argv) -> tuple[int, str, str]:
    """`planthub ARGV` in this process: (exit code, stdout, stderr); argparse's usage errors too."""
    from hub.cli.main import main

    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:   # argparse's own usage errors
        code = exc.code
    captured = capsys.readouterr()
    return code, captured.out, captured.err
