"""Operator commands replayed from a commands.csv: `release` gives a forced slot back what the plant
would have without the force — on a belt's run target and on a sensor's source."""
from __future__ import annotations

import csv

from .helpers import ROOT, run_scenario

STOP_AT_BARRIER = ROOT / "scenarios" / "stop_at_barrier.yaml"


def replay(tmp_path, rows, record, **settings):
    """Run stop_at_barrier with these commands (tick, op, slot, value) applied; its recording as dicts."""
    folder = tmp_path / "commanded"
    folder.mkdir()
    (folder / "events.csv").write_text("time,tick,slot,detail\n")
    with open(folder / "commands.csv", "w", newline="") as handle:
        out = csv.writer(handle, lineterminator="\n")
        out.writerow(["time", "tick", "op", "slot", "value", "by"])
        for tick, op, slot, value in rows:
            out.writerow([tick / 150, tick, op, slot, value, "test"])
    out_dir = tmp_path / "out"
    run_scenario(STOP_AT_BARRIER, out_dir, {"record": record, **settings}, replay=folder)
    with open(out_dir / "recording.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def at(rows, seconds):
    return next(r for r in rows if abs(float(r["time"]) - seconds) < 1e-9)


def test_a_belt_forced_to_stop_runs_again_when_released(tmp_path):
    """No flow writes belt.drive.run before the barrier: released, it has its own value again (true)."""
    rows = replay(tmp_path, [(75, "force", "belt.drive.run", "false"), (150, "release", "belt.drive.run", "")],
                  ["belt.drive.running", "bottle.body.position"])
    assert at(rows, 0.4)["belt.drive.running"] == "1"
    assert at(rows, 0.8)["belt.drive.running"] == "0"     # forced: the belt stands
    assert at(rows, 1.2)["belt.drive.running"] == "1"     # released: it runs again
    assert rows[-1]["belt.drive.running"] == "0"          # and the barrier still stops it


def test_a_released_target_takes_what_its_flows_wrote_while_it_was_forced(tmp_path):
    """Forced to run through the barrier's stop, then released: the flow's false (written while
    forced) is the belt's value again."""
    # 4.1 s: run on past the barrier, the bottle would fall off the belt's end at 4.37 s (a violation)
    rows = replay(tmp_path, [(30, "force", "belt.drive.run", "true"), (600, "release", "belt.drive.run", "")],
                  ["belt.drive.running", "barrier.trigger.on_enter"], **{"run.duration": 4.1})
    entered = next(float(r["time"]) for r in rows if r["barrier.trigger.on_enter"] == "1")
    assert entered < 4.0 and at(rows, 3.98)["belt.drive.running"] == "1"   # forced on past the barrier
    assert at(rows, 4.02)["belt.drive.running"] == "0"                     # released: the flow's stop


def test_a_sensor_forced_occupied_reports_the_world_again_when_released(tmp_path):
    rows = replay(tmp_path, [(30, "force", "barrier.trigger.occupied", "true"),
                             (60, "release", "barrier.trigger.occupied", "")], ["barrier.trigger.occupied"])
    assert at(rows, 0.3)["barrier.trigger.occupied"] == "1"
    assert at(rows, 0.5)["barrier.trigger.occupied"] == "0"   # no bottle there yet: the world says so
