"""The bottling plant (scenarios/bottling_plant.yaml) on a shortened run: every bottle delivered
reaches the sink of its destination, the lanes all deliver, and no bottle tips, falls, speeds
or passes a closed gate. (Determinism of the engine is covered by the other scenario tests.)"""
import csv
import subprocess
import sys

from hub.scenario import load_scenario
from modules.source import Source

from .helpers import ROOT
from .plant_watch import run_watched

SCENARIO = ROOT / "scenarios" / "bottling_plant.yaml"
LANES = {"sink_A": "A", "sink_B": "B", "sink_C": "C", "sink_D": "D"}
DURATION = 56.0     # s: P01..P08 reach their sinks (P08 on lane D at 55.02 s), P09 on lane A too


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def destinations(scenario):
    store = next(o for o in scenario.objects if o.name == "store")
    return dict(Source.bottles("store", store.params, scenario.run.seed))


def deliveries(scenario, directory):
    """(sink, bottle) in the order taken, and the misrouted as (bottle, destination, sink)."""
    wanted = destinations(scenario)
    taken = [(e["slot"].split(".")[0], e["detail"]) for e in rows(directory / "events.csv")
             if e["slot"].endswith(".bin.taken")]
    return taken, [(ident, wanted[ident], sink) for sink, ident in taken if LANES[sink] != wanted[ident]]


def test_bottles_reach_their_destinations_soundly(tmp_path):
    scenario, _, watch = run_watched(SCENARIO, tmp_path, {"run.duration": DURATION})
    watch.assert_sound()
    taken, misrouted = deliveries(scenario, tmp_path)
    assert not misrouted, f"misrouted (bottle, destination, sink): {misrouted}"
    delivered = {ident for _, ident in taken}
    assert len(delivered) == len(taken) >= 8
    assert {f"P{k:02d}" for k in range(1, 9)} <= delivered
    last = rows(tmp_path / "recording.csv")[-1]
    for sink, dest in LANES.items():   # the sinks' own counts agree: every lane delivered, only its own
        assert int(last[f"{sink}.count.total"]) == int(last[f"{sink}.count.{dest}"]) >= 2


def test_a_wrong_routing_participant_misroutes_and_hub_test_names_the_bottles(tmp_path):
    """The plant-management participant with the lanes of sw1 and sw2 swapped (B, A, C)."""
    swapped = ["--set", "run.duration=28", "--set", "objects.control.parameters.lanes=B,A,C"]
    proc = subprocess.run([sys.executable, "-m", "hub", "test", str(SCENARIO), *swapped,
                           "--out", str(tmp_path)], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "  ✗ lane A receives only A bottles — failed 1×: at " in proc.stdout
    assert "it was 'B' (sink_A.bin.object = 'P02')" in proc.stdout
    assert "it was 'A' (sink_B.bin.object = 'P01')" in proc.stdout
    _, misrouted = deliveries(load_scenario(SCENARIO), tmp_path)
    assert sorted(misrouted) == [("P01", "A", "sink_B"), ("P02", "B", "sink_A")]
