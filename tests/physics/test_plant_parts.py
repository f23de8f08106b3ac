"""World parts for plant elements: switched collision, parked bodies, the kinematic arm."""
import math

import numpy as np
import pytest

from hub.physics import PhysicsWorld
from hub.physics.robot import JointMotion, smooth


def belt_world(rate=150, speed=0.5):
    world = PhysicsWorld(rate)
    world.add_static_box((1.0, 0, -0.01), (1.5, 0.3, 0.01))
    world.add_force_field((1.0, 0, 0.15), (1.5, 0.3, 0.15), 0.0, 16.0, speed)
    return world


def test_a_switched_part_blocks_only_while_solid():
    with belt_world() as world:
        bottle = world.add_cylinder((0.2, 0, 0), 0.03, 0.1, 0.05, "b")
        gate = world.add_switchable_boxes([(0.6, 0, 0.04)], [(0.01, 0.2, 0.04)], [0.0], solid=True)
        world.step(300)
        assert world.positions[bottle, 0] < 0.6 - 0.01 - 0.03 + 0.006      # held at the face
        world.set_solid(gate, False)
        world.step(150)
        assert world.positions[bottle, 0] > 0.9                             # gone through


def test_a_parked_body_is_off_stage_still_and_not_read():
    with belt_world() as world:
        live = world.add_cylinder((0.2, 0, 0), 0.03, 0.1, 0.05, "live")
        parked = world.add_cylinder((0.2, 0.2, 0), 0.03, 0.1, 0.05, "parked")
        world.park(parked)
        world.step(1)
        spot = world.positions[parked].copy()
        assert spot[2] < -50
        world.step(300)
        # Asleep in the engine and left out of the per-tick reads: its row never changes.
        assert np.array_equal(world.positions[parked], spot)
        assert world._live_rows.tolist() == [live]
        world.unpark(parked, (1.0, 0.2, 0.0))
        world.step(1)
        assert world.positions[parked, 2] == pytest.approx(0.05, abs=0.005)
        assert math.degrees(world.tilt(parked)) < 0.5
        world.step(150)
        assert world.velocities[parked, 0] == pytest.approx(0.5, abs=0.01)   # back on the belt
        assert world._live_rows is None or parked in world._live_rows.tolist()


def test_joint_motion_starts_and_ends_at_rest_on_integer_ticks():
    motion = JointMotion(np.zeros(7), np.ones(7), start=10, ticks=30, rate=150)
    q, qd = motion.at(10)
    assert np.all(q == 0) and np.all(qd == 0)
    q, qd = motion.at(40)
    assert np.all(q == 1) and np.all(qd == 0)
    q, _ = motion.at(25)
    assert np.allclose(q, 0.5)
    # The speed is the derivative of the position: compare with a finite difference.
    _, qd = motion.at(20)
    assert qd[0] == pytest.approx((motion.at(21)[0][0] - motion.at(19)[0][0]) * 150 / 2, rel=0.01)
    assert smooth(0.0) == (0.0, 0.0) and smooth(1.0) == (1.0, 0.0)


def test_the_arm_reaches_what_it_can_and_says_what_it_cannot():
    with PhysicsWorld(150) as world:
        arm = world.add_arm((0, 0, 0), 0.0, 0.1)
        q, miss = arm.solve((0.5, 0.1, 0.2))
        assert miss < 1e-6
        assert np.all(q >= arm.lower) and np.all(q <= arm.upper)
        _, miss = arm.solve((1.5, 0.0, 0.2))
        assert miss > 0.1
