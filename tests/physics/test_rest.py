"""Bodies at rest (hub/physics/rest.py): the engine leaves still bottles asleep, the hub stops
reading them, and wakes them before anything can move them. Every world here compares the
resting bodies with the engine at every tick (check_rest): a body the engine moved while the
hub thought it at rest stops the test with its name."""
import numpy as np
import pytest

from hub.physics import PhysicsWorld
from hub.physics.rest import BREAKING, SHAPE_MARGIN, bound, boxes

RATE = 150


def world_with(belt_speed: float, sleep_after: float = 0.1) -> PhysicsWorld:
    """A floor from x = −0.5 to 3, a belt over x ∈ [0, 1) and a wall at x = 3; no friction
    anywhere (the paper's rule), so a bottle leaving the belt slides on at its speed."""
    world = PhysicsWorld(RATE, sleep_after=sleep_after)
    world.check_rest = True
    world.add_static_box((1.25, 0, -0.01), (1.75, 0.3, 0.01))
    world.add_static_box((3.01, 0, 0.1), (0.01, 0.3, 0.1))
    world.add_force_field((0.5, 0, 0.15), (0.5, 0.3, 0.15), 0.0, 16.0, belt_speed)
    return world


def queue(world, x0: float, count: int, pitch: float = 0.061):
    """Bottles r = 3 cm, 10 cm tall, standing one behind the other from x0 (1 mm apart)."""
    return [world.add_bottle((x0 + k * pitch, 0, 0), 0.03, 0.1, 0.05, f"q{k}") for k in range(count)]


def test_still_bottles_rest_are_not_read_and_the_engine_holds_them():
    with world_with(belt_speed=0.0) as world:
        bottles = queue(world, 0.3, 4) + queue(world, 1.5, 2)   # on the stopped belt and off it
        world.step(60)                                           # 0.4 s: settled, then still 0.1 s
        assert world.rest.resting[bottles].all()
        assert world._live_rows is not None and len(world._live_rows) == 0
        held = world.positions.copy()
        world.step(300)
        assert np.array_equal(world.positions, held)
        assert not world.velocities.any() and not world.angular_velocities.any()


def test_nothing_rests_with_sleep_after_zero_or_on_a_running_belt():
    with world_with(belt_speed=0.0, sleep_after=0.0) as world:
        queue(world, 0.3, 2)
        world.step(150)
        assert not world.rest.resting.any() and world._live_rows is None
    with world_with(belt_speed=0.5) as world:
        bottle = world.add_bottle((0.2, 0, 0), 0.03, 0.1, 0.05, "riding")
        world.step(300)
        assert not world.rest.resting[bottle] and world.velocities[bottle, 0] > 0.4


def test_a_bottle_held_at_a_closed_gate_on_a_running_belt_rests_and_goes_when_it_opens():
    with world_with(belt_speed=0.5) as world:
        gate = world.add_switchable_boxes([(0.9, 0, 0.05)], [(0.01, 0.3, 0.05)], [0.0], solid=True)
        bottle = world.add_bottle((0.8, 0, 0), 0.03, 0.1, 0.05, "held")
        world.step(60)        # at the gate from tick 25, still (under 5 mm/s) from ~55: not yet
        assert not world.rest.resting[bottle]
        world.step(60)        # still for HELD_AFTER (0.3 s): rests
        assert world.rest.resting[bottle] and abs(world.positions[bottle, 0] - (0.89 - 0.03)) < 0.001
        world.set_solid(gate, False)
        assert not world.rest.resting[bottle]          # woken as the gate opens
        world.step(30)
        assert world.velocities[bottle, 0] > 0.3       # and carried on


def test_a_belt_that_starts_wakes_what_rests_on_it():
    with world_with(belt_speed=0.0) as world:
        bottles = queue(world, 0.2, 3)
        world.step(60)
        assert world.rest.resting[bottles].all()
        world.set_field_speed(0, 0.5)
        assert not world.rest.resting[bottles].any()
        world.step(75)
        assert world.velocities[bottles, 0] == pytest.approx([0.5] * 3, abs=0.01)
        assert world.positions[bottles[0], 0] > 0.2 + 0.15


