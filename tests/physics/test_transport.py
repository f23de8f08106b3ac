"""Free transport (hub/physics/transport.py): a bottle riding a belt with nothing in reach leaves
the engine and follows the belt's law in numpy, and comes back before anything can touch it.
Every run here asks the engine at every tick whether a free bottle touches anything
(check_free), as check_rest does for resting ones."""

import numpy as np
import pybullet
import pytest

from hub.core.errors import ScenarioError
from hub.physics import PhysicsWorld
from hub.physics.frames import Pose, Straight
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from ..helpers import ROOT

SCENARIOS = ROOT / "scenarios"


def crossing(transport: str) -> tuple[int, bool, np.ndarray]:
    """belt_bottle_sensor.yaml: the tick the bottle enters the light barrier, whether it was free
    then, and its state at the end (position, velocity)."""
    scenario = load_scenario(SCENARIOS / "belt_bottle_sensor.yaml", {"objects.bottle.transport": transport})
    with Run(scenario) as run:
        run.start()
        world = run.plant.world
        world.check_free = True
        entered, free = None, False
        while world.tick < 450:
            world.step(1)
            if entered is None and world.triggers.occupied()[0]:
                entered, free = world.tick, bool(world.transport.free[0])
        return entered, free, np.concatenate([world.positions[0], world.velocities[0]])


def test_a_free_bottle_crosses_the_light_barrier_at_the_tick_the_engine_driven_one_does():
    engine_tick, was_free, engine_end = crossing("engine")
    free_tick, is_free, free_end = crossing("free")
    assert not was_free and is_free              # the second crossed it in free transport
    # Within one tick (the stated tolerance): the engine adds only its rocking and sink.
    assert abs(free_tick - engine_tick) <= 1
    assert free_tick == engine_tick              # and here exactly
    assert np.abs(free_end[:2] - engine_end[:2]).max() < 1e-3          # m, after 3 s at 0.5 m/s
    assert np.abs(free_end[3:5] - engine_end[3:5]).max() < 1e-3        # m/s


@pytest.mark.parametrize("name, key, back", [
    ("stopper_queue", "defaults.source.transport", True),   # a queue at a closed stopper, a sink
    ("switch", "defaults.bottle.transport", True),          # a switch's blade
    ("source_sink", "defaults.source.transport", False),    # put down by a source, taken by sinks while free
    ("pusher", "defaults.bottle.transport", True),          # a pusher's plate
])
def test_free_bottles_come_back_before_anything_touches_them(name, key, back):
    """…and the scene ends as it does with the engine moving every bottle: the same bottles
    taken by the same sinks, the others within 1 cm of where they stand then."""
    ends = {}
    for transport in ("engine", "free"):
        scenario = load_scenario(SCENARIOS / f"{name}.yaml", {key: transport})
        with Run(scenario) as run:
            run.start()
            world = run.plant.world
            world.check_free = world.check_rest = True   # the engine's word at every tick
            run.run()
            on_stage = world.bodies.in_play_rows()
            ends[transport] = (sorted(world.bodies.parked), world.positions[on_stage].copy(), world.transport.entered,
                               world.transport.left)
    (parked, stand, _, _), (free_parked, free_stand, entered, left) = ends["engine"], ends["free"]
    assert entered > 0 and (left > 0) == back
    assert free_parked == parked
    assert np.abs(free_stand - stand).max(initial=0.0) < 0.01


def belts_world(fast: float, slow: float, k_slow: float = 16.0) -> PhysicsWorld:
    """A fast belt (x ∈ [0, 1)) handing over to a slow one (x ∈ [1, 3), rate `k_slow`), floors
    merged, rails either side 5 cm from the centre line."""
    world = PhysicsWorld(150)
    world.check_free = world.check_rest = True
    world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
    for x0, length, speed, k in ((0.0, 1.0, fast, 16.0), (1.0, 2.0, slow, k_slow)):
        world.add_belt_field(Straight(Pose(x0, 0.0, 0.0, 0.0), length), 0.05, -0.02, 0.1, k, speed)
    for side in (1, -1):
        world.add_static_box((1.5, side * 0.06, 0.04), (1.5, 0.01, 0.04))
    return world


