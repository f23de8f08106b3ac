"""Source and sink: seeded bottles released at a rate or on command, counted by destination."""
import csv

import pytest

from hub.run.plant import Plant
from hub.scenario.checker import load_scenario
from modules.source import Source

from .helpers import ROOT
from .plant_watch import run_watched

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_every_bottle_made_is_counted_by_destination(tmp_path):
    scenario, _, watch = run_watched(SCENARIO, tmp_path)
    watch.assert_sound()
    made = Source.bottles("source", scenario.objects[1].params, scenario.run.seed)
    assert len(made) == 6
    taken = [e["detail"] for e in rows(tmp_path / "events.csv") if e["slot"] == "sink.bin.taken"]
    assert taken == [ident for ident, _ in made]
    last = rows(tmp_path / "recording.csv")[-1]
    assert last["source.store.remaining"] == "0"
    assert int(last["sink.count.total"]) == 6
    for dest in ("A", "B"):
        assert int(last[f"sink.count.{dest}"]) == sum(d == dest for _, d in made)


def test_destinations_follow_the_seed():
    params = load_scenario(SCENARIO).objects[1].params
    draws = {seed: [d for _, d in Source.bottles("source", params, seed)] for seed in range(6)}
    assert draws[3] == [d for _, d in Source.bottles("source", params, 3)]      # the same seed draws the same
    assert len({tuple(d) for d in draws.values()}) > 1                          # other seeds draw otherwise


def test_a_full_store_costs_no_reads_and_stays_off_stage():
    scenario = load_scenario(SCENARIO, {"objects.source.interval": 100.0})
    with Plant(scenario) as plant:
        world = plant.world
        world.step(150)
        assert world._live_rows is not None and len(world._live_rows) == 0
        assert (world.positions[:, 2] < -50).all()


SCENE = """
planthub: 1
run: {duration: 2.0, physics_rate: 150}
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2.0, speed: 0.5, running: false}
  source: {module: source, position: [0.5, 0, 0], count: 3}
  push: {module: clock, at: [0.1, 0.2, 1.5]}
  run: {module: constant, type: bool, value: true}
  start: {module: clock, at: [0.9]}
flows:
  - {from: push.clock.fire, to: source.store.release}
  - {from: start.clock.fire, to: run.value.set}
  - {from: run.value.out, to: belt.drive.run}
record: [source.store.waiting, source.store.remaining, source.store.released]
"""


def test_a_release_waits_while_the_spot_is_taken(write_scenario, tmp_path):
    # The belt stands still until 0.9 s: the second release waits for the first bottle to go.
    _, _, watch = run_watched(write_scenario(SCENE), tmp_path)
    watch.assert_sound()
    data = rows(tmp_path / "recording.csv")
    released = [float(r["time"]) for r in data if r["source.store.released"] == "1"]
    assert released[0] == pytest.approx(0.1 + 1 / 150)
    assert 0.9 < released[1] < 1.1 and released[2] == pytest.approx(1.5 + 1 / 150)
    assert any(r["source.store.waiting"] == "1" for r in data)
    assert data[-1]["source.store.remaining"] == "0"
