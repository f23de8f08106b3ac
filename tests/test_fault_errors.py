"""Every bad `faults:` and `exercise:` entry is named with its file, line and path, all at once; a
bad fault in a replayed commands.csv names its line; a live `fault` is refused where no fault book is."""
from __future__ import annotations

import pytest

from hub.bus.commands import CommandError, load_commands
from hub.core.errors import ScenarioError
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT


def problems(path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p) for p in info.value.problems]


def test_every_bad_fault_and_goal_is_named_at_its_line(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 4.5, physics_rate: 150}
        objects:
          sw: {module: switch, position: [0, 0, 0], length: 2.0, branch_at: 1.0, branch_length: 1.0, side: right}
          a: {module: bottle, position: [0.10, 0, 0], id: A}
          reader: {module: id_reader, position: [0.8, 0, 0.05]}
          main_end: {module: sink, position: [1.95, 0, 0.05]}
        faults:
          - {kind: part_stuck, target: sww, at: 1}
          - {kind: belt_failure, target: sw, at: 1}
          - {kind: sensor_stuck, target: sw.main, value: true, at: 1}
          - {kind: part_stuck, target: sw, at: 1, after: {event: reader.trigger.on_enter}}
          - {kind: part_stuck, target: sw, after: {event: reader.trigger.occupied}, for: 1}
          - {kind: part_stuck, target: sw, after: {event: reader.trigger.on_entr}, until: 2}
          - {kind: sensor_stuck, target: reader, at: 1}
          - {kind: part_stuck, target: sw, at: 1, speed: 0.5, name: x}
          - {kind: reader_fault, target: reader, reads: wrong, at: 1}
          - {kind: reader_fault, target: reader, reads: nothing, destination: B, at: 1}
          - {kind: part_stuck, target: sw, between: [3, 2]}
          - {kind: part_stuck, target: sw, at: 9}
          - {kind: part_stuck, target: sw, at: 2, until: 1}
          - {kind: part_stuck, target: sw, at: 1, name: x}
          - {kind: melt, target: sw, at: 1, for: -1}
          - {kind: belt_failure, target: sw.main, speed: 1.5, at: 1}
          - {kind: logic_dead, target: sw, at: 1}
        exercise:
          task: t
          goals:
            - {delivered: 1, misrouted: 0}
            - {}
            - {throughput: 2, name: same}
            - {delivered: 2, name: same}
            - {score: 3}
        """)
    assert problems(path) == [
        f"{path}:33: exercise.goals[4].score: unknown key 'score' (known: delivered, longest_jam, misrouted, name, points, recover_within, rejected, throughput)",
        f'{path}:23: faults[14].for: -1 is less than or equal to the minimum of 0',
        f"{path}:23: faults[14].kind: 'melt' is not one of ['sensor_stuck', 'belt_failure', 'part_stuck', 'reader_fault', 'logic_dead', 'bottle_tipped']",
        f'{path}:24: faults[15].speed: 1.5 is greater than or equal to the maximum of 1',
        f"{path}:9: faults[0].target: unknown object 'sww' (did you mean 'sw'?)",
        f"{path}:10: faults[1].target: 'sw' has several: name one (sw.main, sw.branch)",
        f'{path}:11: faults[2].target: sw.main is not a sensor (a volume trigger: on_enter and occupied), which sensor_stuck needs',
        f'{path}:12: faults[3]: give exactly one start: `at` (a time), `after` (an event) or `between` (a window the seed draws a time from), not at and after',
        f'{path}:13: faults[4].after.event: reader.trigger.occupied is bool; a fault starts after an event, a void source',
        f'{path}:14: faults[5].until: `until` is a time, and a fault after an event starts at a time no one knows before the run: give `for`',
        f'{path}:15: faults[6]: sensor_stuck needs `value`',
        f'{path}:16: faults[7].speed: `speed` is not a parameter of part_stuck (it takes none)',
        f'{path}:17: faults[8]: reader_fault with `reads: wrong` needs the `destination` it reads instead',
        f'{path}:18: faults[9].destination: `destination` goes with `reads: wrong`; a reader that reads nothing reads no destination',
        f'{path}:19: faults[10].between: the window [3, 2] s is empty: give [earliest, latest]',
        f"{path}:20: faults[11].at: starts at 9 s, after the run's end at 4.5 s",
        f"{path}:21: faults[12].until: 1 s is not after the fault's start at 2 s",
        f"{path}:22: faults[13].name: two faults are named 'x' (the other at line 16): name them apart",
        f"{path}:25: faults[16].target: object 'sw' has no component that is state logic (a `logic` component: an FMU or a participant), which logic_dead needs",
        f'{path}:29: exercise.goals[0]: give exactly one goal of delivered, misrouted, rejected, longest_jam, recover_within, throughput, not delivered and misrouted',
        f'{path}:30: exercise.goals[1]: give exactly one goal of delivered, misrouted, rejected, longest_jam, recover_within, throughput',
        f"{path}:32: exercise.goals[3]: two goals are named 'same': name them apart",
    ]


def test_an_exercise_needs_a_plant(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 2}
        exercise:
          task: deliver
          goals: [{delivered: 1}]
        """)
    assert problems(path) == [f"{path}:4: exercise: an exercise's goals are judged on a plant, a scenario with a "
                              "source or a sink; this one has neither"]


