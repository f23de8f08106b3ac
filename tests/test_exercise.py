"""Exercises (`exercise:`): each goal judged on the plant's figures and the faults' start times, the
score in the printed summary and summary.json, and each goal and the score as a case of `planthub
test` (its JUnit file and exit code).

    a ─ b ─[reader]─ sw (main slowed to half from 0.5 s to 1.5 s) ─ main_end
"""
from __future__ import annotations

import json
from types import SimpleNamespace
from xml.etree import ElementTree

from hub.run.exercise import SCORE, _ScoreCase
from hub.scenario.exercise import Goal, judge, outage
from hub.scenario.expectations import Outcome, interrupted
from modules.plant.jams import Jam

from .helpers import planthub

SCENE = """
    planthub: 1
    name: ex
    run: {duration: 4.5, physics_rate: 150}
    objects:
      sw: {module: switch, position: [0, 0, 0], length: 2.0, branch_at: 1.0, branch_length: 1.0, side: right}
      a: {module: bottle, position: [0.10, 0, 0], id: A}
      b: {module: bottle, position: [0.60, 0, 0], id: B}
      main_end: {module: sink, position: [1.95, 0, 0.05]}
    faults:
      - {name: slow main, kind: belt_failure, target: sw.main, speed: 0.5, at: 0.5, for: 1}
    exercise:
      task: |
        Deliver both bottles.
        Quickly.
      goals:
        - {delivered: 2}
        - {longest_jam: 0, points: 2}
        - {recover_within: 4}
        - {throughput: %s, name: fast enough}
      pass: 80
    """


def test_run_prints_and_writes_the_goals_and_the_score(write_scenario, tmp_path, capsys):
    path = write_scenario(SCENE % 100)
    code, out, _ = planthub(capsys, "run", path, "--out", tmp_path / "run", "-q")
    assert code == 0
    lines = out.splitlines()
    start = lines.index("  faults       1")
    assert lines[start:start + 9] == [
        "  faults       1",
        "    slow main: belt_failure at sw.main from 0.500 s to 1.500 s",
        "  exercise     Deliver both bottles.",
        "               Quickly.",
        "    ✓ at least 2 bottles delivered — 2 delivered",
        "    ✓ no jam — no jam  (2 points)",
        "    ✓ never 4 s without a delivery after a fault — slow main: at most 2.65 s without a delivery (from 0.500 s)",
        "    ✗ fast enough — 26.67 a minute",
        "  score        80 % (4 of 5 points): passed (passes at 80 %)"]
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["exercise"]["score"] == 80.0 and summary["exercise"]["passed"] is True
    assert [(g["name"], g["met"]) for g in summary["exercise"]["goals"]] == [
        ("at least 2 bottles delivered", True), ("no jam", True), ("never 4 s without a delivery after a fault", True),
        ("fast enough", False)]
    assert summary["faults"] == {"started": [{"name": "slow main", "kind": "belt_failure", "target": "sw.main",
                                              "start": 0.5, "end": 1.5}]}


def test_planthub_test_judges_each_goal_and_the_score(write_scenario, tmp_path, capsys):
    path = write_scenario(SCENE % 20)
    code, out, _ = planthub(capsys, "test", path, "--junit", tmp_path / "ex.xml")
    assert code == 0
    assert out.splitlines()[-2:] == ["  ✓ the score — 100 % (5 of 5 points): passed (passes at 80 %)", "5 passed, 0 failed"]
    cases = ElementTree.parse(tmp_path / "ex.xml").getroot().findall(".//testcase")
    assert [c.get("name") for c in cases] == ["at least 2 bottles delivered", "no jam",
                                              "never 4 s without a delivery after a fault", "fast enough", "the score"]
    path = write_scenario(SCENE % 100)
    code, out, _ = planthub(capsys, "test", path, "--junit", tmp_path / "ex.xml")
    assert code == 1 and "  ✗ fast enough — 26.67 a minute" in out.splitlines()
    root = ElementTree.parse(tmp_path / "ex.xml").getroot()
    assert root.find(".//failure").text == "expected at least 100 deliveries a minute: 26.67 a minute"
    properties = {p.get("name"): p.get("value") for p in root.findall(".//property")}
    assert (properties["score"], properties["passed"]) == ("80", "true")


