"""Flows, connectors and constants acting on the physics world inside the step loop."""
import csv

import pytest

from .helpers import ROOT, run_scenario


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_barrier_stops_the_belt_in_the_step_it_fires(tmp_path):
    """
        barrier.trigger.on_enter ──► stop.value.set ;  stop.value.out (false) ──► belt.drive.run
    """
    run_scenario(ROOT / "scenarios" / "stop_at_barrier.yaml", tmp_path)
    data = rows(tmp_path / "recording.csv")
    fired = [i for i, r in enumerate(data) if r["barrier.trigger.on_enter"] == "1"]
    assert len(fired) == 1
    # The stop is applied at the communication point where the event is sensed; the belt's own
    # source reports it from the next point on (sources are sensed before flows run).
    assert data[fired[0]]["belt.drive.running"] == "1"
    assert data[fired[0] + 1]["belt.drive.running"] == "0"
    # After the stop the field pulls the bottle to rest inside the beam's reach.
    final_x = float(data[-1]["bottle.body.position.x"])
    assert 1.0 - 0.03 - 0.0025 <= final_x <= 1.0 + 0.03 + 0.0025
    assert abs(float(data[-1]["bottle.body.position.x"]) - float(data[-10]["bottle.body.position.x"])) < 1e-6


SCENE = """
planthub: 1
run: {duration: 5.0, physics_rate: 150}   # B reaches the belt's end at 5.8 s
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 3.0, speed: 0.5}
  first: {module: bottle, position: [0.04, 0, 0], id: A}
  second: {module: bottle, position: [0.30, 0, 0], id: B}
  gate: {module: light_barrier, position: [1.5, 0, 0.05]}
  both: {module: connector, op: %s, negate: [%s, false]}
  tick: {module: constant, type: int, value: 1, always: true}
  once: {module: constant, type: int, value: 7, always: true}
  sink: {module: constant, type: int, value: 0}
flows:
  - {from: gate.trigger.on_enter, to: both.logic.in1}
  - {from: gate.trigger.on_stay, to: both.logic.in0}
  - {from: both.logic.out, to: sink.value.set}
record: [both.logic.out, gate.trigger.on_enter, gate.trigger.on_stay, gate.trigger.object]
"""


@pytest.mark.parametrize("op, negate, expected", [
    ("and", "false", lambda enter, stay: enter and stay),
    ("or", "false", lambda enter, stay: enter or stay),
    ("and", "true", lambda enter, stay: enter and not stay),
    ("or", "true", lambda enter, stay: enter or not stay),
])
def test_connector_output_in_the_loop(write_scenario, tmp_path, op, negate, expected):
    path = write_scenario(SCENE % (op, negate))
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert any(r["gate.trigger.on_enter"] == "1" for r in data)
    for r in data:
        want = expected(r["gate.trigger.on_enter"] == "1", r["gate.trigger.on_stay"] == "1")
        assert (r["both.logic.out"] == "1") == want, r


def test_id_of_each_bottle_is_read_in_order(write_scenario, tmp_path):
    path = write_scenario(SCENE % ("or", "false"))
    run_scenario(path, tmp_path / "out")
    events = rows(tmp_path / "out" / "events.csv")
    assert any(e["slot"] == "both.logic.out" for e in events)   # connector output is logged too
    seen = [(e["slot"], e["detail"]) for e in events if e["slot"].startswith("gate.")]
    # B stands downstream of A, so it is read first.
    assert seen == [
        ("gate.trigger.on_enter", "B"), ("gate.trigger.on_leave", "B"),
        ("gate.trigger.on_enter", "A"), ("gate.trigger.on_leave", "A"),
    ]
    ticks = [int(e["tick"]) for e in events]
    assert ticks == sorted(ticks)
    data = rows(tmp_path / "out" / "recording.csv")
    assert [r["gate.trigger.object"] for r in data if r["gate.trigger.on_enter"] == "1"] == ["B", "A"]


@pytest.mark.parametrize("rearm, executions", [(", rearm: gate.trigger.on_leave", 2), ("", 1)])
def test_singular_flow_runs_once_per_arming(write_scenario, tmp_path, rearm, executions):
    """A singular flow from the barrier slows the belt: once, or once per bottle when re-armed."""
    path = write_scenario("""
        planthub: 1
        run: {duration: 8.0}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 3.0, speed: 0.5}
          first: {module: bottle, position: [0.04, 0, 0]}
          second: {module: bottle, position: [0.30, 0, 0]}
          gate: {module: light_barrier, position: [1.5, 0, 0.05]}
          slow: {module: constant, type: real, value: 0.25}
        flows:
          - {from: gate.trigger.on_enter, to: slow.value.set, mode: singular%s}
          - {from: slow.value.out, to: belt.drive.speed}
        record: [gate.trigger.on_enter, slow.value.set, belt.drive.velocity]
        """ % rearm)
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    entered = [i for i, r in enumerate(data) if r["gate.trigger.on_enter"] == "1"]
    executed = [i for i, r in enumerate(data) if r["slow.value.set"] == "1"]
    assert len(entered) == 2
    assert executed == entered[:executions]
    assert float(data[entered[0]]["belt.drive.velocity"]) == 0.5
    assert float(data[entered[0] + 1]["belt.drive.velocity"]) == 0.25