def test_a_free_bottle_comes_back_before_it_catches_up_with_another_free_one():
    # The slow belt grips weakly (k = 2/s): the one behind comes onto it at 0.5 m/s and slows
    # over ~20 cm, catching up with the one ahead, which rides at 0.1 m/s.
    with belts_world(0.5, 0.1, k_slow=2.0) as world:
        front = world.add_bottle((1.05, 0, 0), 0.03, 0.1, 0.05, "front", transport="free")
        back = world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "back", transport="free")
        both_free = False
        for _ in range(750):
            world.step(1)
            both_free |= bool(world.transport.free[[front, back]].all())
        assert both_free                                  # they rode free together
        assert not world.transport.free[back]             # and the one that caught up came back
        gap = world.positions[front, 0] - world.positions[back, 0]
        assert 0.058 < gap < 0.065                        # it rides behind the other, touching


def test_free_transport_is_bit_identical_in_two_runs():
    def run():
        with belts_world(0.5, 0.2) as world:
            for k in range(6):
                world.add_bottle((0.05 + 0.15 * k, 0, 0), 0.03, 0.1, 0.05, f"b{k}", transport="free")
            states = []
            for _ in range(40):
                world.step(15)
                states.append(np.concatenate([world.positions.ravel(), world.velocities.ravel()]))
            return np.array(states), world.transport.entered
    (a, entered), (b, _) = run(), run()
    assert entered > 0
    assert a.tobytes() == b.tobytes()


def test_a_hull_or_two_body_bottle_stays_in_the_engine_and_a_wrong_transport_is_named(tmp_path):
    # Free is the default; what free transport cannot move (a hull, the paper's two bodies) rides in the engine.
    for more, free in (({"objects.bottle.shape": "hull"}, False), ({"objects.bottle.model": "base_body"}, False),
                       ({}, True)):
        with Run(load_scenario(SCENARIOS / "belt_bottle_sensor.yaml", more)) as run:
            run.start()
            world = run.plant.world
            world.step(150)
            assert world.velocities[0, 0] > 0.4 and bool(world.transport.free[0]) is free, more
    path = tmp_path / "old.yaml"
    path.write_text("planthub: 1\nname: old\nrun: {duration: 1.0}\nobjects:\n"
                    "  b: {module: bottle, position: [0, 0, 0], transport: exact}\n")
    with pytest.raises(ScenarioError, match=r"old\.yaml:5.*objects\.b\.transport.*'exact' is not one of \['free', 'engine'\]"):
        load_scenario(path)
    with PhysicsWorld(150) as world, pytest.raises(ValueError, match="transport must be free or engine, not 'exact'"):
        world.add_bottle((0, 0, 0), 0.03, 0.1, 0.05, "b", transport="exact")
    with PhysicsWorld(150) as world, pytest.raises(ValueError, match="look-ahead must be a whole number of ticks, at least 2"):
        world.add_bottle((0, 0, 0), 0.03, 0.1, 0.05, "b", transport="free", lookahead=1)


def magazine(transport: str, spacing: float = 0.1):
    """A line of five bottles `spacing` apart (4 cm gaps by default; 0.06: each touching the
    next) resting on a stopped belt between rails (gripping with friction, μ = 0.3, as the
    bottling plant's magazine does), which then runs for 1 s at 0.5 m/s and stops: (the world's
    positions after each phase, the world), the engine asked at every tick about every resting
    and free bottle."""
    world = PhysicsWorld(150)
    world.check_free = world.check_rest = True
    world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
    belt = world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.0, friction=0.3)
    for side in (1, -1):
        world.add_static_box((1.5, side * 0.06, 0.04), (1.5, 0.01, 0.04))
    for k in range(5):
        world.add_bottle((0.2 + spacing * k, 0, 0), 0.03, 0.1, 0.05, f"b{k}", transport=transport)
    ends = []
    world.step(60)
    ends.append(world.positions.copy())
    world.set_field_speed(belt, 0.5)
    world.step(150)
    ends.append(world.positions.copy())
    world.set_field_speed(belt, 0.0)
    world.step(150)
    ends.append(world.positions.copy())
    return ends, world


