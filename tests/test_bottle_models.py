"""Bottle levels of detail: where the belt grips a bottle decides whether it rocks; hull or cylinder, it stands.

    bottle (at rest) ─► [====== belt, 0.5 m/s, k = 16 ======]   the belt drags the base: it leans back
"""
import numpy as np
import pytest

from hub.core.errors import ScenarioError
from hub.reports.runs import pitch, run
from hub.scenario.checker import load_scenario

SCENE = """
    planthub: 1
    run: {duration: 1.5, physics_rate: 150}
    objects:
      belt: {module: conveyor, position: [0, 0, 0], length: 1.5, speed: 0.5, k: 16}
      bottle: {module: bottle, position: [0.04, 0, 0], %s}
    record: [bottle.body.orientation, bottle.body.position, bottle.body.velocity]
"""


def lean(write_scenario, bottle):
    result = run(write_scenario(SCENE % bottle))
    return result, pitch(result.quat("bottle.body.orientation"))


@pytest.mark.parametrize("shape, floor", [("cylinder", 0.6), ("hull", 1.2)])
def test_a_force_at_the_centre_of_mass_does_not_rock_the_bottle(write_scenario, shape, floor):
    _, angle = lean(write_scenario, f"shape: {shape}")
    # Bullet's contact alone rocks a sliding bottle this much: the hull's 16-gon base more.
    assert np.max(np.abs(angle)) < floor


@pytest.mark.parametrize("model", ["base_point", "base_body"])
@pytest.mark.parametrize("shape", ["cylinder", "hull"])
def test_a_force_at_the_base_leans_the_bottle_back_then_it_rights_itself(write_scenario, model, shape):
    result, angle = lean(write_scenario, f"model: {model}, shape: {shape}")
    assert -3.0 < np.min(angle) < -1.5                        # leans against the motion
    assert abs(angle[-1]) < 0.6 and angle[np.argmin(angle)] == np.min(angle)
    # Wherever it grips, the field still brings the bottle to the belt speed.
    assert result.vec3("bottle.body.velocity")[-1, 0] == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("bottle", ["shape: hull", "shape: hull, profile: [[0, 0.03], [0.07, 0.03], [0.1, 0.01]]"])
def test_a_hull_bottle_stands_on_its_base_like_the_cylinder(write_scenario, bottle):
    result, _ = lean(write_scenario, bottle)
    # Centre of mass at half height, as for the cylinder (inertia of the homogeneous cylinder):
    # it rides about 2 mm deep in the belt surface at 150 Hz, like the cylinder.
    z = result.columns["bottle.body.position.z"][30:]
    assert np.all(np.abs(z - 0.05) < 3e-3)


def test_level_of_detail_errors_are_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          a: {module: bottle, position: [0, 0, 0], base_fraction: 0.1}
          b: {module: bottle, position: [0, 1, 0], profile: [[0, 0.03], [0.1, 0.01]]}
          c: {module: bottle, position: [0, 2, 0], shape: hull, profile: [[0.01, 0.03], [0.05, 0.04]]}
          d: {module: bottle, position: [0, 3, 0], model: torque}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    found = [str(p).split(": ", 1)[1] for p in info.value.problems]
    assert found == [
        "objects.a.base_fraction: only the base_body model has a second body: add `model: base_body` or drop base_fraction",
        "objects.b.profile: a profile shapes only a hull: add `shape: hull`",
        "objects.c.profile: heights must rise from 0 to the bottle's height (0.1 m), got [0.01, 0.05]",
        "objects.c.profile: no radius may exceed the bottle's radius (0.03 m): sensors and rails assume it",
        "objects.d.model: 'torque' is not one of ['simple', 'base_point', 'base_body']",
    ]
