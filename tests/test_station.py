"""Station: a bottle standing in it for the set time changes state; the stopper in front holds it."""
import csv

from .helpers import ROOT
from .plant_watch import run_watched


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_filling_station_fills_each_bottle_standing_in_it(tmp_path):
    """scenarios/station.yaml: two bottles, each held, filled after 1 s, let go, read as filled."""
    scenario, _, watch = run_watched(ROOT / "scenarios" / "station.yaml", tmp_path)
    watch.assert_sound()
    events = rows(tmp_path / "events.csv")
    station = [(e["slot"], e["detail"], int(e["tick"])) for e in events if e["slot"].startswith("filler")]
    assert [(s, d) for s, d, _ in station] == [("filler.process.started", "F1"), ("filler.process.done", "F1"),
                                              ("filler.process.started", "F2"), ("filler.process.done", "F2")]
    rate = scenario.run.physics_rate
    assert station[1][2] - station[0][2] == rate and station[3][2] - station[2][2] == rate
    data = rows(tmp_path / "recording.csv")
    read = [r["reader.trigger.filled"] for r in data if r["reader.trigger.filled"] != "0"]
    assert read, "the reader never read a filled bottle"
    reads = [e["detail"] for e in events if e["slot"] == "reader.trigger.on_enter"]
    assert reads == ["F1", "F2"]
    assert data[-1]["sink.count.total"] == "2"


SCENE = """
planthub: 1
run: {duration: 3.0, physics_rate: 150}
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2.0, speed: 0.5}
  bottle: {module: bottle, position: [0.5, 0, 0], id: Q}
  capper: {module: station, operation: cap, time: 0.5, position: [1.0, 0, 0.05]}
  reader: {module: id_reader, position: [1.5, 0, 0.05]}
record: [reader.trigger.capped, capper.process.busy]
"""


def test_a_bottle_that_does_not_stop_is_not_processed(write_scenario, tmp_path):
    run_watched(write_scenario(SCENE), tmp_path)
    events = [e["slot"] for e in rows(tmp_path / "events.csv")]
    assert "capper.process.started" not in events
    assert all(r["reader.trigger.capped"] == "0" for r in rows(tmp_path / "recording.csv"))
