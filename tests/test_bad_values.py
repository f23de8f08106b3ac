"""A non-finite value from logic never reaches the plant: FMU outputs (in the hub and isolated) and
participant outputs (in-process and over the bus) stop the run naming slot, tick and time, or, with
`on_bad_value: hold`, keep the last good value and say so each time."""
from __future__ import annotations

import csv
import json
import math
import subprocess
import sys

import pytest

from .fmus.fmu_support import build
from .helpers import ROOT

PARTICIPANT = ROOT / "scenarios" / "belt_ramp_participant.yaml"
LAUNCHED = "command: [python, -m, modules.belt_drive_logic]"


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """The test-only `faulty` model (tests/fmu_models/faulty): its `level` turns NaN at step `nan_at`."""
    return build(tmp_path_factory.mktemp("faulty"), models_dir=ROOT / "tests" / "fmu_models")


def planthub(*args):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=120)


def nan_fmu_scene(tmp_path, fmu, extra=""):
    path = tmp_path / "scene.yaml"
    path.write_text(f"""planthub: 1
run: {{duration: 1.0, physics_rate: 100, communication_step: 0.1}}
objects:
  counter: {{module: fmu, file: {fmu}, parameters: {{nan_at: 4}}{extra}}}
record: [counter.logic.level, counter.logic.steps]
""")
    return path


@pytest.mark.parametrize("isolate", [False, True])
def test_a_nan_from_an_fmu_stops_the_run_naming_slot_and_time(faulty, tmp_path, isolate):
    path = nan_fmu_scene(tmp_path, faulty / "faulty-fmi2.fmu", ", runs: child" if isolate else "")
    proc = planthub("run", path, "--out", tmp_path / "out")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert ("counter.logic.level: the logic 'counter' gave nan at t = 0.4 s (tick 40); every value entering "
            "the plant must be finite, so the run stops here") in proc.stderr
    assert "Traceback" not in proc.stderr
    with open(tmp_path / "out" / "recording.csv", newline="") as handle:
        levels = [float(row["counter.logic.level"]) for row in csv.DictReader(handle)]
    assert len(levels) == 4 and all(math.isfinite(v) for v in levels)   # nothing non-finite recorded


def test_hold_keeps_the_last_good_value_and_says_so(faulty, tmp_path):
    path = nan_fmu_scene(tmp_path, faulty / "faulty-fmi3.fmu", ", on_bad_value: hold")
    proc = planthub("run", path, "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    with open(tmp_path / "out" / "recording.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["counter.logic.level"] for row in rows][3:] == ["0.30000000000000004"] * 8
    assert proc.stderr.count("holding the last good value 0.30000000000000004 (on_bad_value: hold)") == 7


@pytest.mark.parametrize("how", ["python: [tests.participants.belt_drives, nan]",
                                 "python: [tests.participants.belt_drives, nan]\n    runs: hub"])
def test_a_nan_from_a_participant_never_reaches_the_belt(tmp_path, how):
    path = tmp_path / "scene.yaml"
    path.write_text(PARTICIPANT.read_text().replace(LAUNCHED, f"{how}\n    cwd: {ROOT}"))
    proc = planthub("run", path, "--out", tmp_path / "out")
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "drive.logic.speed: the logic 'drive' gave nan at t = 0.52 s (tick 78)" in proc.stderr
    with open(tmp_path / "out" / "recording.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert rows and all(math.isfinite(float(row["bottle.body.position.x"])) for row in rows)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["simulated"]["ticks"] == 78   # the point where the NaN arrived
