"""Separator and stopper: one bottle per cycle, gates that wait for the way to clear, the interlock."""
import csv

from .helpers import ROOT
from .plant_watch import run_watched


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


QUEUED = [f"b{n}" for n in range(1, 9)]


def test_one_bottle_per_separator_cycle(tmp_path):
    """scenarios/separator.yaml at 150 Hz: eight bottles queued and pressed by the belt, eight
    cycles, one bottle each, in queue order, none tipped, none through a closed gate."""
    scenario, _, watch = run_watched(ROOT / "scenarios" / "separator.yaml", tmp_path)
    assert scenario.run.physics_rate == 150
    watch.assert_sound()
    events = rows(tmp_path / "events.csv")
    cycles = [int(e["tick"]) for e in events if e["slot"] == "work.clock.fire"] + [10 ** 9]
    passed = [(int(e["tick"]), e["detail"]) for e in events if e["slot"] == "out.trigger.on_enter"]
    assert [who for _, who in passed] == QUEUED
    for (start, end), (tick, _) in zip(zip(cycles, cycles[1:]), passed):
        assert start < tick < end
    # The interlock: WP is closed before BP opens, BP closed before WP opens, in every cycle.
    order = [e["slot"] for e in events if e["slot"].startswith("sep.")]
    assert order == ["sep.wp.on_closed", "sep.bp.on_opened", "sep.bp.on_closed", "sep.wp.on_opened"] * (len(cycles) - 1)
    assert rows(tmp_path / "recording.csv")[-1]["sink.count.total"] == str(len(QUEUED))


def test_a_pressed_queue_stands_upright_and_barely_gives_at_150_hz(write_scenario, tmp_path):
    """Twelve bottles pressed against a closed stopper by a running belt, at the paper's 150 Hz:
    the first stands at the gate, each bottle touches the next, none sinks or tips."""
    bottles = "\n".join(f"  q{n}: {{module: bottle, position: [{0.9675 - 0.0605 * n:.4f}, 0, 0]}}" for n in range(12))
    path = write_scenario(f"""
planthub: 1
run: {{duration: 4.0, physics_rate: 150}}
objects:
  belt: {{module: conveyor, position: [0, 0, 0], length: 1.2, speed: 0.5, width: 0.07, friction: 0.2}}
  stop: {{module: stopper, position: [1.0, 0, 0], width: 0.07}}
{bottles}
record: [{", ".join(f"q{n}.body.position" for n in range(12))}]
""")
    _, _, watch = run_watched(path, tmp_path)
    watch.assert_sound()
    assert watch.max_tilt < 2.0
    assert watch.lowest > -0.001
    last = rows(tmp_path / "recording.csv")[-1]
    x = [float(last[f"q{n}.body.position.x"]) for n in range(12)]
    y = [float(last[f"q{n}.body.position.y"]) for n in range(12)]
    assert abs(x[0] + 0.03 - 0.9975) < 0.001                      # at the gate's face, not in it
    gaps = [((x[n] - x[n + 1]) ** 2 + (y[n] - y[n + 1]) ** 2) ** 0.5 - 0.06 for n in range(11)]
    assert all(-0.001 < gap < 0.001 for gap in gaps), gaps         # touching, < 1 mm into each other


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