def test_a_resting_line_rides_off_free_when_its_belt_starts_and_rests_again_without_the_engine():
    (_, engine_run, engine_end), engine = magazine("engine")
    engine.close()
    (rested, running, end), world = magazine("free")
    with world:
        t = world.transport
        assert t.started == 5 and t.stopped == 5     # from rest to free and back, each bottle once
        assert t.entered == 0 and t.left == 0         # never through the engine
        assert world.rest.resting.all()
        # A line setting off together stays a line: the same law for each, to rounding.
        gaps = np.diff(running[:, 0])
        assert np.abs(gaps - np.diff(rested[:, 0])).max() < 1e-12
        # Against the engine moving them all the way: within a millimetre, after 1 s and the stop.
        assert np.abs(running[:, :2] - engine_run[:, :2]).max() < 1e-3
        assert np.abs(end[:, :2] - engine_end[:, :2]).max() < 1e-3


def test_a_bottle_setting_off_between_rails_is_pulled_along_them_not_into_them():
    # Its look at the rails sees the pull along the belt (2 cm from each rail): it goes free at once.
    with PhysicsWorld(150) as world:
        world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
        belt = world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.0,
                                    friction=0.3)
        for side in (1, -1):
            world.add_static_box((1.5, side * 0.06, 0.04), (1.5, 0.01, 0.04))
        world.check_free = world.check_rest = True
        row = world.add_bottle((0.5, 0, 0), 0.03, 0.1, 0.05, "b", transport="free")
        world.step(60)
        assert world.rest.resting[row]
        world.set_field_speed(belt, 0.5)
        assert world.transport.free[row]
        world.step(30)
        assert world.transport.free[row] and world.velocities[row, 0] > 0.4


@pytest.mark.parametrize("slow", [0.0, 0.1])
@pytest.mark.parametrize("ahead, gap, lead", [(4, 0.01, 0.3), (4, 0.01, 0.33), (4, 0.02, 0.3), (6, 0.02, 0.3),
                                               (6, 0.03, 0.33)])
def test_two_free_bottles_where_the_first_crosses_onto_a_slower_belt_come_back_before_they_touch(slow, ahead, gap,
                                                                                                lead):
    # The first is pulled harder once over the hand-over: a look taken before must not hold
    # past it (found by review: both were still free when they touched, with looks that took
    # the pull each had on the fast belt). At the default look-ahead (6) a pair 1 cm apart does
    # not both go free: its take-free look goes 12 ticks forward.
    with belts_world(0.5, slow) as world:
        world.check_rest = False
        first = world.add_bottle((lead, 0, 0), 0.03, 0.1, 0.05, "lead", transport="free", lookahead=ahead)
        second = world.add_bottle((lead - 0.06 - gap, 0, 0), 0.03, 0.1, 0.05, "back", transport="free",
                                  lookahead=ahead)
        both_free = False
        for _ in range(400):
            world.step(1)                              # check_free: the engine's word at every tick
            both_free |= bool(world.transport.free[[first, second]].all())
        assert both_free and world.transport.left >= 1


@pytest.mark.parametrize("distance", [0.014, 0.02, 0.028])
def test_a_free_bottle_comes_back_before_a_wall_when_its_belt_speeds_up(distance):
    # At the speed change the bottle's pull is the one at the new speed (found by review: it
    # was the last tick's, at the old speed, and a look four look-aheads forward let it hit the wall).
    with PhysicsWorld(150) as world:
        world.check_free = world.check_rest = True
        world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
        belt = world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.1)
        world.add_static_box((1.01, 0.0, 0.04), (0.01, 0.07, 0.04))   # a wall across the belt, its face at x = 1
        row = world.add_bottle((0.7, 0, 0), 0.03, 0.1, 0.05, "b", transport="free")
        world.step(1)
        while world.positions[row, 0] + 0.03 < 1.0 - distance:
            world.step(1)
        assert world.transport.free[row]
        world.set_field_speed(belt, 0.5)
        world.step(60)
        assert not world.transport.free[row] and world.positions[row, 0] + 0.03 <= 1.0 + 1e-3


