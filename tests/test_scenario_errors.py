"""Every class of bad scenario input gets a message naming file, line, path and cause — all at once."""
import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario

GOOD_OBJECTS = """
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2}
  bottle: {module: bottle, position: [0.04, 0, 0]}
  barrier: {module: light_barrier, position: [1.5, 0, 0.05]}
  stop: {module: constant, type: bool, value: false}
  both: {module: connector, op: and}
"""


def problems(path, overrides=None):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, overrides)
    return [str(p) for p in info.value.problems], str(info.value)


def test_yaml_syntax_error_names_line_and_column(write_scenario):
    path = write_scenario("planthub: 1\nobjects:\n  belt: {module: conveyor\n")
    found, _ = problems(path)
    assert len(found) == 1
    assert found[0].startswith(f"{path}:4: not valid YAML")


def test_missing_file_is_named(tmp_path):
    found, _ = problems(tmp_path / "nope.yaml")
    assert found == [f"{tmp_path / 'nope.yaml'}: cannot read the file: No such file or directory"]


def test_duplicate_object_names(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 2}
          belt: {module: conveyor, position: [0, 1, 0], length: 2}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:4: objects.belt: duplicate name 'belt' (first defined at line 3)"]


def test_a_name_yaml_reads_as_a_boolean_is_named_and_checked_as_the_name(write_scenario):
    """YAML reads an unquoted `true` as a boolean: said so, and the name still checks as written.
    Scenarios are read as YAML 1.2, so `off`, `yes` and `no` are names (YAML 1.1 made them booleans)."""
    path = write_scenario("""
        planthub: 1
        objects:
          true: {module: constant, type: bool, value: true}
          off: {module: constant, type: bool, value: true}
        flows:
          - {from: tru.value.out, to: off.value.set, when: target}
        """)
    found, _ = problems(path)
    assert found == [
        f"{path}:3: objects.true: YAML reads the name true as the boolean True: write it in quotes ('true')",
        f"{path}:6: flows[0].from: unknown object 'tru' in 'tru.value.out' (did you mean 'true'?)"]