def test_a_fault_given_with_set_is_blamed_on_set():
    with pytest.raises(ScenarioError) as info:
        load_scenario(ROOT / "scenarios" / "switch.yaml", {"faults": [{"kind": "part_stuck", "target": "reader", "at": 1}]})
    assert [str(p) for p in info.value.problems] == [
        "--set: faults[0].target: object 'reader' has no component that is a part with two positions (a switch blade, a gate, a stopper: "
        "blocked), which part_stuck needs"]


@pytest.mark.parametrize("value, message", [
    ('{"name": "x", "kind": "melt"}', "fault: kind must be one of sensor_stuck, belt_failure, part_stuck, "
                                      "reader_fault, logic_dead, bottle_tipped, got melt"),
    ('{"kind": "part_stuck"}', "fault: its value is a map with the fault's `name`"),
    ('{"name": "x", "kind": "belt_failure", "speed": 2}', "fault x: `speed` cannot be 2"),
    ('{"name": "x", "kind": "sensor_stuck"}', "fault x: sensor_stuck needs `value`"),
    ('{"name": "x", "kind": "belt_failure", "speed": "fast"}', "fault x: `speed` cannot be fast"),
    ('{"name": "x", "kind": "belt_failure", "speed": true}', "fault x: `speed` cannot be True"),
    ('{"name": "x", "kind": "sensor_stuck", "value": 1}', "fault x: `value` cannot be 1"),
    ('{"name": "x", "kind": "sensor_stuck", "value": true, "colour": 3}', "fault x: unknown parameter 'colour'"),
    ('{"name": "x", "kind": "reader_fault", "reads": "garbage"}', "fault x: `reads` is nothing or wrong"),
    ('{"name": "x", "kind": "reader_fault", "reads": "nothing", "id": "M1"}',
     "fault x: `id` goes with `reads: wrong`; a reader that reads nothing reads no id"),
    ('[1, 2]', "fault: its value is a map with the fault's `name`"),
])
def test_a_bad_fault_in_a_replayed_commands_file_names_its_line(tmp_path, value, message):
    scenario = load_scenario(ROOT / "scenarios" / "switch.yaml")
    (tmp_path / "events.csv").write_text("time,tick,slot,detail\n")
    slot = "reader.trigger" if "sensor" in value or "reader" in value else "sw.main" if "belt" in value else "sw.blade"
    quoted = value.replace('"', '""')
    (tmp_path / "commands.csv").write_text(f'time,tick,op,slot,value,by\n0.1,15,fault,{slot},"{quoted}",scenario\n')
    with Run(scenario) as run:
        with pytest.raises(CommandError) as info:
            load_commands(tmp_path, run.plant, run.faults)
    assert str(info.value).startswith(f"{tmp_path / 'commands.csv'}:2: {message}")


def test_a_fault_on_the_wrong_part_in_a_replayed_commands_file_is_refused(tmp_path):
    scenario = load_scenario(ROOT / "scenarios" / "switch.yaml")
    (tmp_path / "events.csv").write_text("time,tick,slot,detail\n")
    (tmp_path / "commands.csv").write_text('time,tick,op,slot,value,by\n'
                                           '0.1,15,fault,sw.main,"{""name"": ""x"", ""kind"": ""part_stuck""}",s\n')
    with Run(scenario) as run:
        with pytest.raises(CommandError) as info:
            load_commands(tmp_path, run.plant, run.faults)
        assert str(info.value) == (f"{tmp_path / 'commands.csv'}:2: fault x: sw.main is not a part with two positions "
                                   "(a switch blade, a gate, a stopper: blocked), which part_stuck needs")
        with pytest.raises(CommandError) as info:
            load_commands(tmp_path, run.plant)   # no fault book: a run that takes no faults
        assert str(info.value) == f"{tmp_path / 'commands.csv'}:2: fault: this run takes no faults"
