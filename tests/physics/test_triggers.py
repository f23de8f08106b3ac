"""Volume triggers: exact cylinder-box overlap, events latched between communication points."""
import math

import numpy as np

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
