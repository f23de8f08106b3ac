"""An operator's hold: pause, single steps, resume and pace over the command path (hub/run/hold.py),
recorded in commands.csv, without changing what the run computes (its recording and its replay are
the same bytes as a run nobody held)."""
from __future__ import annotations

import csv
import threading
import time

import pytest

from hub.bus.session import Bus, wait_until
from hub.bus.settings import BusSettings
from hub.live import Viewer
from hub.run.pacing import Pacer

from .bus_support import hub, same_files
from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "stop_at_barrier.yaml"
RUN = "stop_at_barrier"


@pytest.fixture
def bus():
    with Bus(BusSettings()) as bus:
        yield bus


def running(run):
    thread = threading.Thread(target=run.run, daemon=True)
    thread.start()
    return thread


def test_pause_steps_and_resume_give_the_recording_of_a_run_nobody_held(bus, tmp_path):
    with hub(SCENARIO, tmp_path / "plain") as plain:
        plain.run()
    substeps = None
    with hub(SCENARIO, tmp_path / "held", bus=bus) as run, Viewer(RUN, bus.endpoints) as operator:
        run.start()
        substeps = run.scenario.run.substeps
        pause = operator.command("pause", by="trainer", wait=None)   # taken at the first point
        thread = running(run)
        assert operator.answer(pause, 10)["ok"]
        assert operator.wait_state("paused")["reason"].startswith("paused by an operator at t = ")
        held = run.tick
        time.sleep(0.5)
        assert run.tick == held, "a paused run does not advance"
        answer = operator.command("step", value=3)
        assert answer["ok"], answer
        assert wait_until(lambda: run.tick == held + 3 * substeps, 10), (run.tick, held)
        time.sleep(0.3)
        assert run.tick == held + 3 * substeps, "after its steps the run holds again"
        refused = operator.command("pace", value=2.0)
        assert not refused["ok"] and "not paced" in refused["error"] and "--realtime" in refused["error"]
        assert operator.command("resume")["ok"]
        operator.wait_state("running")
        thread.join(60)
        assert not thread.is_alive()
    assert same_files(tmp_path / "plain", tmp_path / "held"), "recording.csv and events.csv: what the plant did"
    with open(tmp_path / "held" / "bus_log.csv", newline="") as f:
        control = [(r["tick"], r["detail"]) for r in csv.DictReader(f)]
    assert [d for _, d in control] == ["pause by trainer (the run's control)", "step 3 (the run's control)",
                                       "resume (the run's control)"]
    assert [int(t) for t, _ in control][1:] == [held, held + 3 * substeps], "taken at the point the run was held at"
    with open(tmp_path / "held" / "commands.csv", newline="") as f:
        recorded = [(r["op"], r["value"], r["by"]) for r in csv.DictReader(f)]
    assert recorded == [("pause", "", "trainer"), ("step", "3", ""), ("resume", "", "")]
    # A replay records the hold and runs through it: the same files again.
    with hub(SCENARIO, tmp_path / "replayed", replay=tmp_path / "held") as replayed:
        replayed.run()
    assert same_files(tmp_path / "held", tmp_path / "replayed", names=("recording.csv", "events.csv", "commands.csv"))


def test_step_needs_a_pause_and_stop_ends_a_held_run(bus, tmp_path):
    # Paced at real time: unpaced, its 5 s may be over before the pause arrives (the hub runs it
    # at well over 50× real time).
    pacer = Pacer(150, factor=1.0)
    with hub(SCENARIO, tmp_path / "run", bus=bus, pacer=pacer) as run, Viewer(RUN, bus.endpoints) as operator:
        run.start()
        answer = operator.command("step", value=1, wait=None)
        thread = running(run)
        result = operator.answer(answer, 10)
        assert not result["ok"] and result["error"] == "step: the run is not paused (pause it first)"
        bad = operator.command("step", value=0)
        assert not bad["ok"] and "step takes a number of points from 1 to 100000, got 0" in bad["error"]
        assert operator.command("pause")["ok"]
        assert wait_until(lambda: run.master.hold.paused, 5)
        held = run.tick
        assert operator.command("stop")["ok"]
        thread.join(10)
        assert not thread.is_alive(), "a stop ends a held run"
        assert run.stopped_by.startswith("stopped by an operator")
        assert run.tick == held + run.scenario.run.substeps, "at the next point, where it is recorded"
    with open(tmp_path / "run" / "commands.csv", newline="") as f:
        assert [(r["op"], int(r["tick"])) for r in csv.DictReader(f)] == [("pause", held), ("stop", run.tick)]
    # Its replay ends where it ended, with the same files.
    with hub(SCENARIO, tmp_path / "replayed", replay=tmp_path / "run") as replayed:
        replayed.run()
    assert same_files(tmp_path / "run", tmp_path / "replayed")


def test_pace_changes_a_paced_run(bus, tmp_path):
    pacer = Pacer(150, factor=1.0)
    with hub(SCENARIO, tmp_path / "run", bus=bus, pacer=pacer) as run, Viewer(RUN, bus.endpoints) as operator:
        run.start()
        thread = running(run)
        answer = operator.command("pace", value=50.0)
        assert answer["ok"], answer
        # The answer goes out when the command is taken at a point; the pace is set right after.
        assert wait_until(lambda: pacer.factor == 50.0, 5)
        bad = operator.command("pace", value=-1)
        assert not bad["ok"] and "pace takes a factor of real time above 0 and at most 1000" in bad["error"]
        thread.join(60)
        assert not thread.is_alive(), "at 50× real time the 6 s run ends in well under a minute"
