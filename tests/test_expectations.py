"""Co-simulation tests for users' CI: expectations in YAML, `planthub test`, JUnit XML, the Python API."""
import subprocess
import sys
from xml.etree import ElementTree

import pytest

from hub import Simulation
from hub.core.errors import PlanthubError, ScenarioError
from hub.scenario.checker import load_scenario

from .fmus.fmu_support import build
from .helpers import ROOT

SWITCH = ROOT / "scenarios" / "switch_logic.yaml"
# The wrong plant control: the blade goes to working position too late for B and catches A.
WRONG = ["--set", "objects.to_working.at=[1.6]", "--set", "objects.to_base.at=[4.0]"]


@pytest.fixture(scope="module")
def fmus():
    return build(ROOT / "build" / "fmus")


def planthub_test(*args):
    return subprocess.run([sys.executable, "-m", "hub", "test", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT)


def test_passing_expectations_exit_0_and_write_junit(fmus, tmp_path):
    proc = planthub_test(SWITCH, "--junit", tmp_path / "report.xml")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.splitlines()[-1] == "4 passed, 0 failed"
    suite = ElementTree.parse(tmp_path / "report.xml").getroot().find("testsuite")
    assert (suite.get("name"), suite.get("tests"), suite.get("failures")) == ("switch_logic", "4", "0")
    assert [c.get("name") for c in suite.findall("testcase")] == [
        "B is diverted into the branch", "A runs straight on",
        "the blade is in working position by 0.5 s", "only B reaches the branch"]


def test_wrong_control_fails_naming_what_went_wrong(fmus, tmp_path):
    proc = planthub_test(SWITCH, *WRONG, "--junit", tmp_path / "report.xml")
    assert proc.returncode == 1
    assert "  ✗ only B reaches the branch — failed 1×: at 4.013 s it was 'A'\n" in proc.stdout
    assert "  ✗ the blade is in working position by 0.5 s — sw.blade.in_working was False at 0.5 s\n" in proc.stdout
    assert proc.stdout.splitlines()[-1] == "2 passed, 2 failed"
    failures = ElementTree.parse(tmp_path / "report.xml").getroot().iter("failure")
    assert [f.get("message") for f in failures] == [
        "sw.blade.in_working was False at 0.5 s", "failed 1×: at 4.013 s it was 'A'"]


def test_a_scenario_without_expectations_is_named(tmp_path):
    proc = planthub_test(ROOT / "scenarios" / "belt_bottle_sensor.yaml")
    assert proc.returncode == 2
    assert proc.stderr == f"planthub: {ROOT / 'scenarios' / 'belt_bottle_sensor.yaml'} has no `expect:` entries and no `exercise:` to judge\n"


def test_show_names_the_culprit_with_each_failure(fmus, write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 3.5}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 2}
          a: {module: bottle, position: [0.04, 0, 0], id: A7}
          gate: {module: light_barrier, position: [1.5, 0, 0.05]}
        expect:
          - {name: nothing passes the gate, slot: gate.trigger.on_enter, always: {"==": false}, show: gate.trigger.object}
          - {slot: gate.trigger.occupied, at: 100, is: {"==": false}}
        """)
    with Simulation(path) as sim:
        sim.run()
        first, late = sim.check()
    assert not first.passed and first.message == "failed 1×: at 2.92 s it was True (gate.trigger.object = 'A7')"
    assert not late.passed and late.message == "the run ended before 100 s"


def test_python_api_runs_until_a_condition_reads_slots_and_swaps_logic(fmus, tmp_path):
    with Simulation(SWITCH, logic={"sw": fmus / "track_switch-fmi3.fmu"}) as sim:
        assert sim.time == 0.0 and sim["sw.blade.in_base"] is True
        assert sim.run_until(lambda s: s["branch_end.count.total"] == 1, timeout=5.0)
        reached = sim.time
        assert 1.0 < reached < 4.0
        assert sim["main_end.count.total"] == 0
        assert "B" in [detail for _, slot, detail in sim.events if slot == "branch_end.bin.taken"]
        assert not sim.run_until(lambda s: s["main_end.count.total"] == 2, timeout=1.0)
        sim.run()
        assert sim.time == 4.5 and sim["main_end.count.total"] == 1
        assert all(o.passed for o in sim.check())
        assert ("branch_end.bin.taken" in {slot for _, slot, _ in sim.events})
        with pytest.raises(PlanthubError, match=r"no slot 'sw.blade.in_wrking' .*\(did you mean 'sw.blade.in_working'\?\)"):
            sim["sw.blade.in_wrking"]


def test_bad_expectations_are_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 2}
          gate: {module: light_barrier, position: [1.5, 0, 0.05]}
        expect:
          - {slot: gate.trigger.occupied}
          - {slot: gate.trigger.occupied, always: {"==": true}, at: 3}
          - {slot: gate.trigger.occupied, always: {"==": true}, when: gate.trigger.object}
          - {slot: belt.drive.velocity, is: {">": fast}}
          - {slot: gate.trigger.ocupied, is: {"==": true}}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:6: expect[0]: give exactly one of `is` (a value at a time) and `always` (at every point)",
        f"{path}:7: expect[1].at: `at` goes with `is`; `always` is judged at every point",
        f"{path}:8: expect[2].when: gate.trigger.object is string; `when` takes a void slot",
        f"{path}:9: expect[3].is.>: belt.drive.velocity is real: expected a finite number, got 'fast'",
        f"{path}:10: expect[4].slot: object 'gate' (light_barrier) has no slot 'trigger.ocupied' "
        f"(did you mean 'trigger.occupied'?)",
    ]


def test_python_api_launches_and_stops_participants(fmus, tmp_path):
    """The Python API starts what the scenario launches (here: belt-drive logic on the bus)."""
    reference = tmp_path / "in_process"
    with Simulation(ROOT / "scenarios" / "belt_ramp_fmu.yaml", out=reference) as sim:
        sim.run()
    with Simulation(ROOT / "scenarios" / "belt_ramp_participant.yaml", out=tmp_path / "bus") as sim:
        assert sim.run_until(lambda s: s["drive.logic.speed"] == 0.5, timeout=3.0)
        sim.run()
    assert (reference / "recording.csv").read_bytes() == (tmp_path / "bus" / "recording.csv").read_bytes()


def never_fired_scene(write_scenario, extra=""):
    return write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0}}
        objects:
          belt: {{module: conveyor, position: [0, 0, 0], length: 1.0, speed: 0.0}}
          barrier: {{module: light_barrier, position: [0.5, 0, 0.05]}}
        expect:
          - name: only the empty belt passes
            slot: barrier.trigger.object
            when: barrier.trigger.on_enter
            always: {{"==": nothing}}{extra}
        """)