def test_a_queue_standing_touching_rides_off_free_as_a_train_and_rests_again_without_the_engine():
    # Each bottle touches the next (the bottling plant's magazine stands in touching pairs): one
    # law at one velocity, bit for bit, moves them alike, so they ride free touching.
    (_, engine_run, engine_end), engine = magazine("engine", spacing=0.06)
    engine.close()
    (rested, running, end), world = magazine("free", spacing=0.06)
    with world:
        t = world.transport
        assert t.started == 5 and t.stopped == 5 and t.entered == 0 and t.left == 0
        assert np.abs(np.diff(running[:, 0]) - np.diff(rested[:, 0])).max() < 1e-12
        assert np.abs(running[:, :2] - engine_run[:, :2]).max() < 1e-3
        assert np.abs(end[:, :2] - engine_end[:, :2]).max() < 1e-3


def rail_world() -> PhysicsWorld:
    """A belt at 0.5 m/s along x between rails whose inner faces are 5 cm from its centre line,
    and a wall across it at x = 1.5."""
    world = PhysicsWorld(150)
    world.check_free = world.check_rest = True
    world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
    world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.5)
    for side in (1, -1):
        world.add_static_box((1.5, side * 0.06, 0.04), (1.5, 0.01, 0.04))
    world.add_static_box((1.51, 0.0, 0.04), (0.01, 0.05, 0.04))
    return world


def test_a_train_comes_back_into_the_engine_whole():
    # Three touching bottles set off from rest as a train towards the wall: the first comes back
    # before it reaches the wall, and the two touching it with it, at the same tick.
    with rail_world() as world:
        belt = 0
        world.set_field_speed(belt, 0.0)
        rows = [world.add_bottle((0.8 + 0.06 * k, 0, 0), 0.03, 0.1, 0.05, f"b{k}", transport="free")
                for k in range(3)]
        world.step(60)
        assert world.rest.resting[rows].all()
        world.set_field_speed(belt, 0.5)
        assert world.transport.free[rows].all()
        seen = set()
        for _ in range(200):
            world.step(1)        # check_free: the engine's word at every tick
            seen.add(tuple(world.transport.free[rows].tolist()))
        assert seen == {(True, True, True), (False, False, False)}
        assert world.positions[rows[-1], 0] + 0.03 <= 1.5 + 1e-3


def test_a_bottle_riding_against_a_guard_rail_slides_along_it_free():
    # Put down 0.1 mm from the rail, the belt's law takes it along the rail and never into it.
    ends = {}
    for transport in ("engine", "free"):
        with rail_world() as world:
            row = world.add_bottle((0.2, 0.0199, 0), 0.03, 0.1, 0.05, "b", transport=transport)
            free = 0
            for _ in range(150):
                world.step(1)    # check_free: it may touch the rail, no deeper than when it went free
                free += bool(world.transport.free[row])
            ends[transport] = (world.positions[row].copy(), free, world.transport.entered)
    (engine_end, _, _), (end, free, entered) = ends["engine"], ends["free"]
    assert entered == 1 and free > 100           # free from soon after it got going, to the end
    assert np.abs(end[:2] - engine_end[:2]).max() < 1e-3


def test_check_free_names_a_free_bottle_pressed_into_a_rail_or_into_its_train():
    # The allowances above are narrow: a train at one velocity, a rail no deeper than before.
    (_, _, _), world = magazine("free", spacing=0.06)
    with world:
        t, floors = world.transport, world.engine.floors
        fixed = world.engine.fixed_bodies()
        world.set_field_speed(0, 0.5)
        world.step(30)
        rows = t.rows
        assert len(rows) == 5
        world.velocities[rows[0], 0] += 1e-3          # one of the train no longer at the others' velocity
        with pytest.raises(RuntimeError, match=r"free bottles b0 and b1 touch"):
            t.check(world.tick, floors, fixed)
    with rail_world() as world:
        row = world.add_bottle((0.2, 0.0199, 0), 0.03, 0.1, 0.05, "b", transport="free")
        world.step(100)
        assert world.transport.free[row]
        world.positions[row, 1] += 0.001              # a millimetre into the rail
        with pytest.raises(RuntimeError, match=r"b is in free transport but touches body"):
            world.transport.check(world.tick, world.engine.floors, world.engine.fixed_bodies())


