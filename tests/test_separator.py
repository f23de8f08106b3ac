"""Separator and stopper: one bottle per cycle, gates that wait for the way to clear, the interlock."""
import csv

from .helpers import ROOT
from .plant_watch import run_watched


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_one_bottle_per_separator_cycle(tmp_path):
    """scenarios/separator.yaml: four queued bottles, four cycles, one bottle each, in queue order."""
    _, _, watch = run_watched(ROOT / "scenarios" / "separator.yaml", tmp_path)
    watch.assert_sound()
    events = rows(tmp_path / "events.csv")
    cycles = [int(e["tick"]) for e in events if e["slot"] == "work.clock.fire"] + [10 ** 9]
    passed = [(int(e["tick"]), e["detail"]) for e in events if e["slot"] == "out.trigger.on_enter"]
    assert [who for _, who in passed] == ["b1", "b2", "b3", "b4"]
    for (start, end), (tick, _) in zip(zip(cycles, cycles[1:]), passed):
        assert start < tick < end
    # The interlock: WP is closed before BP opens, BP closed before WP opens, in every cycle.
    order = [e["slot"] for e in events if e["slot"].startswith("sep.")]
    assert order == ["sep.wp.on_closed", "sep.bp.on_opened", "sep.bp.on_closed", "sep.wp.on_opened"] * 4


STOPPER = """
planthub: 1
run: {duration: 3.0, physics_rate: 150}
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2.0, speed: 0.5}
  a: {module: bottle, position: [0.30, 0, 0], id: A}
  b: {module: bottle, position: [0.60, 0, 0], id: B}
  stop: {module: stopper, position: [1.0, 0, 0], closed: false, thickness: 0.02}
  sink: {module: sink, position: [1.95, 0, 0.05]}
  go: {module: clock, at: [0.75]}
flows:
  - {from: go.clock.fire, to: stop.gate.close}
record: [stop.gate.blocked, stop.gate.is_closed, a.body.position, b.body.position]
"""


def test_a_gate_closes_only_once_the_bottle_in_it_has_passed(write_scenario, tmp_path):
    # The close is due at 0.85 s with B in the gate: the gate waits for it, then holds A.
    _, _, watch = run_watched(write_scenario(STOPPER), tmp_path)
    watch.assert_sound()
    data = rows(tmp_path / "recording.csv")
    blocked = [i for i, r in enumerate(data) if r["stop.gate.blocked"] == "1"]
    closed = [i for i, r in enumerate(data) if r["stop.gate.is_closed"] == "1"]
    assert blocked and closed and closed[0] > blocked[-1]
    assert float(data[-1]["a.body.position.x"]) < 1.0 - 0.01 - 0.03 + 0.006     # held at the gate
    assert [e["detail"] for e in rows(tmp_path / "events.csv") if e["slot"] == "sink.bin.taken"] == ["B"]