def test_an_always_whose_when_never_fired_is_never_judged_and_fails(write_scenario):
    with Simulation(never_fired_scene(write_scenario)) as sim:
        sim.run()
        (outcome,) = sim.check()
    assert not outcome.passed
    assert outcome.message == ("never judged: barrier.trigger.on_enter never fired "
                               "(say `allow_empty: true` if that is a pass)")


def test_allow_empty_lets_an_unjudged_always_pass(write_scenario):
    with Simulation(never_fired_scene(write_scenario, "\n            allow_empty: true")) as sim:
        sim.run()
        (outcome,) = sim.check()
    assert outcome.passed and outcome.message == "held at 0 points"


def test_allow_empty_goes_with_always_and_when(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0}
        expect:
          - {slot: belt.drive.running, is: {"==": true}, allow_empty: true}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value.problems[0]) == (f"{path}:5: expect[0].allow_empty: `allow_empty` goes with `always` and "
                                           "`when`: only those can go unjudged")


def test_an_interrupted_run_keeps_what_is_settled_and_leaves_the_rest_unjudged():
    """At tick 300 (2 s at 150 Hz): a jam seen and orders out are settled; no jam so far,
    orders short and an `always` whose `when` has not fired yet could each still change."""
    from hub.core.slots import SlotRef, SlotType
    from hub.scenario.expectations import Expectation, Implied, NoJam, Outcome, interrupted

    waiting = Expectation("only B", SlotRef("end", "bin", "object"), SlotType.STRING, "==", "B", always=True,
                          when=SlotRef("end", "bin", "taken"))
    orders = Implied("the run ends with its 4 orders out (run.orders)")
    outcomes = [Outcome(NoJam("no jam"), False, "1 jammed: b1 on belt from 1.2 s"),
                Outcome(NoJam("no jam"), True, "held"),
                Outcome(orders, True, "4 delivered"),
                Outcome(orders, False, "the run ended at t = 2 s with 1 of 4 orders out"),
                Outcome(waiting, False, "never judged: end.bin.taken never fired (say `allow_empty: true` if that "
                                        "is a pass)")]
    judged = interrupted(outcomes, 300, 150)
    assert [(o.judged, o.passed) for o in judged] == [(True, False), (False, False), (True, True), (False, False),
                                                      (False, False)]
    when = "not judged: the run was interrupted at t = 2 s"
    assert [o.message for o in judged] == [
        "1 jammed: b1 on belt from 1.2 s", f"{when} (so far: held)", "4 delivered",
        f"{when} (so far: the run ended at t = 2 s with 1 of 4 orders out)",
        f"{when} (so far: never judged: end.bin.taken never fired (say `allow_empty: true` if that is a pass))"]


def test_a_loaded_scenario_runs_as_its_file_does_and_takes_no_overrides_again(fmus):
    loaded = load_scenario(SWITCH, {"run.duration": 0.5})
    with Simulation(loaded) as sim:
        assert sim.scenario is loaded
        sim.run()
        by_file = Simulation(SWITCH, {"run.duration": 0.5})
        with by_file:
            by_file.run()
            assert sim["main_end.count.total"] == by_file["main_end.count.total"] and sim.time == by_file.time == 0.5
    with pytest.raises(TypeError, match="overrides and logic go with a scenario's file: this Scenario is loaded"):
        Simulation(loaded, {"run.duration": 1.0})
