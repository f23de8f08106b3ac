"""The plant part of the run summary: bottles in, delivered per sink and destination, misrouted, on the line, throughput — printed, in summary.json and from the Python API."""
import csv
import json

import pytest

from hub import Simulation
from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario
from modules.source import Source

from .helpers import ROOT, planthub_run

SOURCE_SINK = ROOT / "scenarios" / "source_sink.yaml"


def taken(out):
    """(time, sink, bottle) of every bottle taken out, from the event log."""
    with open(out / "events.csv", newline="") as f:
        return [(float(e["time"]), e["slot"].split(".")[0], e["detail"]) for e in csv.DictReader(f)
                if e["slot"].endswith(".bin.taken")]


def test_source_sink_counts_bottles_in_and_out_by_destination(tmp_path):
    stdout, summary = planthub_run(SOURCE_SINK, tmp_path)
    scenario = load_scenario(SOURCE_SINK)
    made = Source.bottles("source", scenario.objects[1].params, scenario.run.seed)
    wanted = {d: sum(1 for _, x in made if x == d) for d in sorted({d for _, d in made})}
    plant = summary["plant"]
    assert plant["bottles_in"] == plant["released"]["source"] == plant["delivered"] == 6
    assert plant["by_destination"] == wanted == plant["sinks"]["sink"]["by_destination"]
    assert plant["misrouted"] is None and plant["sinks"]["sink"]["accepts"] is None   # no sink says its lane
    assert plant["on_line"] == [] and plant["jams"] == [] and plant["jam_after"] == 5.0
    times = [t for t, _, _ in taken(tmp_path)]
    assert plant["throughput"] == {"per_minute": 6 * 60 / 6.5, "window": [0.0, 6.5],
                                   "first_to_last_per_minute": 5 * 60 / (times[-1] - times[0]),
                                   "first": times[0], "last": times[-1]}
    counts = ", ".join(f"{d} {n}" for d, n in wanted.items())
    lines = stdout.splitlines()
    assert "  bottles in   6  (released by source 6)" in lines
    assert f"  delivered    6  ({counts})" in lines
    assert f"    sink     6  ({counts})" in lines
    assert "  misrouted    not judged (no sink says which destinations its lane is for: give sinks `accepts`)" in lines
    most = plant["most_on_line"]
    assert 2 <= most["bottles"] <= 6 and 0 < most["time"] < 6.5
    assert f"  on the line  none  (at most {most['bottles']}, at {most['time']:.1f} s)" in lines
    # The real-time factor while the line held 90 % of its most, as printed and in summary.json.
    full = summary["wall"]["full_line"]
    assert full["at_least"] == -(-9 * most["bottles"] // 10) and 0 < full["simulated_seconds"] <= 6.5
    assert full["realtime_factor"] == full["simulated_seconds"] / full["wall_seconds"]
    assert (f"; {full['realtime_factor']:.1f}× while {full['at_least']} or more bottles were on the line, "
            f"{full['simulated_seconds']:.1f} s)") in next(line for line in lines if line.startswith("  wall time"))
    assert (f"  throughput   55.38 /min over 0–6.5 s  (6 delivered; {5 * 60 / (times[-1] - times[0]):.2f} /min "
            f"from the first delivery at {times[0]:.3f} s to the last at {times[-1]:.3f} s)") in lines
    assert f"  summary      {tmp_path / 'summary.json'}" in lines
    assert summary["files"]["summary"] == str(tmp_path / "summary.json")
    assert summary["simulated"] == {"seconds": 6.5, "ticks": 975, "physics_rate": 150, "communication_step": 1 / 150}


def test_a_sink_for_one_lane_names_the_misrouted_bottles(tmp_path):
    stdout, summary = planthub_run(SOURCE_SINK, tmp_path, "objects.sink.accepts=[A]",
                                   "record=[sink.count.misrouted]")
    scenario = load_scenario(SOURCE_SINK)
    made = dict(Source.bottles("source", scenario.objects[1].params, scenario.run.seed))
    wrong = [(t, ident) for t, _, ident in taken(tmp_path) if made[ident] != "A"]
    assert wrong   # the seed draws B bottles too
    plant = summary["plant"]
    assert plant["misrouted"] == [{"bottle": ident, "destination": made[ident], "sink": "sink", "time": t}
                                  for t, ident in wrong]
    assert plant["sinks"]["sink"]["misrouted"] == len(wrong) and plant["sinks"]["sink"]["accepts"] == ["A"]
    lines = stdout.splitlines()
    assert f"  misrouted    {len(wrong)}" in lines
    for t, ident in wrong:
        assert f"    {ident} (for {made[ident]}) at sink, {t:.3f} s" in lines
    assert any(line.endswith(f"lane for A, {len(wrong)} misrouted") for line in lines)
    with open(tmp_path / "recording.csv", newline="") as f:
        assert int(list(csv.DictReader(f))[-1]["sink.count.misrouted"]) == len(wrong)
    with open(tmp_path / "events.csv", newline="") as f:
        logged = [e["detail"] for e in csv.DictReader(f) if e["slot"] == "sink.bin.misrouted"]
    assert logged == [f"{ident} (for {made[ident]})" for _, ident in wrong]


def test_switch_bottles_placed_up_front_are_delivered_without_destination():
    with Simulation(ROOT / "scenarios" / "switch.yaml") as sim:
        sim.run()
        plant = sim.summary().plant
    assert (plant.placed, plant.released, plant.bottles_in, plant.delivered) == (2, {}, 2, 2)
    assert [(s.name, s.by_destination) for s in plant.sinks] == [("main_end", {"": 1}), ("branch_end", {"": 1})]
    assert plant.misrouted is None and plant.on_line == () and plant.jams == ()


def test_bottles_still_on_the_line_are_named_with_their_belt(tmp_path):
    stdout, summary = planthub_run(SOURCE_SINK, tmp_path, "run.duration=2")
    plant = summary["plant"]
    assert plant["delivered"] == 0 and plant["bottles_in"] == len(plant["on_line"]) == 4
    assert [b["belt"] for b in plant["on_line"]] == ["belt"] * 4
    names = ", ".join(f"{b['bottle']} on belt" for b in plant["on_line"])
    assert plant["most_on_line"]["bottles"] == 4
    assert f"  on the line  4  ({names}; at most 4, at {plant['most_on_line']['time']:.1f} s)" in stdout.splitlines()


def test_a_scene_without_sinks_and_sources_keeps_the_plain_summary(tmp_path):
    stdout, summary = planthub_run(ROOT / "scenarios" / "belt_bottle_sensor.yaml", tmp_path)
    assert "plant" not in summary   # a scene that is no plant has no plant section
    starts = [line.split()[0] for line in stdout.splitlines() if line.startswith("  ") and not line.startswith("    ")]
    assert starts == ["ended", "simulated", "wall", "events", "recording", "event", "summary"]


def test_the_python_api_writes_summary_json_when_closed(tmp_path):
    with Simulation(SOURCE_SINK, out=tmp_path) as sim:
        sim.run(until=4.0)
        early = sim.summary()
        sim.run()
    assert early.plant.delivered < 6 and early.sim_seconds == 4.0
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["plant"]["delivered"] == 6 and written["simulated"]["seconds"] == 6.5


def test_bad_sink_lanes_and_jam_setting_are_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 1, jam_after: 0}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0}
          sink: {module: sink, position: [0.95, 0, 0.05], accepts: []}
          sink2: {module: sink, position: [0.95, 0.5, 0.05], accepts: [A, A]}
          sink3: {module: sink, position: [0.95, 1.0, 0.05], destinations: [A, misrouted]}
        """)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    assert str(caught.value).splitlines()[1:] == [
        f"  - {path}:2: run.jam_after: 0 is less than or equal to the minimum of 0",
        f"  - {path}:5: objects.sink.accepts: [] should be non-empty",
        f"  - {path}:6: objects.sink2.accepts: ['A', 'A'] has non-unique elements",
        f"  - {path}:7: objects.sink3.destinations[1]: 'misrouted' is taken by the slot count.misrouted",
    ]
