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


def test_a_released_bottle_is_addressable_by_its_id_and_gone_once_taken(tmp_path):
    """`P1.body.position` names the first bottle the source releases (Module.members): recorded,
    judged by an expectation and fed by a flow; off stage its pose holds and `present` is false."""
    overrides = {"record": ["P1.body.position", "P1.body.present"],
                 "expect": [{"name": "P1 stands", "slot": "P1.body.tilt", "always": {"<": 5}}]}
    from hub.run.assembly import Run
    from hub.scenario.expectations import Watcher

    scenario = load_scenario(SCENARIO, overrides)
    with Run(scenario, out=tmp_path) as run:
        watcher = Watcher(scenario.expect, run.plant.index, scenario.run.physics_rate)
        run.master.observers.append(watcher)
        run.run()
    [outcome] = watcher.judge()
    assert outcome.passed, outcome
    table = rows(tmp_path / "recording.csv")
    present = [r["P1.body.present"] for r in table]
    first, last = present.index("1"), len(present) - 1 - present[::-1].index("1")
    assert present[:first] == ["0"] * first and set(present[first:last + 1]) == {"1"}
    assert present[last + 1:] and set(present[last + 1:]) == {"0"}, "taken by the sink: gone"
    # On stage it rides the belt; once gone its pose holds where the sink took it, never off stage.
    xs = [float(r["P1.body.position.x"]) for r in table]
    assert xs[first] < 0.1 and xs[last] > 1.8
    assert xs[last + 1:] == [xs[last]] * (len(xs) - last - 1)


def test_a_bottle_id_that_clashes_with_an_object_is_an_error(tmp_path):
    from hub.core.errors import ScenarioError

    text = SCENARIO.read_text().replace("  sink: {module: sink", "  P2: {module: constant, type: int, value: 1}\n  sink: {module: sink")
    path = tmp_path / "clash.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    assert "object 'source' makes 'P2', a name object 'P2' has already: rename one of them" in str(caught.value)
    assert "clash.yaml:" in str(caught.value)
