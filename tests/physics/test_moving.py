"""Moving kinematic parts (hub/physics/moving.py): a travel from the integer tick, a plate that hands
its speed to the bottle it pushes and holds still when leant on, and the rest rule around it —
what rests in its way is woken first (the engine would move it behind the hub's back otherwise,
and check_rest says so), and nothing is put to rest where it is about to go."""
import numpy as np
import pytest

from hub.physics import PhysicsWorld
from hub.physics.moving import Leg, Travel

RATE = 150
PLATE = ([(0.5, -0.06, 0.04)], [(0.06, 0.005, 0.04)], [0.0])   # a plate along x, its face at y = −0.055


def floor_world(sleep_after: float = 0.05, belt_speed: float | None = None) -> PhysicsWorld:
    world = PhysicsWorld(RATE, sleep_after=sleep_after)
    world.check_rest = True
    world.add_static_box((0.5, 0, -0.01), (1.0, 1.0, 0.01))
    if belt_speed is not None:
        world.add_force_field((0.5, 0, 0.15), (1.0, 0.3, 0.15), 0.0, 16.0, belt_speed)
    return world


def test_a_travel_is_a_function_of_the_integer_tick():
    travel = Travel(10, 0.0, [Leg(0.1, 0.5, hold=0.1), Leg(0.0, 0.25)], RATE)
    assert travel.arrivals == [40, 115] and travel.end == 115   # 0.1 m in 30 ticks, 15 held, 60 back
    assert travel.at(10) == 0.0 and travel.at(25) == pytest.approx(0.05)
    assert travel.at(40) == travel.at(54) == travel.at(55) == 0.1        # arrived exactly, held
    assert travel.at(85) == pytest.approx(0.05) and travel.at(115) == travel.at(500) == 0.0
    # The last tick of a leg moves what is left, never past it.
    odd = Travel(0, 0.0, [Leg(0.011, 0.5)], RATE)
    assert odd.end == 4 and odd.at(3) < 0.011 and odd.at(4) == 0.011
    with pytest.raises(ValueError, match="a leg's speed must be positive, not 0"):
        Travel(0, 0.0, [Leg(0.1, 0.0)], RATE)


def test_the_plate_pushes_a_bottle_at_its_own_speed_without_sinking_into_it():
    with floor_world() as world:
        bottle = world.add_bottle((0.5, 0, 0), 0.03, 0.1, 0.05, "b")
        plate = world.add_moving_boxes(*PLATE, axis=(0, 1, 0))
        world.step(15)
        plate.move(world.tick, [Leg(0.12, 0.5)])
        world.step(9)    # the face reaches the bottle at the 8th tick, 1.7 mm into it
        face = -0.055 + plate.offset
        assert world.positions[bottle, 1] - 0.03 > face - 0.002        # pushed out of the plate at once
        # The engine pushes the bottle out of that first overlap with velocity of its own (a
        # multibody contact has no split impulse): it runs 14 % ahead of the plate from then on.
        assert 0.5 <= world.velocities[bottle, 1] < 0.5 * 1.2
        world.step(60)
        assert not plate.moving and plate.offset == 0.12
        assert 0.5 <= world.velocities[bottle, 1] < 0.5 * 1.2          # left the plate with that speed
        # It rocks on the frictionless floor after the push (up to 4°, and a bottle that tips
        # over passes 10° within these 60 ticks). Woken from rest it rejoined the collision world
        # with a new contact on the floor (Engine.rejoin): 2.0° at this tick, 0.6° when it had kept one.
        assert np.degrees(world.tilt(bottle)) < 2.5


def test_a_standing_plate_holds_against_a_bottle_pressed_on_it():
    # The plate across a running belt, like a gate: the belt presses the bottle on its face for 2 s.
    with floor_world(sleep_after=0.0, belt_speed=0.5) as world:
        bottle = world.add_bottle((0.2, 0, 0), 0.03, 0.1, 0.05, "b")
        world.add_moving_boxes([(0.6, 0, 0.04)], [(0.005, 0.2, 0.04)], [0.0], axis=(1, 0, 0))
        world.step(2 * RATE)
        held = world.positions[bottle, 0]
        world.step(2 * RATE)
        assert held == pytest.approx(0.6 - 0.005 - 0.03, abs=0.003)
        assert world.positions[bottle, 0] == pytest.approx(held, abs=1e-4)


def resting_in_the_way(world):
    bottle = world.add_bottle((0.5, 0, 0), 0.03, 0.1, 0.05, "in_the_way")
    plate = world.add_moving_boxes(*PLATE, axis=(0, 1, 0))
    world.step(30)
    assert world.rest.resting[bottle]
    plate.move(world.tick, [Leg(0.12, 0.5)])
    return bottle, plate


def test_a_moving_plate_wakes_the_bottle_resting_in_its_way_and_pushes_it():
    with floor_world() as world:
        bottle, plate = resting_in_the_way(world)
        world.step(3)
        assert not world.rest.resting[bottle]        # woken before the plate reached it (5 ticks away)
        world.step(40)
        assert world.positions[bottle, 1] > 0.05     # pushed


def test_without_the_wake_the_engine_moves_a_resting_bottle_and_the_check_names_it(monkeypatch):
    """The proof that the wake matters: a resting bottle is out of the collision world, so the
    awake plate would pass through it while the hub still holds it at rest; the check names it."""
    from hub.physics.moving import MovingParts
    monkeypatch.setattr(MovingParts, "sweep", lambda self: None)   # nothing announced
    with floor_world() as world:
        resting_in_the_way(world)
        with pytest.raises(RuntimeError, match=r"in_the_way rests in planthub but body \d+ touches it: the wake came too late"):
            world.step(40)


def test_nothing_is_put_to_rest_in_a_moving_parts_way():
    # A still bottle 2 cm beside the plate's path, which runs along x past it at 1 m/s. Their
    # boxes join while the plate is within 0.06 + 0.03 + 2 × 0.022 (margins) + 0.007 m (its reach in
    # a tick) = 0.14 m of it, along x.
    with floor_world() as world:
        bottle = world.add_bottle((0.5, -0.065 - 0.02 - 0.03, 0), 0.03, 0.1, 0.05, "beside")
        plate = world.add_moving_boxes([(0.0, -0.06, 0.04)], [(0.06, 0.005, 0.04)], [0.0], axis=(1, 0, 0))
        plate.move(world.tick, [Leg(1.0, 1.0)])
        resting = []
        for _ in range(RATE):
            world.step(1)
            resting.append((plate.offset, bool(world.rest.resting[bottle])))
        assert resting[20][0] < 0.2 and resting[20][1]   # at rest while the plate is far
        assert not any(still for at, still in resting if abs(at - 0.5) < 0.13)
        assert resting[-1][1]                        # at rest again once the plate has gone by
