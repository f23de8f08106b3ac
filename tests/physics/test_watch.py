"""The physics watch (hub/physics/watch.py, placement.py): a run gone wrong stops, or the body is taken
out, naming the body, the tick and the cause; bodies placed overlapping are reported at load."""
import logging
import math
from pathlib import Path

import numpy as np
import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.physics import PhysicsWorld
from hub.physics._quiet import quiet_stderr
from hub.physics.watch import Watch
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

with quiet_stderr():
    import pybullet

SCENES = Path(__file__).parent / "scenes"
ROOT = Path(__file__).parents[2]


def run(name: str, **overrides):
    with Run(load_scenario(SCENES / f"{name}.yaml", overrides or None)) as r:
        result = r.run()
    return r.plant.world, result


def table_world(max_speed=None, policy="stop") -> PhysicsWorld:
    """A bottle standing on a 2 m × 0.6 m table, the world started."""
    world = PhysicsWorld(150)
    world.watch.configure(max_speed, policy)
    world.add_static_box((0.5, 0, -0.01), (1.0, 0.3, 0.01))
    world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "b")
    world.start()
    return world


def test_a_bottle_at_50_m_s_stops_the_run_at_the_first_tick_naming_it():
    with table_world() as world:
        world.engine.call(pybullet.resetBaseVelocity, world.bodies.ids[0], (50.0, 0, 0), (0, 0, 0))
        with pytest.raises(SimulationError) as caught:
            world.step(10)
    message = str(caught.value)
    assert "bottle 'b', tick 1 (t = 0.0067 s)" in message and "moves at 50.00 m/s" in message
    assert world.tick == 1


def test_a_non_finite_state_is_named_as_such():
    with table_world() as world:
        world.engine.call(pybullet.resetBaseVelocity, world.bodies.ids[0], (math.nan, 0, 0), (0, 0, 0))
        with pytest.raises(SimulationError, match=r"bottle 'b', tick 1 .*not finite"):
            world.step(10)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")   # 0·inf, on purpose
def test_the_check_catches_nan_speed_and_box_and_passes_the_rest():
    watch = Watch(9.81, max_speed=2.0)
    watch.arm((0, 0, 0), (1, 1, 0.1), np.zeros((0, 3)), 0.5)
    state = np.zeros((7, 13))           # per row: position, orientation, velocity, spin
    state[:, :3], state[:, 6] = (0.5, 0.5, 0.05), 1.0
    p, v = state[:, :3], state[:, 7:10]
    v[5] = (1.1, 1.1, 1.1)              # 1.91 m/s: past the quick per-component test, within the bound
    assert watch.check(state, None) is None
    p[1, 2] = -0.6                      # below the floor (box ends 0.5 m under the geometry)
    v[2, 0] = 2.1                       # too fast
    p[3, 0] = math.nan                  # not finite
    v[4, 1] = 1.9                       # fast, within the bound
    state[6, 12] = math.inf             # a spin gone infinite
    assert watch.check(state, None).tolist() == [1, 2, 3, 6]
    rows = np.array([10, 12, 14])
    assert watch.check(state[[0, 2, 4]], rows).tolist() == [12]   # named by the rows they are
    assert "below the floor" in watch.cause(p[1], v[1]) and "2.10 m/s" in watch.cause(p[2], v[2])
    assert "not finite" in watch.cause(p[3], v[3])
    assert "not finite" in watch.cause(p[6], v[6], state[6, 3:7].tolist() + state[6, 10:].tolist())


def test_a_bare_world_is_unwatched_until_configured():
    """Engine tests and benchmarks tip bottles off tables on purpose; a scenario's plant always watches."""
    world = PhysicsWorld(150)
    world.add_static_box((0.5, 0, -0.01), (1.0, 0.3, 0.01))
    world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "b")
    with world:
        world.start()
        world.engine.call(pybullet.resetBaseVelocity, world.bodies.ids[0], (50.0, 0, 0), (0, 0, 0))
        assert world.step(3) == 3 and not world.watch.enabled


def test_the_default_bound_follows_the_fastest_belt():
    watch = Watch(9.81)
    watch.arm((0, 0, 0), (1, 1, 0.0), np.zeros((0, 3)), 0.5)
    fall = math.sqrt(2 * 9.81 * 2.5)    # over the box: 0.5 m below, 2 m above
    assert watch.bound == pytest.approx(4 * 1.0 + fall)
    watch.belt_speed(3.0)
    assert watch.bound == pytest.approx(4 * 3.0 + fall)
    watch.belt_speed(0.0)               # a belt stopping does not lower it
    assert watch.bound == pytest.approx(4 * 3.0 + fall)


