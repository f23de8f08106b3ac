"""Track switch: diverting in working position, passing in base position, waiting for a bottle on the blade."""
import csv

from .helpers import ROOT
from .plant_watch import run_watched


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_bottle_is_diverted_in_working_position_and_passes_in_base(tmp_path):
    """scenarios/switch.yaml: B ahead with the blade working, A behind with the blade back in base."""
    _, recorder, watch = run_watched(ROOT / "scenarios" / "switch.yaml", tmp_path)
    watch.assert_sound()
    taken = [(e["slot"], e["detail"]) for e in rows(tmp_path / "events.csv") if e["slot"].endswith("bin.taken")]
    assert taken == [("branch_end.bin.taken", "B"), ("main_end.bin.taken", "A")]
    data = rows(tmp_path / "recording.csv")
    assert max(abs(float(r["a.body.position.y"])) for r in data) < 0.01          # A ran straight on
    assert min(float(r["b.body.position.y"]) for r in data) < -0.9               # B went down the branch
    read = [r["reader.trigger.object"] for r in data if r["reader.trigger.object"]]
    assert read[0] == "B" and read[-1] == "A"


SCENE = """
planthub: 1
run: {duration: 4.0, physics_rate: 150}
objects:
  sw: {module: switch, position: [0, 0, 0], length: 2.0, branch_at: 1.0, branch_length: 1.0, side: left}
  a: {module: bottle, position: [0.50, 0, 0], id: A}
  main_end: {module: sink, position: [1.95, 0, 0.05]}
  branch_end: {module: sink, position: [1.0, 1.01, 0.05], yaw: 90}
  working: {module: constant, type: bool, value: true}
  go: {module: clock, at: [%s]}
flows:
  - {from: go.clock.fire, to: working.value.set}
  - {from: working.value.out, to: sw.blade.working}
record: [a.body.position, sw.blade.blocked, sw.blade.in_working, sw.blade.on_working]
"""


def test_the_blade_waits_for_a_bottle_on_it_and_never_launches_it(write_scenario, tmp_path):
    # A crosses the blade's path from ~0.9 s to ~1.1 s: the command at 0.95 s must wait.
    _, _, watch = run_watched(write_scenario(SCENE % 0.95), tmp_path)
    watch.assert_sound()
    data = rows(tmp_path / "recording.csv")
    blocked = [i for i, r in enumerate(data) if r["sw.blade.blocked"] == "1"]
    reached = [i for i, r in enumerate(data) if r["sw.blade.on_working"] == "1"]
    assert blocked and len(reached) == 1 and reached[0] > blocked[-1]
    # The bottle on the blade ran on along the main belt, untouched.
    events = rows(tmp_path / "events.csv")
    assert [e["slot"] for e in events if e["detail"] == "A"] == ["main_end.bin.taken"]


def test_a_left_switch_diverts_to_the_left(write_scenario, tmp_path):
    _, _, watch = run_watched(write_scenario(SCENE % 0.1), tmp_path)
    watch.assert_sound()
    assert [e["slot"] for e in rows(tmp_path / "events.csv") if e["detail"] == "A"] == ["branch_end.bin.taken"]