def plant(times, jams=(), end=60.0, misrouted=(), rejected=()):
    return SimpleNamespace(delivery_times=tuple(times), jams=tuple(jams), end=end, delivered=len(times),
                           misrouted=tuple(misrouted), rejected=rejected, per_minute=60.0 * len(times) / end)


def test_recovery_is_the_longest_stretch_without_a_delivery_after_the_fault():
    assert outage(10.0, plant([5.0, 15.0, 19.0, 22.0], end=25.0)) == (10.0, 5.0)
    assert outage(10.0, plant([5.0, 11.0, 13.0], end=20.0)) == (13.0, 7.0)   # open at the end
    assert outage(30.0, plant([5.0, 11.0], end=40.0)) == (30.0, 10.0)
    goal = Goal("recover_within", 6.0, 1, "back within 6 s")
    verdict = judge(goal, plant([5.0, 15.0, 19.0, 22.0], end=25.0), [("lane C", 10.0), ("late", 14.0)])
    assert (verdict.met, verdict.message) == (True, "lane C: at most 5.00 s without a delivery (from 10.000 s); "
                                                    "late: at most 4.00 s without a delivery (from 15.000 s)")
    verdict = judge(goal, plant([5.0, 15.0], end=25.0), [("lane C", 10.0)])
    assert (verdict.met, verdict.message) == (False, "lane C: at most 10.00 s without a delivery (from 15.000 s to "
                                                     "the end)")


def test_jam_and_misroute_goals_say_what_they_measured():
    jam = Jam("M3", "b02", 12.0, None)
    assert judge(Goal("longest_jam", 5.0, 1, "j"), plant([1.0], [jam], end=30.0), []).message == \
        "1 jam, the longest M3 on b02 from 12.000 s for 18.00 s (still jammed at the end)"
    wrong = SimpleNamespace(bottle="M7", destination="C", sink="sink_F")
    verdict = judge(Goal("misrouted", 0, 1, "m"), plant([1.0], misrouted=[wrong]), [])
    assert (verdict.met, verdict.message) == (False, "1 misrouted: M7 (for C) at sink_F")


def test_the_reject_goal_counts_what_reject_sinks_took_and_needs_one():
    out = [SimpleNamespace(bottle=f"M{i}", destination="A", sink="reject", time=float(i)) for i in range(1, 8)]
    verdict = judge(Goal("rejected", 1, 1, "r"), plant([1.0], rejected=tuple(out)), [])
    assert (verdict.met, verdict.message) == (False, "7 rejected: M1 (for A); M2 (for A); M3 (for A); M4 (for A); "
                                                     "M5 (for A)")
    assert judge(Goal("rejected", 1, 1, "r"), plant([1.0], rejected=tuple(out[:1])), []).met
    assert Goal("rejected", 0, 1, "").describe() == "no bottle rejected"
    verdict = judge(Goal("rejected", 0, 1, "r"), plant([1.0], rejected=None), [])
    assert (verdict.met, verdict.message) == (False, "not judged: no sink takes rejects (`rejects: true`)")


def test_an_interrupted_run_judges_only_the_goals_the_rest_of_it_could_not_change():
    goals = [(Goal("misrouted", 0, 1, "none misrouted"), False), (Goal("misrouted", 0, 1, "none yet"), True),
             (Goal("longest_jam", 5, 1, "short jams"), False), (Goal("delivered", 10, 1, "ten"), True),
             (Goal("delivered", 20, 1, "twenty"), False), (Goal("throughput", 9, 1, "pace"), True),
             (_ScoreCase(SCORE, 100.0), False)]
    outcomes = interrupted([Outcome(g, met, "so far") for g, met in goals], 300, 150)
    assert [(o.expectation.name, o.judged, o.passed) for o in outcomes] == [
        ("none misrouted", True, False), ("none yet", False, False), ("short jams", True, False),
        ("ten", True, True), ("twenty", False, False), ("pace", False, False), ("the score", False, False)]
    assert outcomes[1].message == "not judged: the run was interrupted at t = 2 s (so far: so far)"