def test_a_belt_past_the_stated_bound_stops_the_run_at_the_tick_it_is_crossed():
    with pytest.raises(SimulationError) as caught:
        run("watch_fast")
    message = str(caught.value)
    assert message.startswith("bottle 'bottle', tick 7 (t = 0.0467 s): it moves at 1.05 m/s, above 1.00 m/s")
    assert "run.watch.max_speed" in message


def test_a_thrown_bottle_stops_the_run_by_default():
    with pytest.raises(SimulationError, match=r"bottle 'thrown', tick 79 .*fell below the floor"):
        run("watch_fling", **{"run.watch.on_violation": "stop"})


def test_remove_parks_the_thrown_bottle_logs_it_and_the_run_goes_on(caplog):
    with caplog.at_level(logging.WARNING, logger="hub.physics.world"):
        world, result = run("watch_fling")
    assert result.ticks == 225
    thrown, rider = world.labels.index("thrown"), world.labels.index("rider")
    assert world.is_parked(thrown) and not world.is_parked(rider)
    assert [(tick, body) for tick, body, _ in world.watch.removed] == [(79, thrown)]
    assert world.positions[rider][0] > 0.6          # the other bottle rode on: ~0.5 m/s for 1.5 s
    assert any("bottle 'thrown', tick 79" in r.getMessage() and "taken out" in r.getMessage()
               for r in caplog.records)


def test_a_body_taken_out_at_a_tick_the_rest_rule_looks_leaves_the_rest_to_the_next_look():
    """The rest rule reads the fields under the bodies of the tick's read; the body the watch took
    out since is skipped at that look, not a crash (a TypeError before)."""
    world, result = run("watch_fall_on_a_look")
    off = world.labels.index("off")
    assert [(tick, body) for tick, body, _ in world.watch.removed] == [(51, off)]
    assert 51 % world.rest.every == 0 and result.ticks == 150
    assert world.positions[world.labels.index("resting")][0] > 0.9   # the other bottle rode on


def test_a_bottle_placed_inside_a_rail_is_reported_at_load():
    with pytest.raises(SimulationError) as caught:
        run("watch_in_rail")
    message = str(caught.value)
    assert "tick 0" in message and "'bottle' is placed 30.0 mm into static geometry" in message
    assert "(0.500, 0.055, 0.035)" in message   # the rail's box


def test_two_bottles_placed_into_each_other_are_reported_at_load_naming_both():
    with pytest.raises(SimulationError, match=r"'first' at .* and 'second' at .* overlap by 20.0 mm"):
        run("watch_overlap")


def test_a_trigger_a_bottle_can_jump_between_ticks_is_reported_at_load(caplog):
    with caplog.at_level(logging.WARNING, logger="hub.physics.world"):
        world, _ = run("watch_thin_barrier")
    assert len(world.warnings) == 1 and "trigger 0 at (1.500, 0.000, 0.050) m is 5.0 mm deep" in world.warnings[0]
    assert "80.0 mm per tick" in caplog.text
    slow, _ = run("watch_thin_barrier", **{"objects.belt.speed": 0.5})
    assert slow.warnings == []


def test_a_gate_a_bottle_may_pass_through_between_ticks_is_reported_at_load(caplog):
    with caplog.at_level(logging.WARNING, logger="hub.physics.world"):
        world, _ = run("watch_thin_gate")
    assert len(world.warnings) == 1
    assert world.warnings[0].startswith("gate or blade 0 at (1.500, 0.000, ") and "is 5.0 mm thick" in world.warnings[0]
    assert "a bottle of 60 mm moving 41.7 mm per tick (the fastest belt) may pass through it" in caplog.text
    slow, _ = run("watch_thin_gate", **{"run.physics_rate": 150})   # 16.7 mm per tick: held
    assert slow.warnings == []


def test_a_shipped_scenario_runs_watched_and_unwarned():
    """The watch is on in a shipped scenario (a finite box and bound) and finds nothing there;
    every shipped scenario runs watched in tests/test_plant_scenarios.py."""
    with Run(load_scenario(ROOT / "scenarios" / "belt_bottle_sensor.yaml")) as r:
        r.run()
    world = r.plant.world
    assert np.isfinite(world.watch.lo).all() and 2.0 < world.watch.bound < 20.0
    assert world.warnings == [] and world.watch.removed == []


@pytest.mark.parametrize("watch, wrong", [({"max_speed": -1}, "max_speed"), ({"on_violation": "ignore"}, "on_violation"),
                                          ({"speed": 1}, "speed")])
def test_bad_watch_settings_are_scenario_errors(watch, wrong):
    with pytest.raises(ScenarioError, match=rf"run\.watch\.{wrong}: "):
        load_scenario(SCENES / "watch_fast.yaml", {"run.watch": watch})
