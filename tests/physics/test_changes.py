"""One registration for what the plant changes (hub/physics/changes.py): every part announces its
change through the world, every level of detail that listens hears every kind of change, and no
part tells a level of detail by hand any more (so a new one registered the same way misses nothing)."""
import ast
from pathlib import Path

import numpy as np

from hub.physics import PhysicsWorld
from hub.physics.changes import KINDS, BeltSpeed, Changes
from hub.physics.frames import Pose, Straight
from hub.physics.moving import Leg

ROOT = Path(__file__).resolve().parents[2]
RATE = 150


class Heard:
    """A new level of detail, registered as free transport and sleep are: it only writes down."""

    def __init__(self):
        self.kinds = []

    def hear(self, change):
        self.kinds.append(type(change))


def test_a_level_of_detail_registered_on_the_world_hears_every_kind_of_change():
    with PhysicsWorld(RATE) as world:
        heard = Heard()
        world.changes.listen(heard)
        world.add_static_box((0.5, 0, -0.01), (1.0, 1.0, 0.01))
        belt = world.add_force_field((0.5, 0, 0.15), (1.0, 0.3, 0.15), 0.0, 16.0, 0.0)
        gate = world.add_switchable_boxes([(0.9, 0.0, 0.05)], [(0.005, 0.1, 0.05)], [0.0], solid=True)
        plate = world.add_moving_boxes([(0.5, -0.2, 0.04)], [(0.06, 0.005, 0.04)], [0.0], axis=(0, 1, 0))
        arm = world.add_arm((0.3, 0.5, 0.0), 0.0, 0.1)
        bottles = [world.add_bottle((0.2 + 0.1 * i, 0, 0), 0.03, 0.1, 0.05, f"b{i}", transport="free")
                   for i in range(4)]
        world.step(30)                          # they come to rest on the still belt
        heard.kinds.clear()                     # building announced the gate's first state
        world.set_field_speed(belt, 0.2)
        world.set_solid(gate, False)
        plate.move(world.tick, [Leg(0.05, 0.5)])
        world.step(2)
        world.grip(arm, bottles[0])
        world.release(arm)
        world.park(bottles[1])
        world.unpark(bottles[1], (0.6, 0.3, 0.0))
        world.tip(bottles[2], 0.0)
        assert set(heard.kinds) == set(KINDS)


def test_every_listener_hears_every_change_in_the_order_they_registered():
    changes, order = Changes(), []

    class Listener:
        def __init__(self, name):
            self.name = name

        def hear(self, change):
            order.append((self.name, change.field))

    changes.listen(Listener("first"))
    changes.listen(Listener("second"))
    changes.announce(BeltSpeed(3, 0.5))
    assert order == [("first", 3), ("second", 3)]


# What a level of detail is told on a change. Only the levels of detail themselves (and the
# announcement) call these on one another: any other part of the physics or a module announces.
HOOKS = {"transport": {"release", "look_whole", "from_rest", "forget", "hear"},
         "sleep": {"wake", "wake_in", "hear"},
         "rest": {"forget", "wake", "on_field", "joining", "put"}}
OWNERS = {"hub/physics/transport.py", "hub/physics/sleep.py", "hub/physics/rest.py", "hub/physics/changes.py"}


def _told_by_hand(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            owner = node.func.value
            name = owner.attr if isinstance(owner, ast.Attribute) else owner.id if isinstance(owner, ast.Name) else ""
            if node.func.attr in HOOKS.get(name, ()):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {name}.{node.func.attr}(…)")
    return found


def test_no_part_of_the_physics_and_no_module_tells_a_level_of_detail_by_hand():
    files = sorted((ROOT / "hub" / "physics").glob("*.py")) + sorted((ROOT / "modules").rglob("*.py"))
    found = [hit for path in files if str(path.relative_to(ROOT)) not in OWNERS for hit in _told_by_hand(path)]
    assert found == [], "announce a change (world.announce, hub/physics/changes.py) instead:\n" + "\n".join(found)


def test_the_walk_finds_a_call_by_hand(tmp_path):
    """The walk above is not vacuous: the direct calls set_field_speed made before are found."""
    old = ROOT / "tests" / "physics" / "_old.py"
    try:
        old.write_text("def set_field_speed(self, field):\n    self.transport.look_whole()\n"
                       "    rows = self.rest.on_field(field, self.bodies.positions)\n    self.sleep.wake(rows)\n")
        assert [hit.split(": ")[1] for hit in _told_by_hand(old)] == [
            "transport.look_whole(…)", "rest.on_field(…)", "sleep.wake(…)"]
    finally:
        old.unlink()


def test_a_belt_start_wakes_its_resting_bottles_or_lets_them_ride_off_free():
    """The hand-off one announcement makes: free transport, heard first, takes off free those of
    the resting bottles that may ride free; sleep wakes the others."""
    with PhysicsWorld(RATE) as world:
        world.add_support(0.0, (0.0, -0.1, 2.0, 0.1))
        belt = world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 2.0), 0.08, -0.02, 0.1, 16.0, 0.0)
        free = world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "free", transport="free")
        engine = world.add_bottle((0.6, 0, 0), 0.03, 0.1, 0.05, "engine", transport="engine")
        world.step(30)
        assert world.rest.resting[[free, engine]].all()
        changes = []
        world.changes.listen(type("Last", (), {"hear": lambda self, change: changes.append(change)})())
        world.set_field_speed(belt, 0.3)
        assert [type(c) for c in changes] == [BeltSpeed] and list(changes[0].woken) == [engine]   # left to wake
        assert world.transport.free[free] and not world.rest.resting[[free, engine]].any()
        assert np.isfinite(world.positions).all()
