"""Robot arm: storage to belt, the held bottle following the tool, release at the tool's velocity, determinism."""
import csv
import subprocess
import sys

import numpy as np

from .helpers import ROOT, run_scenario
from .plant_watch import run_watched

SCENARIO = ROOT / "scenarios" / "robot.yaml"


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_the_arm_moves_bottles_from_storage_to_belt(tmp_path):
    _, _, watch = run_watched(SCENARIO, tmp_path)
    watch.assert_sound()
    events = [(e["slot"], e["detail"]) for e in rows(tmp_path / "events.csv")]
    gripper = [ev for ev in events if ev[0] in ("robot.gripper.on_grip", "robot.gripper.on_release")]
    assert gripper == [("robot.gripper.on_grip", "S1"), ("robot.gripper.on_release", "S1"),
                       ("robot.gripper.on_grip", "S2"), ("robot.gripper.on_release", "S2")]
    assert [d for s, d in events if s == "sink.bin.taken"] == ["S1", "S2"]
    last = rows(tmp_path / "recording.csv")[-1]
    assert (last["sink.count.A"], last["sink.count.B"]) == ("1", "1")


def test_the_robot_scenario_is_bit_identical_in_every_run(tmp_path):
    run_scenario(SCENARIO, tmp_path / "one")
    run_scenario(SCENARIO, tmp_path / "two")
    subprocess.run([sys.executable, "-m", "hub", "run", str(SCENARIO), "--out", str(tmp_path / "three")],
                   check=True, capture_output=True, cwd=ROOT)
    for name in ("recording.csv", "events.csv"):
        first = (tmp_path / "one" / name).read_bytes()
        assert first == (tmp_path / "two" / name).read_bytes()
        assert first == (tmp_path / "three" / name).read_bytes()


SCENE = """
planthub: 1
run: {duration: %s, physics_rate: 150}
objects:
  shelf: {module: source, position: [0.6, 0.95, 0.0], platform: true, count: 1}
  bottle: {module: bottle, position: [0.6, 0.95, 0.0], id: held}
  robot: {module: robot_arm, position: [0.6, 0.45, 0.0], pick: [0.6, 0.95, 0.0], place: [0.6, 0.0, 0.2]}
  go: {module: clock, at: [0.1]}
  drop: {module: clock, at: [3.5]}
flows:
  - {from: go.clock.fire, to: robot.arm.pick}
  - {from: robot.arm.picked, to: robot.arm.carry}
  - {from: drop.clock.fire, to: robot.gripper.release}
record: [bottle.body.position, bottle.body.velocity, robot.gripper.position, robot.gripper.holding]
"""


def test_the_held_bottle_follows_the_tool_and_leaves_with_its_velocity(write_scenario, tmp_path):
    # The storage platform is the shelf's; the bottle on it is a plain `bottle` object, so its
    # body slots can be recorded. The gripper lets go in the middle of the carry move.
    run_scenario(write_scenario(SCENE % 3.6), tmp_path)
    data = rows(tmp_path / "recording.csv")
    vec = lambda r, s: np.array([float(r[f"{s}.{a}"]) for a in "xyz"])
    held = [i for i, r in enumerate(data) if r["robot.gripper.holding"] == "1"]
    assert held and data[held[-1] + 1]["robot.gripper.holding"] == "0"
    offsets = [vec(data[i], "bottle.body.position") - vec(data[i], "robot.gripper.position") for i in held[1:]]
    assert np.ptp(offsets, axis=0).max() < 1e-9          # rigidly at the tool while held
    # Released mid-move at point k = held[-1]: one tick later it moves horizontally at the tool's
    # velocity at k, here its central difference (gravity acts on the vertical only).
    k = held[-1]
    tool = (vec(data[k + 1], "robot.gripper.position") - vec(data[k - 1], "robot.gripper.position")) * 150 / 2
    assert np.linalg.norm(tool) > 0.3
    assert np.allclose(vec(data[k + 1], "bottle.body.velocity")[:2], tool[:2], atol=0.005)