def plain_belt(world: PhysicsWorld, z: float = 0.0) -> int:
    """A 3 m belt at 0.5 m/s along x at height `z`, its floor under it."""
    world.add_support(z, (0.0, -0.07, 3.0, 0.07))
    return world.add_belt_field(Straight(Pose(0.0, 0.0, z, 0.0), 3.0), 0.05, z - 0.02, z + 0.1, 16.0, 0.5)


def test_a_bottle_deep_in_an_open_gate_does_not_slide_along_it_when_it_closes():
    # Found by review: a bottle 1 cm into a box that was not solid went free "sliding" along it,
    # and rode on inside it once it turned solid. It stays in the engine, which pushes it out.
    with PhysicsWorld(150) as world:
        world.check_free = world.check_rest = True
        plain_belt(world)
        row = world.add_bottle((0.05, 0, 0), 0.03, 0.1, 0.05, "a", transport="free")
        part = world.add_switchable_boxes([(1.0, 0.035, 0.04)], [(0.9, 0.015, 0.04)], [0.0], solid=False)
        world.step(150)
        world.set_solid(part, True)
        world.step(90)
        assert world.positions[row, 1] + 0.03 <= 0.02 + 5e-4     # out of the box (its face at y = 0.02)


def test_a_bottle_falling_onto_a_free_one_brings_it_back_first():
    # Found by review: two upright bottles one above the other counted as apart whatever their
    # vertical speeds; a falling one is not steady, and heights close by what falling can close.
    with PhysicsWorld(150) as world:
        world.check_free = world.check_rest = True     # the engine's word at every tick
        plain_belt(world)
        below = world.add_bottle((0.05, 0, 0), 0.03, 0.1, 0.05, "below", transport="free")
        world.add_bottle((0.105, 0, 0.3), 0.03, 0.1, 0.05, "above", transport="engine")
        world.step(60)
        assert world.transport.entered >= 1 and not world.transport.free[below]


def test_a_bottle_put_onto_a_belt_above_lists_the_boxes_up_there():
    # Found by review: a bottle's list of fixed boxes was refreshed only when it had moved across,
    # so one put on the belt above where it was listed rode free into a stopper up there.
    with PhysicsWorld(150) as world:
        world.check_free = world.check_rest = True
        plain_belt(world)
        plain_belt(world, 0.3)
        world.add_static_box((0.29, 0.0, 0.34), (0.01, 0.07, 0.04))   # a stopper on the upper belt, its face at 0.28
        row = world.add_bottle((0.05, 0, 0), 0.03, 0.1, 0.05, "a", transport="free")
        world.step(90)
        assert world.transport.free[row]
        world.park(row)
        world.unpark(row, (0.20, 0.0, 0.3))
        world.step(60)
        assert world.positions[row, 0] + 0.03 <= 0.28 + 1e-3


def spun_or_thrown(world: PhysicsWorld, row: int, velocity=(0.0, 0.0, 0.0), spin=(0.0, 0.0, 0.0)) -> None:
    """Give a bottle in the engine a velocity and a spin (read back at the next tick)."""
    world.start()
    world.engine.call(pybullet.resetBaseVelocity, world.bodies.ids[row], list(velocity), list(spin))


