"""The bottling plant (scenarios/bottling_plant.yaml, the scenario `make run` runs) on shortened
runs: every good bottle delivered reaches the sink of its destination, every bottle the filler
left unfilled is pushed into the reject lane, every lane delivers, no bottle tips, falls, speeds
or passes a closed gate, and nothing jams — with the engine moving every bottle and with free
transport (the default); routing by the plant-management participant over Zenoh gives the
run of the same logic in-process, bit for bit, either way; a participant with two lanes
swapped makes `planthub test` fail naming the misrouted bottles."""
import csv
import json
import subprocess
import sys

import pytest

from hub.scenario.checker import load_scenario
from modules.source import Source

from .helpers import ROOT, planthub_run, run_scenario
from .plant_watch import run_watched

pytestmark = pytest.mark.slow   # each test runs the bottling plant for 40-56 s

SCENARIO = ROOT / "scenarios" / "bottling_plant.yaml"
LANES = {f"sink_{lane}": lane for lane in "ABCDEF"}
IN_PROCESS = {"objects.control.runs": "hub"}
DURATION = 56.0     # s: the first delivery is at 34.7 s; by 56 s every lane has had a bottle
# The filler's share of bad fills for the watched run: the plant's 4 % leaves its first bottle
# unfilled only at the 36th; at 30 % the seed makes M002, M004, M013 and M015 bad, within 56 s.
FAULTS = 0.3


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def destinations(scenario):
    """Every bottle's destination, as the sources draw them from the run's seed."""
    wanted = {}
    for obj in scenario.objects:
        if obj.module_name == "source":
            wanted.update(Source.bottles(obj.name, obj.params, scenario.run.seed))
    return wanted


def deliveries(scenario, directory):
    """(sink, bottle) in the order taken at the lanes' sinks, and the misrouted as (bottle,
    destination, sink); the reject lane's sink is not a lane."""
    wanted = destinations(scenario)
    taken = [(e["slot"].split(".")[0], e["detail"]) for e in rows(directory / "events.csv")
             if e["slot"].endswith(".bin.taken") and e["slot"].split(".")[0] in LANES]
    return taken, [(ident, wanted[ident], sink) for sink, ident in taken if LANES[sink] != wanted[ident]]


@pytest.mark.parametrize("transport", ["engine", "free"])   # free (the default): every bottle may ride free
def test_good_bottles_reach_their_destinations_and_the_bad_the_reject_lane_soundly(tmp_path, transport):
    overrides = {"run.duration": DURATION, "objects.filler.faults": FAULTS, "defaults.source.transport": transport,
                 **IN_PROCESS}
    scenario, _, watch = run_watched(SCENARIO, tmp_path, overrides)
    watch.assert_sound()
    events = rows(tmp_path / "events.csv")
    bad = [e["detail"] for e in events if e["slot"] == "filler.process.faulty"]
    rejected = [e["detail"] for e in events if e["slot"] == "reject.bin.taken"]
    failed = [e["detail"] for e in events if e["slot"] == "inspect.trigger.failed"]
    assert bad[:4] == ["M002", "M004", "M013", "M015"]          # the seed's draw, in filling order
    assert rejected == failed == bad[:len(rejected)] and len(rejected) >= 3   # each bad one, in turn
    assert not any(e["slot"] == "kicker.push.refused" for e in events)
    taken, misrouted = deliveries(scenario, tmp_path)
    assert not misrouted, f"misrouted (bottle, destination, sink): {misrouted}"
    assert not set(bad) & {ident for _, ident in taken}         # no bad bottle reached a lane
    assert len({ident for _, ident in taken}) == len(taken) >= 8
    assert {sink for sink, _ in taken} == set(LANES)      # every lane delivered
    last = rows(tmp_path / "recording.csv")[-1]
    assert sum(int(last[f"{sink}.count.total"]) for sink in LANES) == len(taken)
    assert int(last["reject.count.total"]) == len(rejected)
    plant = json.loads((tmp_path / "summary.json").read_text())["plant"]
    assert [r["bottle"] for r in plant["rejected"]] == rejected and plant["delivered"] == len(taken)
    assert plant["misrouted"] == [] and plant["jams"] == []


def test_the_run_summary_counts_what_the_event_log_shows_and_finds_no_jam(tmp_path):
    stdout, summary = planthub_run(SCENARIO, tmp_path, "run.duration=45", "objects.control.runs=hub")
    plant = summary["plant"]
    taken, _ = deliveries(load_scenario(SCENARIO), tmp_path)
    released = [e for e in rows(tmp_path / "events.csv") if e["slot"].endswith(".store.released")]
    assert plant["bottles_in"] == len(released) >= 60   # the magazine fills at the start
    assert plant["delivered"] == len(taken) > 0
    assert plant["misrouted"] == [] and plant["jams"] == []
    assert "  misrouted    none" in stdout and "  jams         none" in stdout


@pytest.mark.parametrize("transport", ["engine", "free"])
def test_routing_over_the_bus_gives_the_in_process_run_bit_for_bit(tmp_path, transport):
    for name, overrides in (("bus", {}), ("in_process", IN_PROCESS)):
        run_scenario(SCENARIO, tmp_path / name, {"run.duration": 40.0, "defaults.source.transport": transport,
                                                 **overrides})
    for file in ("recording.csv", "events.csv"):
        assert (tmp_path / "bus" / file).read_bytes() == (tmp_path / "in_process" / file).read_bytes()
    assert any(e["slot"] == "control.logic.sw1_work" for e in rows(tmp_path / "bus" / "events.csv"))


def test_a_wrong_routing_participant_misroutes_and_hub_test_names_the_bottles(tmp_path):
    """The plant-management participant with the lanes of sw1 and sw2 swapped (B, A, C, D, E)."""
    swapped = ["--set", "run.duration=44", "--set", 'objects.control.python=[modules.plant_control, --lanes, "B,A,C,D,E"]']
    proc = subprocess.run([sys.executable, "-m", "hub", "test", str(SCENARIO), *swapped,
                           "--out", str(tmp_path)], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    _, misrouted = deliveries(load_scenario(SCENARIO), tmp_path)
    assert misrouted and all((dest, sink) in {("A", "sink_B"), ("B", "sink_A")} for _, dest, sink in misrouted)
    assert "  ✗ lane A receives only A bottles — failed" in proc.stdout
    assert "  ✗ lane B receives only B bottles — failed" in proc.stdout
    for ident, dest, sink in misrouted:
        assert f"it was '{dest}' ({sink}.bin.object = '{ident}')" in proc.stdout
