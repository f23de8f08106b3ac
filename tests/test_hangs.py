"""No wait without a limit: an FMU whose step never returns stops the run naming it — its worker
killed when it runs isolated, the hub's process ended by the watchdog when it runs in the hub —
with the recording complete and summary.json saying why; and children never outlive the hub."""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from .fmus.fmu_support import build
from .helpers import ROOT


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """The test-only `faulty` model: its step at `hang_at` never returns."""
    return build(tmp_path_factory.mktemp("faulty"), models_dir=ROOT / "tests" / "fmu_models")


def scene(tmp_path, fmu, extra):
    path = tmp_path / "scene.yaml"
    path.write_text(f"""planthub: 1
run: {{duration: 2.0, physics_rate: 100, communication_step: 0.1}}
objects:
  counter: {{module: fmu, file: {fmu}, parameters: {{hang_at: 4}}, step_timeout: 1.5{extra}}}
record: [counter.logic.steps]
""")
    return path


def rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.mark.parametrize("isolate", [True, False])
def test_a_hanging_fmu_stops_the_run_naming_it_with_its_files_complete(faulty, tmp_path, isolate):
    path = scene(tmp_path, faulty / "faulty-fmi2.fmu", ", isolate: true" if isolate else "")
    out = tmp_path / "out"
    started = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "hub", "run", str(path), "--out", str(out)],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 1, proc.stderr
    assert time.monotonic() - started < 30
    if isolate:
        assert ("FMU instance 'counter' (faulty-fmi2.fmu) at t = 0.3 s: its step did not return within 1.5 s "
                "(step_timeout), so its worker process was killed") in proc.stderr
    else:
        assert ("FMU instance 'counter' (faulty-fmi2.fmu) at t = 0.3 s: its step has not returned for") in proc.stderr
        assert "an FMU in the hub's process cannot be interrupted, so planthub ends here" in proc.stderr
    recorded = rows(out / "recording.csv")
    assert [r["counter.logic.steps"] for r in recorded] == ["0", "1", "2", "3"]
    assert (out / "events.csv").read_text().startswith("time,tick,slot,detail")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulated"]["ticks"] == 30


def test_a_launched_participant_dies_with_a_hub_killed_by_sigkill(tmp_path):
    """kill -9 of the hub: the kernel ends the participant it launched (no orphan 2 s later)."""
    scene_path = tmp_path / "long.yaml"
    scene_path.write_text((ROOT / "scenarios" / "belt_ramp_participant.yaml").read_text()
                          .replace("duration: 6.0", "duration: 600.0"))
    hub = subprocess.Popen([sys.executable, "-m", "hub", "run", str(scene_path), "--out", str(tmp_path / "out"),
                            "--realtime", "1"], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        child = None
        deadline = time.monotonic() + 30
        while child is None and time.monotonic() < deadline:
            time.sleep(0.2)
            found = subprocess.run(["pgrep", "-P", str(hub.pid)], capture_output=True, text=True).stdout.split()
            child = int(found[0]) if found else None
        assert child is not None, "the hub launched no participant"
        time.sleep(1.0)   # the participant is in its steps
        os.kill(hub.pid, signal.SIGKILL)
        hub.wait(10)
        time.sleep(2.0)
        alive = subprocess.run(["ps", "-o", "stat=", "-p", str(child)], capture_output=True, text=True).stdout.strip()
        assert alive in ("", "Z"), f"participant {child} outlived the hub ({alive})"
        # Its files were flushed at most 0.5 s of wall time before the kill: readable, header first.
        recorded = rows(tmp_path / "out" / "recording.csv")
        assert recorded and float(recorded[-1]["time"]) > 0.0
        assert (tmp_path / "out" / "events.csv").read_text().startswith("time,tick,slot,detail\n")
    finally:
        if hub.poll() is None:
            hub.kill()
            hub.wait(10)
