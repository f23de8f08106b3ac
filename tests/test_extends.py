"""A scenario that extends another (`extends:`, hub/scenario/extends.py): mappings merge key by key,
`null` takes a key out, flows, record, expect and faults add to the base's (`remove:` takes one
out), other lists replace; the name is the file's own; every problem names the file and line its
value was written at; a base elsewhere, missing, in a ring or unreadable is named."""
from __future__ import annotations

import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario

BASE = """
    planthub: 1
    name: line
    description: a belt, a barrier and a bottle
    run: {duration: 4.0, seed: 3}
    objects:
      belt: {module: conveyor, position: [0, 0, 0], length: 2.0, speed: 0.5}
      bottle: {module: bottle, position: [0.04, 0, 0]}
      barrier: {module: light_barrier, position: [1.0, 0, 0.05]}
      spare: {module: bottle, position: [0.5, 0, 0]}
      stop: {module: constant, type: bool, value: false}
    flows:
      - {from: barrier.trigger.on_enter, to: stop.value.set}
      - {from: stop.value.out, to: belt.drive.run}
    record: [bottle.body.position]
    """


def problems(path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p) for p in info.value.problems]


def test_an_extending_scenario_is_laid_over_its_base(write_scenario):
    write_scenario(BASE, "base.yaml")
    path = write_scenario("""
        planthub: 1
        extends: base.yaml
        run: {duration: 2.0}
        objects:
          belt: {speed: 0.3}
          spare: null
          bottle: {position: [0.1, 0, 0]}
        flows:
          - remove: {from: stop.value.out, to: belt.drive.run}
          - {from: barrier.trigger.on_leave, to: stop.value.set}
        record: [belt.drive.running]
        """, "child.yaml")
    scenario = load_scenario(path)
    assert scenario.name == "child" and scenario.description == ""      # its own, not the base's
    assert scenario.run.end_tick == 300 and scenario.run.seed == 3       # `run` merged key by key (2 s)
    objects = {o.name: o for o in scenario.objects}
    assert sorted(objects) == ["barrier", "belt", "bottle", "stop"]     # `spare: null` took it out
    assert objects["belt"].params["speed"] == 0.3 and objects["belt"].params["length"] == 2.0
    assert objects["bottle"].params["position"] == [0.1, 0, 0]          # a list replaces
    assert [(str(f.source), str(f.target)) for f in scenario.flows] == [
        ("barrier.trigger.on_enter", "stop.value.set"), ("barrier.trigger.on_leave", "stop.value.set")]
    assert [str(slot) for slot, _ in scenario.record] == ["bottle.body.position", "belt.drive.running"]


def test_a_chain_of_bases_merges_in_order(write_scenario):
    write_scenario(BASE, "base.yaml")
    write_scenario("""
        planthub: 1
        extends: base.yaml
        objects:
          belt: {speed: 0.3, k: 8}
        """, "middle.yaml")
    path = write_scenario("""
        planthub: 1
        extends: middle.yaml
        name: top
        objects:
          belt: {speed: 0.2}
        """, "top.yaml")
    belt = next(o for o in load_scenario(path).objects if o.name == "belt")
    assert (belt.params["speed"], belt.params["k"], belt.params["length"]) == (0.2, 8, 2.0)


def test_each_problem_names_the_file_and_line_its_value_was_written_at(write_scenario):
    base = write_scenario(BASE.replace("length: 2.0", "length: -2.0"), "base.yaml")
    path = write_scenario("""
        planthub: 1
        extends: base.yaml
        objects:
          bottle: {mass: -1}
        flows:
          - {from: barrier.trigger.on_entr, to: stop.value.set}
        """, "child.yaml")
    assert problems(path) == [
        f"{base}:6: objects.belt.length: -2.0 is less than or equal to the minimum of 0",
        f"{path}:4: objects.bottle.mass: -1 is less than or equal to the minimum of 0",
        f"{path}:6: flows[2].from: object 'barrier' (light_barrier) has no slot 'trigger.on_entr' "
        f"(did you mean 'trigger.on_enter'?)",
    ]


def test_a_base_that_cannot_be_used_is_named_at_the_extends_line(write_scenario, tmp_path):
    (tmp_path / "elsewhere").mkdir()
    write_scenario(BASE, "elsewhere/base.yaml")
    write_scenario("planthub: 1\nextends: ring_b.yaml\nobjects: {}\n", "ring_a.yaml")
    write_scenario("planthub: 1\nextends: ring_a.yaml\nobjects: {}\n", "ring_b.yaml")
    write_scenario("planthub: 1\nobjects: {belt: {module: conveyor\n", "broken.yaml")
    cases = {
        "elsewhere/base.yaml": "'elsewhere/base.yaml' is not in this file's folder: a base is a scenario beside the "
                               "one that extends it, so that the relative paths it holds are read from the same folder",
        "nowhere.yaml": f"no scenario file 'nowhere.yaml' (looked for {tmp_path / 'nowhere.yaml'})",
        "ring_a.yaml": "the scenarios extend each other in a ring: child.yaml → ring_a.yaml → ring_b.yaml → ring_a.yaml",
        "7": "7: give the file name of a scenario in this folder",
    }
    for named, message in cases.items():
        path = write_scenario(f"planthub: 1\nextends: {named}\nobjects: {{}}\n", "child.yaml")
        at = tmp_path / "ring_b.yaml" if named == "ring_a.yaml" else path   # where the ring closes
        assert problems(path) == [f"{at}:2: extends: {message}"], named
    path = write_scenario("planthub: 1\nextends: broken.yaml\nobjects: {}\n", "child.yaml")
    assert problems(path) == [f"{tmp_path / 'broken.yaml'}:3: not valid YAML (column 1): "
                              f"expected ',' or '}}', but got '<stream end>'"]


def test_removing_what_the_base_does_not_hold_is_named(write_scenario):
    write_scenario(BASE, "base.yaml")
    path = write_scenario("""
        planthub: 1
        extends: base.yaml
        flows:
          - remove: {from: stop.value.out, to: belt.drive.speed}
        """, "child.yaml")
    assert problems(path) == [f"{path}:4: flows: removes nothing: the base's flows hold no "
                              f"{{'from': 'stop.value.out', 'to': 'belt.drive.speed'}}"]


def test_a_name_no_file_can_have_is_named(write_scenario):
    path = write_scenario('planthub: 1\nextends: "a\\0b.yaml"\nobjects: {}\n', "child.yaml")
    assert problems(path) == [f"{path}:2: extends: 'a\\x00b.yaml' is not a file name (embedded null byte)"]
