"""The body recording (hub/view/bodies_file.py): every body's pose per point in bodies.arrows, beside
scene.json, equal to what the run recorded in CSV, the same bytes for the same run, readable after
a kill -9 up to its last batch, and clear errors for what is not one."""
from __future__ import annotations

import csv
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from hub.core.errors import PlanthubError
from hub.view.bodies_file import NAME, BodyRecording

from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"


def planthub(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, **kwargs)


def test_the_body_recording_holds_every_released_bottle_as_the_csv_does(tmp_path):
    out = tmp_path / "run"
    done = planthub("run", SCENARIO, "--record-bodies", "--out", out, "--set",
                    "record=[P1.body.position, P1.body.present]")
    assert done.returncode == 0, done.stderr
    recording = BodyRecording(out)
    with open(out / "recording.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert len(recording) == len(table), "one point of the body recording per communication point"
    import json
    scene = json.loads((out / "scene.json").read_text())
    p1 = next(b["row"] for b in scene["bodies"] if b["id"] == "P1")
    rate = scene["physics_rate"]
    compared, changes = 0, []
    for i, row in enumerate(table):
        m = recording.message(i, rate)
        assert m["tick"] == round(float(row["time"]) * rate)
        rows = np.frombuffer(m["rows"], "<u2").tolist()
        if (p1 in rows) != (row["P1.body.present"] == "1"):
            # The recording shows the world after the point (the source released P1 at it), the
            # slot what was sensed at its start: they differ at the point of a release or take-out.
            changes.append(i)
            assert table[i + 1]["P1.body.present"] == ("1" if p1 in rows else "0")
        elif p1 in rows:
            pose = np.frombuffer(m["poses"], "<f4").reshape(-1, 7)[rows.index(p1)]
            csv_position = [float(row[f"P1.body.position.{c}"]) for c in "xyz"]
            assert np.allclose(pose[:3], csv_position, atol=1e-6), (i, pose, csv_position)
            compared += 1
    assert compared > 100 and len(changes) <= 2
    # The same run again: the same bytes.
    again = tmp_path / "again"
    assert planthub("run", SCENARIO, "--record-bodies", "--out", again, "--set",
                    "record=[P1.body.position, P1.body.present]").returncode == 0
    assert (again / NAME).read_bytes() == (out / NAME).read_bytes()


def test_a_body_recording_cut_by_kill_9_is_readable_up_to_its_last_batch(tmp_path):
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "hub", "run", str(ROOT / "scenarios" / "bottling_plant.yaml"),
                             "--record-bodies", "--out", str(out), "-q"], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not ((out / NAME).is_file() and (out / NAME).stat().st_size > 200_000):
            time.sleep(0.2)
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    recording = BodyRecording(out)
    assert len(recording) > 10
    assert list(recording.ticks) == sorted(recording.ticks)


def test_what_is_no_body_recording_is_named(tmp_path):
    with pytest.raises(PlanthubError) as caught:
        BodyRecording(tmp_path)
    assert str(caught.value) == (f"{tmp_path}: no body recording (bodies.arrows); record one with "
                                 "`planthub run --record-bodies` or `run.record_bodies: true`")
    (tmp_path / NAME).write_bytes(b"not arrow at all")
    with pytest.raises(PlanthubError) as caught:
        BodyRecording(tmp_path)
    assert str(caught.value).startswith(f"{tmp_path / NAME}: not an Arrow stream")