def test_a_bottle_sliding_in_wakes_the_resting_queue_it_runs_into():
    """Off the belt's end a bottle slides on at 0.5 m/s into a queue resting against the wall.
    The whole queue must be awake before the engine lets the bottles touch: Bullet wakes a
    sleeping island when an awake body's box joins it, and so does the hub, a tick ahead."""
    with world_with(belt_speed=0.5) as world:
        rest = queue(world, 3.0 - 0.0305 - 4 * 0.061, 5)   # the last one 0.5 mm from the wall
        runner = world.add_bottle((0.2, 0, 0), 0.03, 0.1, 0.05, "runner")
        world.step(150)
        assert world.rest.resting[rest].all() and not world.rest.resting[runner]
        before = world.positions[rest].copy()
        closest = np.inf
        for _ in range(900):                 # it arrives after ~5 s and pushes the queue into the wall
            world.step(1)
            closest = min(closest, world.positions[rest[0], 0] - world.positions[runner, 0])
            assert np.all(np.diff(world.positions[rest, 0]) > 0.055)   # no bottle into another
        assert closest < 0.0605 and not np.array_equal(world.positions[rest], before)


def test_a_gate_turning_solid_over_a_resting_bottle_wakes_it():
    with world_with(belt_speed=0.0) as world:
        bottle = world.add_bottle((0.5, 0, 0), 0.03, 0.1, 0.05, "b")
        other = world.add_bottle((0.2, 0, 0), 0.03, 0.1, 0.05, "far")
        gate = world.add_switchable_boxes([(0.5, 0, 0.05)], [(0.01, 0.3, 0.05)], [0.0], solid=False)
        world.step(60)
        assert world.rest.resting[[bottle, other]].all()
        world.set_solid(gate, True)
        assert not world.rest.resting[bottle] and world.rest.resting[other]
        world.step(30)
        assert abs(world.positions[bottle, 0] - 0.5) > 0.001          # the gate pushes it


def test_gripping_a_resting_bottle_wakes_it():
    with world_with(belt_speed=0.0) as world:
        bottle = world.add_bottle((1.5, 0, 0), 0.03, 0.1, 0.05, "b")
        arm = world.add_arm((1.5, -0.5, 0.0), 0.0, 0.1)
        world.step(60)
        assert world.rest.resting[bottle]
        world.grip(arm, bottle)
        assert not world.rest.resting[bottle]
        world.step(150)
        assert not world.rest.resting[bottle]       # held by an arm: never at rest
        world.release(arm)


def test_the_hubs_boxes_hold_the_engines_boxes_in_any_pose():
    """rest.boxes, less the breaking threshold Bullet adds in its pair search, against the
    engine's own box of bottles of three shapes tumbling down a pile; and the one-number
    bound against both."""
    with PhysicsWorld(RATE, sleep_after=0.0) as world:
        world.add_static_box((0, 0, -0.01), (1.0, 1.0, 0.01))
        shapes = [(0.03, 0.05), (0.04, 0.02), (0.02, 0.12)]
        bodies = [world.add_bottle((0.013 * (k % 5), 0.011 * (k % 3), 0.25 * k), r, 2 * h, 0.05, f"b{k}")
                  for k, (r, h) in enumerate(shapes * 8)]
        worst, tilts = 0.0, []
        for _ in range(40):
            world.step(6)
            tilts += [np.degrees(world.tilt(n)) for n in bodies]
            lo, hi = (np.array(a) for a in zip(*(world.engine_box(n) for n in bodies)))
            engine = (hi - lo) / 2.0
            assert np.allclose((hi + lo) / 2.0, world.positions[bodies], atol=1e-9)
            ours = boxes(world.orientations[bodies], world.radii[bodies], world.half_heights[bodies]) - BREAKING
            assert (ours >= engine).all()
            worst = max(worst, (ours - engine).max())
            reach = np.array([bound(world.radii[n], world.half_heights[n], world.velocities[n],
                                    world.angular_velocities[n], world.dt, SHAPE_MARGIN + BREAKING) for n in bodies])
            assert (reach[:, None] >= ours + BREAKING - 1e-12).all()
        assert worst < 0.003
        tilts = np.array(tilts)
        assert (tilts > 60).sum() > 100 and ((tilts > 5) & (tilts < 60)).sum() > 50   # turned every way