@pytest.mark.parametrize("lead", [0.2, 0.25, 0.3])
def test_a_free_bottle_comes_back_before_a_bottle_thrown_in_the_engine_reaches_it(lead):
    # Between two whole looks a free bottle is looked at against the bodies awake in the engine
    # only: one thrown after it along a weak belt (k = 2/s keeps it fast) must bring it back.
    with PhysicsWorld(150) as world:
        world.check_free = world.check_rest = True     # the engine's word at every tick
        world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
        world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 2.0, 0.5)
        ahead = world.add_bottle((lead, 0, 0), 0.03, 0.1, 0.05, "ahead", transport="free")
        thrown = world.add_bottle((0.05, 0, 0), 0.03, 0.1, 0.05, "thrown", transport="engine")
        world.step(90)
        assert world.transport.free[ahead] and not world.transport.free[thrown]
        spun_or_thrown(world, thrown, velocity=(3.0, 0.0, 0.0))
        world.step(90)
        assert world.transport.left >= 1                # it came back (check_free: before it was hit)


@pytest.mark.parametrize("spin, goes_free", [(0.0, True), (4.0, False)])
def test_a_bottle_spinning_on_a_belt_stays_in_the_engine(spin, goes_free):
    # The paper's `along` grip leaves a frictionless bottle's spin alone: one spinning faster than
    # a riding bottle does (SPIN) never leaves the engine; the same bottle not spinning does.
    with PhysicsWorld(150) as world:
        world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
        world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.5, grip="along")
        row = world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "b", transport="free")
        spun_or_thrown(world, row, spin=(0.0, 0.0, spin))
        world.step(120)
        assert bool(world.transport.entered) == goes_free
        assert goes_free or abs(world.angular_velocities[row, 2]) > 3.0


@pytest.mark.parametrize("speed, start", [(0.5, 0.27), (1.0, 0.2), (1.5, 0.27)])
def test_a_fast_free_bottle_comes_back_before_a_thin_closed_gate_across_its_belt(speed, start):
    """Its way over a long look (24 ticks: 8 cm at 0.5 m/s) is longer than it is wide: both ends of
    it may lie clear of a 5 mm gate it crosses, and a box listed LIST/2 back may be out of the list.
    Before transport._segment_gap saw a way crossing a box, and _fixed_hit tested such ways against
    every box, check_free found these three bottles in the gate (tests/physics/test_kernels.py)."""
    with PhysicsWorld(150) as world:
        world.check_free = True
        world.add_support(0.0, (0.0, -0.1, 3.0, 0.1))
        world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.08, -0.02, 0.1, 16.0, speed)
        world.add_switchable_boxes([(1.5, 0.0, 0.05)], [(0.0025, 0.1, 0.05)], [0.0], solid=True)
        bottle = world.add_bottle((start, 0, 0), 0.03, 0.1, 0.05, "b", transport="free")
        world.step(int(150 * 1.6 / speed))
        t = world.transport
        assert t.entered == 1 and t.left == 1 and not t.free[bottle]     # rode free, came back, held at the gate
        assert world.positions[bottle, 0] == pytest.approx(1.5 - 0.0025 - 0.03, abs=0.001)


def test_a_body_no_part_declared_keeps_a_free_bottle_coming_near_it_in_the_engine():
    """A body made in the engine by a primitive that tells free transport nothing (here, boxes made
    straight in the engine across the belt, 1 m ahead) is kept clear of as a fixed box is, by its
    bounding box: the bottle rides free up to it, comes back into the engine before it and stops
    there against it; never touches it while free (the engine asked at every tick)."""
    with PhysicsWorld(150) as world:
        world.check_free = True
        plain_belt(world)
        row = world.add_bottle((0.2, 0, 0), 0.03, 0.1, 0.05, "b", transport="free")
        wall = world.engine.boxes_body([(1.2, 0.0, 0.05)], [(0.01, 0.1, 0.05)], [0.0])
        assert wall not in world.engine.fixed_bodies()    # declared by no part of the world
        world.step(150)
        assert world.transport.free[row]               # free on the open belt
        world.step(450)                                # check_free: touching the wall while free is an error
        assert not world.transport.free[row] and world.transport.left >= 1
        face = 1.2 - 0.01 - 0.03
        assert face - 0.005 < world.positions[row, 0] < face + 0.001   # stopped by it, in the engine
