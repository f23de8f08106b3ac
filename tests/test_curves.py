"""Curved and chained belts: bottles follow curves without touching a rail and cross seams upright.

    s1 (0.6 m) ─► left 90° ─► right 90° ─► s2 (0.6 m, faster: 0.8 m/s)    `after:` chains them
"""
import math

import numpy as np
import pytest

from hub.core.errors import ScenarioError
from hub.reports.runs import run
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario

S_BEND = """
    planthub: 1
    run: {duration: 4.1, physics_rate: 150}
    objects:
      s1: {module: conveyor, position: [0, 0, 0], yaw: 30, length: 0.6, speed: 0.5}
      left: {module: curve, after: s1, turn: left, radius: 0.3, speed: 0.5}
      right: {module: curve, after: left, turn: right, angle: 90, radius: 0.45, speed: 0.5}
      s2: {module: conveyor, after: right, length: 0.6, speed: 0.8}
      bottle: {module: bottle, position: [0.0346, 0.02, 0], %s}
    record: [bottle.body.position, bottle.body.velocity, bottle.body.tilt]
"""


def test_after_starts_a_belt_where_the_one_before_ends(write_scenario):
    path = write_scenario(S_BEND % "model: simple")
    with Plant(load_scenario(path)) as plant:
        ends = plant.world.anchors
    s1, left, right = ends["s1"], ends["left"], ends["right"]
    yaw = math.radians(30)
    assert (s1.x, s1.y, s1.yaw) == pytest.approx((0.6 * math.cos(yaw), 0.6 * math.sin(yaw), yaw))
    # A left quarter turn of r = 0.3 m: forward by r and left by r, heading 90° further.
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    leftward = np.array([-math.sin(yaw), math.cos(yaw)])
    assert (left.x, left.y) == pytest.approx(tuple(np.array([s1.x, s1.y]) + 0.3 * forward + 0.3 * leftward))
    assert left.yaw == pytest.approx(yaw + math.pi / 2)
    assert right.yaw == pytest.approx(yaw)


@pytest.mark.parametrize("bottle", ["model: simple", "model: base_point", "model: base_body",
                                    "shape: hull", "model: base_point, shape: hull"])
def test_a_bottle_follows_both_curves_and_crosses_every_seam_upright(write_scenario, bottle):
    result = run(write_scenario(S_BEND % bottle))
    positions = result.vec3("bottle.body.position")
    field, along, across = result.fields.locate(positions)
    assert np.all(field >= 0), "the bottle left the belts"
    # It started 2 cm left of the centre line; on the curves it keeps that offset, far from a
    # rail (1 cm of play on either side).
    assert np.max(np.abs(across - across[0])) < 2e-3
    assert field[-1] == 3 and np.max(result.columns["bottle.body.tilt"]) < 3.0
    # On the last belt it takes on that belt's higher speed.
    speed = np.hypot(*result.vec3("bottle.body.velocity")[-1, :2])
    assert speed == pytest.approx(0.8, rel=0.02)


def test_the_along_grip_of_the_paper_leans_the_bottle_on_the_outer_rail(write_scenario):
    text = S_BEND % "model: simple"
    text = text.replace("turn: left,", "turn: left, grip: along,")
    result = run(write_scenario(text))
    _, _, across = result.fields.locate(result.vec3("bottle.body.position"))
    # Against the outer (right-hand) rail of the left turn: 2 cm of play, bottle radius 3 cm.
    assert np.min(across) < -0.015


def test_belts_butted_end_to_end_share_one_floor_so_a_bottle_crosses_without_a_bump(write_scenario):
    chain = "\n".join(f"  b{i}: {{module: conveyor, {'after: b%d' % (i - 1) if i else 'position: [0, 0, 0]'}, length: 0.5}}"
                      for i in range(4))
    path = write_scenario("planthub: 1\nrun: {duration: 3.5}\nobjects:\n" + chain
                          + "\n  bottle: {module: bottle, position: [0.04, 0, 0]}\n"
                          "record: [bottle.body.position, bottle.body.tilt]\n")
    result = run(path)
    # Four separate floor boxes tip this bottle over at the first seam (90°); one merged floor
    # carries it as a single belt does: it rocks by under 0.6°, as on any belt, because Bullet
    # finds the contact points of a base sliding over the fixed floor anew as it slides.
    assert np.max(result.columns["bottle.body.tilt"]) < 1.0
    assert np.ptp(result.columns["bottle.body.position.z"][150:]) < 1e-3


def problems(write_scenario, objects):
    path = write_scenario("planthub: 1\nobjects:\n" + objects)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p).split(": ", 1)[1] for p in info.value.problems]


def test_placement_errors_are_named(write_scenario):
    found = problems(write_scenario, """
  a: {module: conveyor, length: 1}
  b: {module: curve, after: a, position: [0, 0, 0], yaw: 10, turn: left}
  c: {module: curve, position: [0, 0, 0], turn: left, radius: 0.05}
  d: {module: conveyor, position: [0, 0, 0], length: 1, k: 4, gain: 0.2}
  e: {module: curve, position: [0, 0, 0], turn: up, angle: 400}
""")
    assert found == [
        "objects.a: needs `position` (start of its centre line) or `after` (the belt it continues)",
        "objects.b.position: give either `after` or `position`: a belt placed after 'a' starts where that belt ends",
        "objects.b.yaw: give either `after` or `yaw`: a belt placed after 'a' starts where that belt ends",
        "objects.c.radius: 0.05 m is too tight for a belt 0.1 m wide: the centre line's radius must exceed "
        "half the width plus the rail (0.06 m)",
        "objects.d.gain: give `k` (rate 1/s, force scaled by mass) or `gain` (the paper's unscaled law, N·s/m), not both",
        "objects.e.angle: 400 is greater than the maximum of 360",
        "objects.e.turn: 'up' is not one of ['left', 'right']",
    ]


def test_after_an_unknown_or_later_belt_is_named_with_a_suggestion(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          belt1: {module: conveyor, position: [0, 0, 0], length: 1}
          bend: {module: curve, after: belt_1, turn: left}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)   # checked with the scenario, before anything is built
    assert [str(p) for p in info.value.problems] == [
        f"{path}:4: objects.bend.after: no conveyor or curve 'belt_1' is declared before this object "
        f"(did you mean 'belt1'?)"]
