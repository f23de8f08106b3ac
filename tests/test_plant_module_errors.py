"""Bad parameters of the plant modules: every problem reported at once, each message naming the fix."""
import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario

BAD = """
planthub: 1
objects:
  sep: {module: separator, position: [1, 0, 0], push: 0.002, thickness: 0.005}
  sep2: {module: separator, position: [1, 0, 0], push: 0.04}
  sw: {module: switch, position: [0, 0, 0], length: 1.0, branch_at: 0.02, branch_length: 1.0}
  sw2: {module: switch, position: [0, 0, 0], length: 1.0, branch_at: 0.98, branch_length: 1.0}
  src: {module: source, position: [0, 0, 0], count: 3, bottles: [{id: a}]}
  src2: {module: source, position: [0, 0, 0], bottles: [{id: a}, {id: a}], weights: {A: 1}}
  src3: {module: source, position: [0, 0, 0], count: 2, weights: {A: 0}}
  sink: {module: sink, position: [0, 0, 0], destinations: [north-east, total]}
  arm: {module: robot_arm, position: [0, 0, 0], pick: [2, 0, 0], place: [0.5, 0, 0]}
  clk: {module: clock}
  clk2: {module: clock, at: [2, 1]}
  st: {module: station, position: [0, 0, 0], operation: paint}
"""


def test_bad_parameters_are_all_reported_with_their_lines(write_scenario):
    path = write_scenario(BAD)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path)
    text = str(caught.value)
    expected = [
        ":3: objects.sep.push: 0.002 m is less than WP's thickness (0.005 m): the second bottle of a queue "
        "reaches that far into WP, so it could never close",
        ":4: objects.sep2.push: 0.04 m reaches the axis of a bottle of diameter 0.06 m: WP would push it "
        "through, not back (keep it below 0.03 m)",
        ":5: objects.sw.branch_at: 0.02 m leaves no room for the blade before the branch: it needs at least "
        "0.06 m of main belt",
        ":6: objects.sw2.branch_at: 0.98 m puts the branch's opening past the main belt's end (length 1 m): "
        "at most 0.94 m",
        ":7: objects.src: give either `bottles` (a list of ids and destinations) or `count` (made by a rule)",
        ":8: objects.src2.weights: `weights` makes bottles by the rule: it goes with `count`, not `bottles`",
        ":8: objects.src2.bottles: duplicate ids: a",
        ":9: objects.src3.weights: at least one destination needs a weight above 0",
        ":10: objects.sink.destinations[0]: 'north-east' cannot name a slot: use letters, digits and _ "
        "(not starting with a digit)",
        ":10: objects.sink.destinations[1]: 'total' is taken by the slot count.total",
        ":11: objects.arm.pick: [2, 0, 0] is out of reach of the arm standing at [0, 0, 0]: the tool cannot "
        "get to above_pick and at_pick",
        ":12: objects.clk: give either `at` (a list of times) or `every` (a period), not both or neither",
        ":13: objects.clk2.at: times must be in increasing order",
        ":14: objects.st.operation: 'paint' is not one of ['cap', 'fill']",
    ]
    for line in expected:
        assert line in text, f"missing: {line}\nin:\n{text}"
    assert text.startswith(f"{len(expected)} problems in scenario")


def test_a_pose_the_arm_cannot_take_fails_the_build_naming_it(write_scenario):
    # Straight above its own base, pointing down: within reach, outside the joint limits.
    path = write_scenario("""
        planthub: 1
        objects:
          arm: {module: robot_arm, position: [0, 0, 0], pick: [0.5, 0, 0], place: [0, 0.5, 0], home: [0, 0, 0.5]}
        """)
    with pytest.raises(SimulationError, match=r"object 'arm': the arm cannot put its tool at home "
                                              r"\[0.0, 0.0, 0.5\] pointing down \(outside its joint limits\)"):
        Plant(load_scenario(path))


def test_a_source_id_already_taken_fails_the_build(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          b: {module: bottle, position: [0, 0, 0], id: S1}
          store: {module: source, position: [1, 0, 0], bottles: [{id: S1}]}
        """)
    with pytest.raises(SimulationError, match="object 'store': bottle id 'S1' is already used by another bottle"):
        Plant(load_scenario(path))
