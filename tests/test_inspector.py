"""Inspector and the station's faults: a filler that leaves a seeded share of bottles unfilled, an
inspector that fails them as they reach a pusher, which rejects them; good bottles pass."""
import csv

import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario
from modules.station import Process

from .helpers import run_scenario

# At run.seed 0 a filler named `filler` draws 0.866 for B3, 0.338 for B1 and 0.807 for B4: with
# `faults: 0.5` only B1 is filled badly.
LINE = """
planthub: 1
run: {duration: 10.0, physics_rate: 150}
objects:
  feed: {module: conveyor, position: [0, 0, 0], length: 1.6}
  source: {module: source, position: [0.04, 0, 0], bottles: [{id: B3}, {id: B1}, {id: B4}], interval: 2.0}
  filler: {module: station, operation: fill, time: 0.3, position: [0.96, 0, 0.05], faults: %s}
  stop: {module: stopper, position: [1.0, 0, 0], thickness: 0.02}
  out: {module: light_barrier, position: [1.3, 0, 0.05]}
  kicker: {module: pusher, after: feed, length: 1.0, at: 0.5}
  inspect: {module: inspector, position: [2.06, 0, 0.05], requires: [filled]}
  good: {module: sink, position: [2.55, 0, 0.05]}
  rejects: {module: sink, position: [2.1, -0.53, 0.05], yaw: 90, size: [0.05, 0.2, 0.1], rejects: true}
flows:
  - {from: filler.process.done, to: stop.gate.open}
  - {from: out.trigger.on_leave, to: stop.gate.close}
  - {from: inspect.trigger.failed, to: kicker.push.push}
record: [inspect.trigger.checked, rejects.count.total, good.count.total]
"""


def events(path):
    with open(path / "events.csv", newline="") as f:
        return [(e["slot"], e["detail"]) for e in csv.DictReader(f)]


def test_the_badly_filled_bottle_fails_the_inspection_and_is_rejected(write_scenario, tmp_path):
    run_scenario(write_scenario(LINE % 0.5), tmp_path)
    log = events(tmp_path)
    assert [d for s, d in log if s == "filler.process.faulty"] == ["B1"]
    assert [d for s, d in log if s == "filler.process.done"] == ["B3", "B1", "B4"]   # done, all three
    assert [(s, d) for s, d in log if s.startswith("inspect.trigger.") and s[16:] in ("passed", "failed")] == [
        ("inspect.trigger.passed", "B3"), ("inspect.trigger.failed", "B1"), ("inspect.trigger.passed", "B4")]
    assert [(s, d) for s, d in log if s.endswith("bin.taken")] == [
        ("good.bin.taken", "B3"), ("rejects.bin.taken", "B1"), ("good.bin.taken", "B4")]


def test_without_faults_every_bottle_is_filled_and_passes(write_scenario, tmp_path):
    run_scenario(write_scenario(LINE % 0), tmp_path)
    log = events(tmp_path)
    assert not any(s in ("filler.process.faulty", "inspect.trigger.failed", "kicker.push.on_extended")
                   for s, _ in log)
    assert [d for s, d in log if s == "good.bin.taken"] == ["B3", "B1", "B4"]


class Station:
    """What Process.faulty reads of its station."""

    def __init__(self, name, faults, seed=0):
        self.obj, self.faults, self.seed = name, faults, seed


def test_which_bottles_are_faulty_is_drawn_per_bottle_from_seed_and_name():
    ids = [f"M{i:03d}" for i in range(1, 131)] + [f"S{i:02d}" for i in range(1, 21)]

    def bad(station):
        return [b for b in ids if Process.faulty(station, b)]

    plant = bad(Station("filler", 0.04))
    assert plant == ["M036", "M072", "M098", "M100", "M110", "M123", "S12", "S19"]   # the bottling plant's 8
    assert [b for b in reversed(ids) if Process.faulty(Station("filler", 0.04), b)] == plant[::-1]   # any order
    assert bad(Station("filler", 0.04, seed=1)) != plant and bad(Station("capper", 0.04)) != plant
    assert bad(Station("filler", 0.0)) == [] and bad(Station("filler", 1.0)) == ids


def test_a_reject_sink_takes_no_accepts_and_faults_are_a_share(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          rej: {module: sink, position: [0, 0, 0], rejects: true, accepts: [A]}
          st: {module: station, position: [0, 0, 0], operation: fill, faults: 1.5}
          insp: {module: inspector, position: [0, 0, 0], requires: [painted]}
        """)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    text = str(caught.value)
    for line in (":3: objects.rej.accepts: a reject sink (`rejects: true`) takes whatever the line rejected, "
                 "whatever its destination: it takes no `accepts`",
                 ":4: objects.st.faults:", ":5: objects.insp.requires[0]:"):
        assert line in text, f"missing: {line}\nin:\n{text}"
