"""Volume triggers: exact cylinder-box overlap, events latched between communication points."""
import math

import numpy as np

from hub.core import state
from hub.physics.triggers import VolumeTriggers

R, HZ = np.array([0.03]), np.array([0.05])


def at(x, y=0.0, z=0.05):
    return np.array([[x, y, z]])


def test_enter_stay_leave_in_order_with_their_ticks():
    triggers = VolumeTriggers()
    t = triggers.add((1.0, 0, 0.05), (0.0025, 0.1, 0.01), 0.0)
    seen = []
    for tick, x in enumerate(np.arange(0.9, 1.1, 0.01)):
        triggers.evaluate(tick, at(x), R, HZ)
        latch = triggers.take(t)
        seen += [("enter", tk) for tk, _ in latch.entered] + [("leave", tk) for tk, _ in latch.left]
        if latch.stayed and not latch.entered:
            seen.append(("stay", tick))
    kinds = [k for k, _ in seen]
    assert kinds[0] == "enter" and kinds[-1] == "leave" and set(kinds[1:-1]) == {"stay"}
    # The edge (x + r) reaches the beam face at 0.9975: first x on the grid with x ≥ 0.9675 is 0.97.
    assert seen[0] == ("enter", 7)
    # The rear edge (x − r) passes 1.0025 at x ≥ 1.0325, first grid point 1.04: tick 14.
    assert seen[-1] == ("leave", 14)


def test_a_pass_between_two_takes_still_gives_both_events():
    triggers = VolumeTriggers()
    t = triggers.add((1.0, 0, 0.05), (0.0025, 0.1, 0.01), 0.0)
    for tick, x in enumerate([0.9, 0.99, 1.0, 1.01, 1.1]):
        triggers.evaluate(tick, at(x), R, HZ)
    latch = triggers.take(t)
    assert latch.entered == [(1, 0)] and latch.left == [(4, 0)]
    assert latch.stayed and latch.inside == ()
    assert triggers.take(t).entered == []


def test_cylinder_overlap_is_exact_at_the_box_corner():
    triggers = VolumeTriggers()
    t = triggers.add((0, 0, 0.05), (0.1, 0.1, 0.01), 0.0)
    corner = 0.1 + 0.03 / math.sqrt(2)
    triggers.evaluate(0, at(corner - 1e-4, corner - 1e-4), R, HZ)   # touching the corner
    assert triggers.take(t).inside == (0,)
    triggers.evaluate(1, at(corner + 1e-4, corner + 1e-4), R, HZ)   # inside the bounding box only
    assert triggers.take(t).inside == ()


def test_yawed_trigger_and_height():
    triggers = VolumeTriggers()
    t = triggers.add((0, 0, 0.05), (0.0025, 0.1, 0.01), math.radians(90))   # beam along x
    triggers.evaluate(0, at(0.08, 0.0), R, HZ)
    assert triggers.take(t).inside == (0,)
    triggers.evaluate(1, at(0.0, 0.04), R, HZ)
    assert triggers.take(t).inside == ()
    triggers.evaluate(2, at(0.08, 0.0, z=0.5), R, HZ)       # flying far above the beam
    assert triggers.take(t).inside == ()


def test_several_bodies_keep_body_order():
    triggers = VolumeTriggers()
    t = triggers.add((0, 0, 0.05), (0.5, 0.1, 0.01), 0.0)
    positions = np.array([[0.3, 0, 0.05], [5, 0, 0.05], [-0.3, 0, 0.05]])
    triggers.evaluate(3, positions, np.full(3, 0.03), np.full(3, 0.05))
    latch = triggers.take(t)
    assert latch.entered == [(3, 0), (3, 2)] and latch.inside == (0, 2)


def test_the_bodies_that_moved_looked_up_near_them_give_what_every_pair_gives():
    """A floor of triggers, bottles of many widths wandering over it and an arm's trigger that
    moves now and then from half-way: a VolumeTriggers told which bodies moved (its grid of the
    triggers that never moved, each widened by the widest bottle; those that did tested against
    every moved body) latches at every tick what one that tests every pair latches, and goes on
    doing so after its state is put back."""
    rng = np.random.default_rng(7)
    n, ticks = 120, 240
    looked_up, every_pair = VolumeTriggers(), VolumeTriggers()
    for k in range(40):   # the first, the arm's, wide: bottles wander into it where it waits
        center, half = (*rng.uniform(-3, 3, 2), 0.05), (0.4, 0.4, 0.02) if k == 0 else (*rng.uniform(0.003, 0.1, 2), 0.02)
        yaw = rng.uniform(-math.pi, math.pi)
        looked_up.add(center, half, yaw)
        every_pair.add(center, half, yaw)
    radii, heights = rng.uniform(0.02, 0.2, n), np.full(n, 0.05)
    positions = np.column_stack((rng.uniform(-3, 3, (n, 2)), np.full(n, 0.05)))
    steps = rng.normal(0, 0.02, (n, 2))
    entered = 0
    for tick in range(ticks):
        if tick >= ticks // 2 and tick % 25 == 0:   # the arm's trigger goes to a bottle and waits there
            for triggers in (looked_up, every_pair):
                triggers.move(0, (positions[tick % n, 0], positions[tick % n, 1], 0.05))
        if tick == 3 * ticks // 4:
            state.restore(looked_up, state.loads(state.dumps(state.save(looked_up)), "here"))
            assert looked_up._made is None   # made again from the boxes put back
        positions[:, :2] += steps
        looked_up.evaluate(tick, positions, radii, heights, moved=np.arange(n))
        every_pair.evaluate(tick, positions, radii, heights)
        for t in range(len(looked_up)):
            a, b = looked_up.take(t), every_pair.take(t)
            assert (a.entered, a.left, a.stayed, a.inside) == (b.entered, b.left, b.stayed, b.inside), (tick, t)
            entered += len(a.entered)
    assert entered > 50 and len(looked_up._made[3]) == 39   # bodies came and went; trigger 0 is out of the grid