def test_duplicate_bottle_ids(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          b1: {module: bottle, position: [0, 0, 0], id: A7}
          b2: {module: bottle, position: [1, 0, 0], id: A7}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:4: objects.b2.id: duplicate id 'A7' (also used by object 'b1')"]


def test_unknown_module_suggests_the_closest(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          bottle: {module: botle, position: [0, 0, 0]}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:3: objects.bottle.module: unknown module 'botle' (did you mean 'bottle'?)"]


def test_unknown_and_wrong_parameters(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt:
            module: conveyor
            position: [0, 0, 0]
            lenght: 2
            speed: fast
        """)
    found, _ = problems(path)
    assert f"{path}:3: objects.belt: 'length' is missing" in found
    assert f"{path}:6: objects.belt.lenght: unknown key 'lenght' (did you mean 'length'?)" in found
    assert f"{path}:7: objects.belt.speed: 'fast' is not of type 'number'" in found


def test_unknown_top_level_and_run_keys(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duraton: 5}
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        flow: []
        """)
    found, _ = problems(path)
    assert f"{path}:5: flow: unknown key 'flow' (did you mean 'flows'?)" in found
    assert f"{path}:2: run.duraton: unknown key 'duraton' (did you mean 'duration'?)" in found


def test_unknown_object_and_slot_in_flows(write_scenario):
    path = write_scenario("planthub: 1" + GOOD_OBJECTS + """
flows:
  - {from: barier.trigger.on_enter, to: stop.value.set}
  - {from: barrier.trigger.on_entr, to: stop.value.set}
  - {from: barrier.on_enter, to: stop.set}
record: [bottle.body.positon]
""")
    found, _ = problems(path)
    assert found == [
        f"{path}:10: flows[0].from: unknown object 'barier' in 'barier.trigger.on_enter' (did you mean 'barrier'?)",
        f"{path}:11: flows[1].from: object 'barrier' (light_barrier) has no slot 'trigger.on_entr' "
        f"(did you mean 'trigger.on_enter'?)",
        f"{path}:13: record[0]: object 'bottle' (bottle) has no slot 'body.positon' (did you mean 'body.position'?)",
    ]


def test_type_mismatch_names_both_ends(write_scenario):
    path = write_scenario("planthub: 1" + GOOD_OBJECTS + """
flows:
  - {from: barrier.trigger.object, to: belt.drive.speed}
""")
    found, _ = problems(path)
    assert found == [f"{path}:10: flows[0]: type mismatch: barrier.trigger.object is string "
                     f"but belt.drive.speed is real"]


def test_direction_mismatch(write_scenario):
    path = write_scenario("planthub: 1" + GOOD_OBJECTS + """
flows:
  - {from: belt.drive.speed, to: barrier.trigger.on_enter}
""")
    found, _ = problems(path)
    assert found == [
        f"{path}:10: flows[0].from: belt.drive.speed is a target slot and cannot be read from here",
        f"{path}:10: flows[0].to: barrier.trigger.on_enter is a source slot and cannot be written to here",
    ]


def test_rearm_must_be_a_void_source_of_a_singular_flow(write_scenario):
    path = write_scenario("planthub: 1" + GOOD_OBJECTS + """
flows:
  - {from: stop.value.out, to: belt.drive.run, rearm: barrier.trigger.occupied, mode: singular}
  - {from: stop.value.out, to: belt.drive.run, rearm: barrier.trigger.on_leave}
""")
    found, _ = problems(path)
    assert found == [
        f"{path}:10: flows[0].rearm: re-arm slot barrier.trigger.occupied must be void, not bool",
        f"{path}:11: flows[1].rearm: only a singular flow can be re-armed (add mode: singular)",
    ]


def test_zero_delay_loop_names_its_flows(write_scenario):
    path = write_scenario("planthub: 1" + GOOD_OBJECTS + """  other: {module: connector, op: or}
flows:
  - {from: barrier.trigger.on_enter, to: both.logic.in0}
  - {from: both.logic.out, to: other.logic.in0}
  - {from: other.logic.out, to: both.logic.in1}
""")
    found, _ = problems(path)
    assert found == [
        f"{path}:11: flows: flows form a zero-delay loop (line 11: both.logic.out → other.logic.in0; "
        f"line 12: other.logic.out → both.logic.in1); break it with a component that delays"
    ]


def test_communication_step_must_be_whole_ticks(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {physics_rate: 150, communication_step: 0.01}
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:2: run.communication_step: 0.01 s is not a whole number of physics ticks at "
                     f"150 Hz (nearest: 0.00666667 s = 1 ticks, 0.0133333 s = 2 ticks)"]


def test_sleep_after_must_be_a_time_not_below_zero(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {sleep_after: -0.1}
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:2: run.sleep_after: -0.1 is less than the minimum of 0"]
    found, _ = problems(path, {"run.sleep_after": "soon"})
    assert found == ["--set: run.sleep_after: 'soon' is not of type 'number'"]


def test_solver_iterations_and_integrator_are_checked(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {solver_iterations: 0, integrator: implicit}
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:2: run.integrator: 'implicit' is not one of ['exact', 'explicit']",
                     f"{path}:2: run.solver_iterations: 0 is less than the minimum of 1"]


def test_ambiguous_short_slot_name(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        record: [bottle.position, bottle.id]
        """)
    scenario = load_scenario(path)   # unique short names resolve
    assert [str(ref) for ref, _ in scenario.record] == ["bottle.body.position", "bottle.tag.id"]


def test_constant_value_must_fit_its_type(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          v: {module: constant, type: vec3, value: [1, 2]}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:3: objects.v.value: not a vec3: expected a list of 3 numbers, got [1, 2]"]


def test_every_problem_is_reported_in_one_error(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {physics_rate: fast}
        objects:
          belt: {module: conveyer, position: [0, 0, 0], length: 2}
          bottle: {module: bottle, position: [0, 0]}
          barrier: {module: light_barrier, position: [1.5, 0, 0.05]}
        flows:
          - {from: barrier.trigger.on_enter, to: belt.drive.run}
          - {from: barrier.trigger.object, to: barrier.trigger.on_stay}
        """)
    found, message = problems(path)
    assert len(found) == 4, found
    assert message.startswith("4 problems in scenario:\n  - ")
    assert f"{path}:2: run.physics_rate: 'fast' is not of type 'integer'" in found
    assert f"{path}:4: objects.belt.module: unknown module 'conveyer' (did you mean 'conveyor'?)" in found
    assert f"{path}:5: objects.bottle.position: [0, 0] is too short" in found
    # The flow into an object already reported is not judged a second time.
    assert f"{path}:9: flows[1].to: barrier.trigger.on_stay is a source slot and cannot be written to here" in found


def test_override_that_breaks_the_schema_is_reported(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        """)
    found, _ = problems(path, {"run.physics_rate": 0})
    assert found == ["--set: run.physics_rate: 0 is less than the minimum of 1"]


def test_empty_file(write_scenario):
    path = write_scenario("# nothing here\n")
    found, _ = problems(path)
    assert found == [f"{path}:1: the file is empty"]


def test_top_level_must_be_a_mapping(write_scenario):
    path = write_scenario("- planthub: 1\n")
    found, _ = problems(path)
    assert found == [f"{path}:1: [{{'planthub': 1}}] is not of type 'object'"]


def test_override_into_a_non_mapping_is_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          bottle: {module: bottle, position: [0, 0, 0]}
        """)
    found, _ = problems(path, {"objects.bottle.position.x": 1})
    assert found == ["--set: objects.bottle.position.x: override does not name a mapping entry"]


def test_a_belt_placed_after_another_names_an_earlier_belt(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt_1: {module: conveyor, position: [0, 0, 0], length: 1}
          lamp: {module: light_barrier, position: [0, 0, 0]}
          bend: {module: curve, after: belt_l, turn: left, angle: 90, radius: 0.5}
          bend2: {module: curve, after: lamp, turn: left, angle: 90, radius: 0.5}
          early: {module: conveyor, after: late, length: 1}
          late: {module: conveyor, position: [5, 0, 0], length: 1}
        """)
    found, _ = problems(path)
    assert found == [
        f"{path}:5: objects.bend.after: no conveyor or curve 'belt_l' is declared before this object "
        f"(did you mean 'belt_1'?)",
        f"{path}:6: objects.bend2.after: object 'lamp' is a light_barrier, not a conveyor or curve (known: belt_1)",
        f"{path}:7: objects.early.after: no conveyor or curve 'late' is declared before this object (known: belt_1)",
    ]


def test_defaults_give_every_object_of_a_module_its_parameters(write_scenario):
    path = write_scenario("""
        planthub: 1
        defaults:
          bottle: {mass: 0.02, radius: 0.025}
          botle: {mass: 1}
        objects:
          a: {module: bottle, position: [0, 0, 0]}
          b: {module: bottle, position: [1, 0, 0], mass: 0.08}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:4: defaults.botle: unknown module 'botle' (did you mean 'bottle'?)"]
    path.write_text(path.read_text().replace("  botle: {mass: 1}\n", ""))
    params = {o.name: o.params for o in load_scenario(path).objects}
    assert (params["a"]["mass"], params["a"]["radius"]) == (0.02, 0.025)
    assert (params["b"]["mass"], params["b"]["radius"]) == (0.08, 0.025)


def test_an_error_in_a_belt_is_not_reported_again_at_the_objects_placed_after_it(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          feed: {module: conveyor, position: [0, 0, 0], lenght: 1.0}
          next: {module: conveyor, after: feed, length: 1.0}
          sw: {module: conveyor, after: next, length: "1.0"}
        """)
    found, _ = problems(path)
    assert found == [f"{path}:3: objects.feed: 'length' is missing",
                     f"{path}:3: objects.feed.lenght: unknown key 'lenght' (did you mean 'length'?)",
                     f"{path}:5: objects.sw.length: '1.0' is not of type 'number'"]   # nothing said of next.after
