"""The shipped exercises on the bottling plant: each reference routing logic scores full marks, the
naive one fails a goal, and the plant they extend is scenarios/bottling_plant.yaml but for what each
says it changes."""
from __future__ import annotations

from xml.etree import ElementTree

import pytest

from hub.scenario.extends import read_document
from hub.scenario.yamlsource import load_yaml

from .helpers import ROOT, planthub

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
READER = ROOT / "scenarios" / "exercise_reader_fault.yaml"
SEPARATOR = ROOT / "scenarios" / "exercise_separator_sensor.yaml"
BELT = ROOT / "scenarios" / "exercise_belt_failure.yaml"
NAIVE = 'objects.control.python=[modules.plant_control, --lanes, "A,B,C,D,E", --occupied]'
NAIVE_SEPARATOR = 'objects.control.python=[modules.plant_control, --lanes, "A,B,C,D,E", --separator]'
NAIVE_FEED = 'objects.control.python=[modules.plant_control, --lanes, "A,B,C,D,E", --feed]'


def test_the_reader_exercise_is_the_bottling_plant_with_the_readers_occupied_wired_to_control():
    plant, exercise = load_yaml(PLANT)[0], read_document(READER)[0].data
    assert {k: v for k, v in exercise["objects"].items() if k != "control"} == \
        {k: v for k, v in plant["objects"].items() if k != "control"}
    added = [f for f in exercise["flows"] if f not in plant["flows"]]
    assert [f for f in plant["flows"] if f not in exercise["flows"]] == []
    assert added == [{"from": f"r{i}.trigger.occupied", "to": f"control.logic.r{i}_occupied"} for i in range(1, 6)]
    assert exercise.get("defaults") == plant.get("defaults")
    assert {k: v for k, v in exercise["run"].items() if k != "duration"} == \
        {k: v for k, v in plant["run"].items() if k not in ("duration", "orders")}


@pytest.mark.slow
def test_tracking_bottles_from_reader_to_reader_scores_full_marks(tmp_path, capsys):
    code, out, _ = planthub(capsys, "test", READER, "--junit", tmp_path / "ref.xml")
    assert code == 0, out
    assert "  ✓ the score — 100 % (5 of 5 points): passed (passes at 100 %)" in out.splitlines()
    assert ElementTree.parse(tmp_path / "ref.xml").getroot().get("failures") == "0"


@pytest.mark.slow
def test_routing_on_reads_only_misroutes_once_r3_reads_nothing(tmp_path, capsys):
    code, out, _ = planthub(capsys, "test", READER, "--set", NAIVE)
    assert code == 1
    lines = out.splitlines()
    assert "  ✗ no bottle misrouted — 1 misrouted: M012 (for C) at sink_F" in lines
    assert "  ✗ the score — 40 % (2 of 5 points): failed (passes at 100 %)" in lines


def test_the_separator_exercise_is_the_bottling_plant_with_b327_passed_through_control():
    plant, exercise = load_yaml(PLANT)[0], read_document(SEPARATOR)[0].data
    assert {k: v for k, v in exercise["objects"].items() if k != "control"} == \
        {k: v for k, v in plant["objects"].items() if k != "control"}
    assert [f for f in plant["flows"] if f not in exercise["flows"]] == [
        {"from": "B327.trigger.on_stay", "to": "sep.logic.B327_put"}]
    assert [f for f in exercise["flows"] if f not in plant["flows"]] == [
        {"from": "B327.trigger.on_stay", "to": "control.logic.b327"},
        {"from": "control.logic.sep_b327", "to": "sep.logic.B327_put"}]
    assert exercise.get("defaults") == plant.get("defaults")
    assert {k: v for k, v in exercise["run"].items() if k not in ("duration", "watch")} == \
        {k: v for k, v in plant["run"].items() if k not in ("duration", "orders")}


