"""Pusher: the bottle it is told to push leaves the belt into the reject lane, the others pass, the stroke is
reported (busy, arrivals, a refused push), recordings repeat byte for byte, and bad parameters are named."""
import csv
import subprocess
import sys

import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario

from .helpers import ROOT, planthub_run, run_scenario
from .plant_watch import run_watched

SCENARIO = ROOT / "scenarios" / "pusher.yaml"
BELT_EDGE = 0.05 + 0.01   # m: the belt's half width and its rail, from the centre line


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_the_pushed_bottle_leaves_into_the_reject_lane_and_the_others_pass(tmp_path):
    """scenarios/pusher.yaml: the barrier's first bottle, B, is pushed; A and C behind it pass."""
    _, _, watch = run_watched(SCENARIO, tmp_path)
    watch.assert_sound()
    events = rows(tmp_path / "events.csv")
    taken = [(e["slot"], e["detail"]) for e in events if e["slot"].endswith("bin.taken")]
    assert taken == [("rejects.bin.taken", "B"), ("main_end.bin.taken", "A"), ("main_end.bin.taken", "C")]
    data = rows(tmp_path / "recording.csv")
    b_y = [float(r["b.body.position.y"]) for r in data if float(r["b.body.position.x"]) > -50]
    assert min(b_y) < -BELT_EDGE - 0.3                                 # B went down the lane
    a_y = [float(r["a.body.position.y"]) for r in data if float(r["a.body.position.x"]) > -50]
    assert max(abs(y) for y in a_y) < 0.001                            # A ran straight past the plate
    # busy: false, true from the point after the push, false again once the plate is back — once.
    busy = "".join(r["kicker.push.busy"] for r in data)
    assert busy.strip("0") == "1" * len(busy.strip("0")) and busy.count("01") == busy.count("10") == 1
    pushed = next(float(e["time"]) for e in events if e["slot"] == "barrier.trigger.on_enter")
    assert float(data[busy.index("1")]["time"]) == pytest.approx(pushed + 1 / 150, abs=1e-9)
    # The arrivals are logged at the tick the plate got there: 0.11 m out and back at 0.5 m/s.
    arrivals = {e["slot"]: int(e["tick"]) for e in events if e["slot"].startswith("kicker.push.on_")}
    start = round(pushed * 150)
    assert arrivals == {"kicker.push.on_extended": start + 33, "kicker.push.on_returned": start + 66}
    assert float(data[busy.rindex("1") + 1]["time"]) * 150 == pytest.approx(start + 66, abs=1e-6)


def test_the_recording_repeats_byte_for_byte_in_process_and_from_the_command_line(tmp_path):
    run_scenario(SCENARIO, tmp_path / "one")
    run_scenario(SCENARIO, tmp_path / "two")
    stdout, summary = planthub_run(SCENARIO, tmp_path / "cli")
    for file in ("recording.csv", "events.csv"):
        first = (tmp_path / "one" / file).read_bytes()
        assert first == (tmp_path / "two" / file).read_bytes() == (tmp_path / "cli" / file).read_bytes()
    # The summary counts the rejected bottle on a line of its own, not as delivered.
    plant = summary["plant"]
    assert plant["delivered"] == 2 and [r["bottle"] for r in plant["rejected"]] == ["B"]
    assert "  rejected     1" in stdout and "    B (for no destination) at rejects, " in stdout


REFUSED = """
planthub: 1
run: {duration: 1.5, physics_rate: 150}
objects:
  kicker: {module: pusher, position: [0, 0, 0], length: 1.0, at: 0.5, side: left, dwell: 0.1, return_speed: 0.25}
  go: {module: clock, at: [0.1, 0.2, 1.0]}
flows:
  - {from: go.clock.fire, to: kicker.push.push}
record: [kicker.push.busy, kicker.push.extended, kicker.push.refused]
"""


def test_a_push_during_a_stroke_is_refused_and_the_next_one_after_it_taken(write_scenario, tmp_path):
    # Out 0.11 m at 0.5 m/s (33 ticks), 0.1 s out (15), back at 0.25 m/s (66): from tick 15 to 129.
    run_scenario(write_scenario(REFUSED), tmp_path)
    events = [(e["slot"], int(e["tick"])) for e in rows(tmp_path / "events.csv") if e["slot"].startswith("kicker")]
    # Each logged with its own tick: the refusal at the point it came (reported at the next one).
    assert events == [("kicker.push.refused", 30), ("kicker.push.on_extended", 48),
                      ("kicker.push.on_returned", 129), ("kicker.push.on_extended", 183)]
    data = rows(tmp_path / "recording.csv")
    refused = [round(float(r["time"]) * 150) for r in data if r["kicker.push.refused"] == "1"]
    assert refused == [31]
    extended = [round(float(r["time"]) * 150) for r in data if r["kicker.push.extended"] == "1"]
    assert extended == list(range(48, 64)) + list(range(183, 199))   # out from arrival to the return's start


def test_bad_pusher_parameters_are_named_with_their_lines(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          k1: {module: pusher, position: [0, 0, 0], length: 1.0, at: 0.5, plate_length: 0.3, lane_width: 0.2}
          k2: {module: pusher, position: [0, 1, 0], length: 1.0, at: 0.05}
          k3: {module: pusher, position: [0, 2, 0], length: 1.0, at: 0.5, push_speed: 0}
        """)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    text = str(caught.value)
    for line in (
        ":3: objects.k1.plate_length: 0.3 m is longer than the lane's mouth (lane_width 0.2 m): a bottle pushed "
        "at the plate's ends would hit the lane's rails",
        ":4: objects.k2.at: 0.05 m puts the lane's mouth and its rails (0.22 m) past the belt's ends (length 1 m): "
        "give 0.11 to 0.89 m",
        ":5: objects.k3.push_speed:",
    ):
        assert line in text, f"missing: {line}\nin:\n{text}"


def test_describe_shows_the_pushers_slots():
    proc = subprocess.run([sys.executable, "-m", "hub", "describe", "pusher"], capture_output=True, text=True,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    for slot in ("push.push", "push.busy", "push.extended", "push.on_extended", "push.on_returned",
                 "push.refused", "main.speed", "lane.speed"):
        assert f"\n  {slot} " in proc.stdout
