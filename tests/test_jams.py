"""Jams in the run summary: a bottle stuck at a rail is one, bottles a closed stopper holds are not.

    jam.yaml:            source ──► [==== feed ====]● ║ cross      P1 stands at the cross belt's rail
    stopper_queue.yaml:  source ──► [== belt ==●●●|stop|====] ──► sink    held 4 s, then let go
"""
import subprocess
import sys

import pytest

from hub import Simulation
from modules.plant.jams import JamWatch

from .helpers import ROOT, planthub_run
from .test_scenario_errors import problems

JAM = ROOT / "scenarios" / "jam.yaml"
STOPPER = ROOT / "scenarios" / "stopper_queue.yaml"


def test_a_bottle_against_a_rail_on_a_running_belt_is_a_jam(tmp_path):
    stdout, summary = planthub_run(JAM, tmp_path)
    plant = summary["plant"]
    (jam,) = plant["jams"]
    # P1 leaves the source at 0.04 m and meets the rail at 0.975 m: about 1.9 s at 0.5 m/s.
    assert jam["bottle"] == "P1" and jam["belt"] == "feed" and jam["until"] is None
    assert 1.85 <= jam["since"] <= 2.05 and jam["seconds"] == pytest.approx(6.0 - jam["since"])
    assert plant["on_line"][0]["bottle"] == "P1" and plant["on_line"][0]["belt"] == "feed"
    assert plant["delivered"] == 0 and plant["misrouted"] == []
    lines = stdout.splitlines()
    assert "  jams         1  (standing still over 3 s on a running belt, not held at a closed gate)" in lines
    assert f"    P1 on feed since {jam['since']:.3f} s, still at the end ({jam['seconds']:.2f} s)" in lines


def test_a_jam_ends_when_its_belt_stops(write_scenario, tmp_path):
    # jam.yaml's layout; the feed stops at 4.5 s: a bottle on a stopped belt is not jammed.
    path = write_scenario("""
        planthub: 1
        run: {duration: 6.0, physics_rate: 150, jam_after: 1.5}
        objects:
          feed: {module: conveyor, position: [0, 0, 0], length: 1.0, speed: 0.5}
          cross: {module: conveyor, position: [1.065, -0.5, 0], yaw: 90, length: 1.0, speed: 0.5}
          source: {module: source, position: [0.04, 0, 0], bottles: [{id: P1, destination: A}], interval: 10}
          sink: {module: sink, position: [1.065, 0.45, 0.05], yaw: 90, accepts: [A]}
          stop_feed: {module: clock, at: [4.5]}
          halt: {module: constant, type: bool, value: false}
        flows:
          - {from: stop_feed.clock.fire, to: halt.value.set}
          - {from: halt.value.out, to: feed.drive.run}
        """)
    _, summary = planthub_run(path, tmp_path)
    (jam,) = summary["plant"]["jams"]
    assert jam["bottle"] == "P1" and 4.5 <= jam["until"] <= 4.6   # the first look after the stop
    assert jam["seconds"] == pytest.approx(jam["until"] - jam["since"])


def test_bottles_a_closed_stopper_holds_are_no_jam_however_long():
    with Simulation(STOPPER) as sim:
        # The same world watched without the stopper's hold: its queue would count as jammed.
        bare = JamWatch(sim.plant.world, sim.figures[0].belts, None, sim.scenario.run.jam_after)
        sim.run_until(lambda s: bare.observe(s.master.tick) and False, timeout=sim.scenario.run.end_tick / 300)
        plant = sim.summary().plant
    assert plant.jams == ()
    assert plant.delivered == 3 and plant.misrouted == () and plant.by_destination == {"A": 3}
    # Q1 against the gate, Q2 and Q3 queued behind it, from their arrival until the stopper opens at 6 s.
    assert [(j.bottle, j.belt) for j in bare.jams()] == [("Q1", "belt"), ("Q2", "belt"), ("Q3", "belt")]
    assert all(j.since < 3.0 and 6.0 < j.until < 6.3 for j in bare.jams())


def test_equal_runs_give_equal_summaries_and_the_api_agrees_with_the_cli(tmp_path):
    _, first = planthub_run(JAM, tmp_path / "a")
    _, second = planthub_run(JAM, tmp_path / "b")
    for summary in (first, second):
        del summary["wall"], summary["files"]
    assert first == second
    with Simulation(JAM) as sim:
        sim.run()
        assert sim.summary().plant.as_dict() == first["plant"]


def test_hub_test_fails_a_jam_expected_away_and_names_the_bottle(write_scenario, tmp_path):
    jam = write_scenario(JAM.read_text() + "\nexpect:\n  - {name: nothing jams, jams: none}\n")
    proc = subprocess.run([sys.executable, "-m", "hub", "test", str(jam), "--junit", str(tmp_path / "j.xml")],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 1, proc.stderr
    (line,) = [line for line in proc.stdout.splitlines() if "nothing jams" in line]
    assert line.startswith("  ✗ nothing jams — 1 jammed: P1 on feed from 1.9") and line.endswith(", still at 6 s")
    assert "expected no bottle jams at any time: 1 jammed: P1 on feed" in (tmp_path / "j.xml").read_text()
    held = write_scenario(STOPPER.read_text() + "\nexpect:\n  - {jams: none}\n", name="held.yaml")
    with Simulation(held) as sim:
        sim.run()
        (outcome,) = sim.check()
    assert outcome.passed and outcome.expectation.name == "no jam" and outcome.message == "held"


def test_a_jam_expectation_is_checked_as_written(write_scenario):
    path = write_scenario(JAM.read_text() + """
expect:
  - {jams: some}
  - {jams: none, slot: sink.count.total}
  - {name: alone}
""")
    lines = len(JAM.read_text().splitlines())
    assert problems(path)[0] == [
        f"{path}:{lines + 3}: expect[0].jams: 'none' was expected",
        f"{path}:{lines + 4}: expect[1]: `jams: none` stands alone (with a `name`), not with slot",
        f"{path}:{lines + 5}: expect[2]: give `slot` (a slot's value, with `is` or `always`) or `jams: none`",
    ]


def test_a_jam_expectation_needs_a_plant(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0}
          bottle: {module: bottle, position: [0.04, 0, 0]}
        expect:
          - {jams: none}
        """)
    assert problems(path)[0] == [
        f"{path}:6: expect[0].jams: jams are watched in a plant, a scenario with a source or a sink; this one has neither"]