@pytest.mark.slow
def test_a_stuck_sensor_taken_as_stuck_keeps_the_separator_going(capsys):
    """B327 sticks on at 47.96 s (drawn from seed 0 in [38, 48] s)."""
    code, out, _ = planthub(capsys, "test", SEPARATOR)
    assert code == 0, out
    assert "  ✓ the score — 100 % (5 of 5 points): passed (passes at 100 %)" in out.splitlines()


@pytest.mark.slow
def test_a_stuck_sensor_passed_on_holds_the_separator_shut(capsys):
    code, out, _ = planthub(capsys, "test", SEPARATOR, "--set", NAIVE_SEPARATOR)
    assert code == 1
    lines = out.splitlines()
    assert "  ✗ never 10 s without a delivery after a fault — B327 stuck on: at most 16.12 s without a delivery " \
           "(from 73.880 s to the end)" in lines
    assert "  ✗ at least 28 bottles delivered — 21 delivered" in lines


def test_the_belt_exercise_is_the_bottling_plant_with_a_barrier_at_b02_and_the_feed_run_by_control():
    plant, exercise = load_yaml(PLANT)[0], read_document(BELT)[0].data
    assert {k: v for k, v in exercise["objects"].items() if k not in ("control", "B020")} == \
        {k: v for k, v in plant["objects"].items() if k != "control"}
    assert [f for f in plant["flows"] if f not in exercise["flows"]] == [
        {"from": "B327.trigger.on_stay", "to": "sep.logic.B327_put"}]
    assert [f for f in exercise["flows"] if f not in plant["flows"]] == [
        {"from": "B327.trigger.on_stay", "to": "control.logic.b327"},
        {"from": "control.logic.sep_b327", "to": "sep.logic.B327_put"},
        {"from": "control.logic.b01_run", "to": "b01.drive.run"},
        {"from": "B020.trigger.occupied", "to": "control.logic.b02_in"},
        {"from": "fill_out.trigger.occupied", "to": "control.logic.b02_out"}]
    assert exercise.get("defaults") == plant.get("defaults")
    assert {k: v for k, v in exercise["run"].items() if k != "duration"} == \
        {k: v for k, v in plant["run"].items() if k not in ("duration", "orders")}


@pytest.mark.slow
def test_feeding_a_slow_belt_one_bottle_at_a_time_fills_every_bottle(capsys):
    code, out, _ = planthub(capsys, "test", BELT)
    assert code == 0, out
    lines = out.splitlines()
    assert "  ✓ at most 1 rejected — 0 rejected" in lines
    assert "  ✓ the score — 100 % (5 of 5 points): passed (passes at 100 %)" in lines


@pytest.mark.slow
def test_feeding_a_slow_belt_as_fast_as_ever_lets_bottles_past_the_filler_unfilled(capsys):
    code, out, _ = planthub(capsys, "test", BELT, "--set", NAIVE_FEED)
    assert code == 1
    lines = out.splitlines()
    assert "  ✗ at most 1 rejected — 11 rejected: M009 (for D); M011 (for A); M013 (for A); M015 (for A); " \
           "M017 (for D)" in lines
    assert "  ✗ the score — 60 % (3 of 5 points): failed (passes at 100 %)" in lines


def test_validate_says_when_each_fault_starts_a_drawn_time_too(capsys):
    code, out, _ = planthub(capsys, "validate", SEPARATOR)
    assert code == 0
    assert out.splitlines()[1:] == [
        "  fault     B327 stuck on: sensor_stuck at B327.trigger (value True), from 47.96 s (drawn from run.seed in "
        "[38, 48] s) to the end",
        "  exercise  4 goals (never 10 s without a delivery after a fault, at least 28 bottles delivered, no bottle "
        "misrouted, no jam longer than 5 s), passes at 100 %"]
    code, out, _ = planthub(capsys, "validate", READER, "--set", "run.seed=3")
    assert out.splitlines()[1] == ("  fault     r3 reads nothing: reader_fault at r3.trigger (reads 'nothing'), "
                                   "from the 5th r3.trigger.on_enter to the end")
