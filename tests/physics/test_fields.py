"""The belt force field: exact exponential velocity update, stable at any k·dt."""
import math

import numpy as np
import pybullet
import pytest

from hub.physics import PhysicsWorld
from hub.physics.fields import ForceFields
from hub.physics.frames import Pose, Straight


def drive(k, dt, steps, speed=0.5, mass=0.05, v0=0.0, integrator="exact"):
    """Integrate one free body under the field alone, as the physics engine would (v += F/m·dt)."""
    fields = ForceFields(dt, integrator)
    fields.add((0, 0, 0), (10, 10, 10), 0.0, k, speed)
    v = np.array([[v0, 0.0, 0.0]])
    history = []
    for _ in range(steps):
        bodies, forces = fields.forces(np.zeros((1, 3)), v, np.array([mass]))
        v = v + forces / mass * dt
        history.append(v[0, 0])
    return np.array(history)


@pytest.mark.parametrize("k, rate", [(1, 150), (16, 60), (16, 150), (16, 1000), (300, 60)])
def test_velocity_follows_the_analytical_curve_at_every_tick(k, rate):
    dt = 1.0 / rate
    v = drive(k, dt, rate * 2)
    t = dt * np.arange(1, len(v) + 1)
    np.testing.assert_allclose(v, 0.5 * (1 - np.exp(-k * t)), rtol=1e-12, atol=1e-15)


def test_stable_and_without_overshoot_where_explicit_euler_diverges():
    k, dt = 400.0, 1.0 / 60      # k·dt ≈ 6.7; the explicit update's factor |1 − k·dt| > 1
    v = drive(k, dt, 200, v0=-3.0)
    assert np.all(np.diff(v) >= 0) and np.all(v <= 0.5)
    assert v[-1] == pytest.approx(0.5, abs=1e-12)


def test_the_explicit_law_is_the_papers_euler_step_and_diverges_past_k_dt_2():
    """`integrator: explicit` (for comparison only): each tick v += k·dt·(v_tar − v), so the error
    shrinks by 1 − k·dt: first-order close to the exact curve for small k·dt, overshooting between
    1 and 2, growing beyond."""
    dt = 1 / 150
    v = drive(16.0, dt, 300, integrator="explicit")
    n = np.arange(1, 301)
    np.testing.assert_allclose(v, 0.5 * (1 - (1 - 16.0 * dt) ** n), rtol=1e-12)
    exact = 0.5 * (1 - np.exp(-16.0 * dt * n))
    assert 0 < np.max(v - exact) < 0.5 * 16.0 * dt * 0.5   # ahead of the exact curve, by O(k·dt)
    overshoot = drive(225.0, dt, 20, integrator="explicit")   # k·dt = 1.5
    assert overshoot[0] > 0.5 and abs(overshoot[-1] - 0.5) < 1e-3
    grows = drive(450.0, dt, 20, integrator="explicit")       # k·dt = 3: the error doubles every tick
    assert abs(grows[-1] - 0.5) == pytest.approx(0.5 * 2.0 ** 20, rel=1e-9)


def test_an_unknown_integrator_is_refused():
    with pytest.raises(ValueError, match="integrator must be one of exact, explicit, not 'implicit'"):
        ForceFields(1 / 150, "implicit")


def test_force_scales_with_mass_so_every_bottle_accelerates_alike():
    fields = ForceFields(1 / 150)
    fields.add((0, 0, 0), (1, 1, 1), 0.0, 16.0, 0.5)
    _, forces = fields.forces(np.zeros((2, 3)), np.zeros((2, 3)), np.array([0.02, 0.08]))
    assert forces[1, 0] == pytest.approx(4 * forces[0, 0])


def test_only_the_component_along_the_belt_is_driven():
    yaw = math.radians(30)
    fields = ForceFields(1 / 150)
    fields.add((0, 0, 0), (1, 1, 1), yaw, 16.0, 0.5)
    sideways = np.array([[-math.sin(yaw), math.cos(yaw), 0.0]])   # across the belt
    _, forces = fields.forces(np.zeros((1, 3)), sideways * 0.3, np.array([1.0]))
    direction = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    assert np.cross(forces[0], direction) == pytest.approx(np.zeros(3), abs=1e-12)
    assert forces[0] @ direction > 0


def test_bodies_outside_every_field_get_no_force_and_the_first_field_wins():
    fields = ForceFields(1 / 150)
    fields.add((0, 0, 0), (1, 1, 1), 0.0, 16.0, 0.5)
    fields.add((1.5, 0, 0), (1, 1, 1), math.pi, 16.0, 0.5)   # overlaps the first for 0.5 <= x <= 1
    positions = np.array([[0.8, 0, 0], [2.0, 0, 0], [5.0, 0, 0]])
    bodies, forces = fields.forces(positions, np.zeros((3, 3)), np.ones(3))
    assert bodies.tolist() == [0, 1]
    assert forces[0, 0] > 0 and forces[1, 0] < 0


def test_friction_caps_the_acceleration_and_the_exact_update_takes_over_below_it():
    """A belt with friction μ accelerates a bottle by at most μ·g: from rest on a 0.5 m/s belt
    (k = 16/s would give 8 m/s²) at μ·g until the exact update asks for less, then exactly as
    without the cap."""
    dt, k, mu, g = 1 / 150, 16.0, 0.2, 9.81
    fields = ForceFields(dt)
    fields.add_region(Straight(Pose(0, 0, 0, 0), 10), 1.0, -1, 1, k, 0.5, limit=mu * g)
    v, history = np.zeros((1, 3)), []
    for _ in range(150):
        _, forces = fields.forces(np.zeros((1, 3)), v, np.array([0.05]))
        history.append(forces[0, 0] / 0.05)
        v = v + forces / 0.05 * dt
    a = np.array(history)
    assert a.max() == pytest.approx(mu * g, rel=1e-12)
    capped = int(np.sum(np.isclose(a, mu * g, rtol=1e-12)))
    # While capped the speed grows linearly; the first uncapped tick relaxes the rest exactly.
    assert 10 < capped < 35
    assert np.all(a[capped:] < mu * g)
    assert a[capped + 1] == pytest.approx(a[capped] * math.exp(-k * dt), rel=1e-9)
    assert v[0, 0] == pytest.approx(0.5, abs=1e-6)


def test_a_held_bottle_is_pushed_by_friction_alone_whatever_the_direction():
    fields = ForceFields(1 / 150)
    fields.add_region(Straight(Pose(0, 0, 0, 0.3), 10), 1.0, -1, 1, 16.0, 0.5, limit=0.1 * 9.81)
    _, forces = fields.forces(np.zeros((1, 3)), np.array([[0.0, -0.2, 0.0]]), np.array([0.08]))
    assert np.hypot(*forces[0, :2]) == pytest.approx(0.08 * 0.1 * 9.81, rel=1e-12)


def test_the_surface_grips_a_spinning_base():
    """The spin about the vertical decays exactly at the field's rate, capped by the friction
    over the base, (2/3)·μ·m·g·r, on straights and curves alike; the paper's `along` grip does
    not touch it, nor is a spin under SPIN_AT_REST touched."""
    from hub.physics.fields import SPIN_AT_REST
    from hub.physics.frames import Arc

    dt, k, m, r = 1 / 150, 16.0, 0.05, 0.03
    fields = ForceFields(dt)
    fields.add_region(Straight(Pose(0, 0, 0, 0), 10), 1.0, -1, 1, k, 0.5)
    fields.add_region(Straight(Pose(0, 5, 0, 0), 10), 1.0, -1, 1, k, 0.5, limit=0.1 * 9.81)
    fields.add_region(Arc(Pose(0, 10, 0, 0), 0.5, math.pi / 2, 1), 0.1, -1, 1, k, 0.5)
    fields.add_region(Straight(Pose(0, 20, 0, 0), 10), 1.0, -1, 1, k, 0.5, grip="along")
    f, masses, radii = np.array([0, 1, 2, 3]), np.full(4, m), np.full(4, r)
    torques = fields.spin_torques(f, np.array([5.0, 5.0, -2.0, 5.0]), masses, radii)
    inertia = m * r * r / 2
    assert torques[0] == pytest.approx(-inertia * 5.0 * (1 - math.exp(-k * dt)) / dt, rel=1e-12)
    assert torques[1] == pytest.approx(-(2 / 3) * 0.1 * 9.81 * m * r, rel=1e-12)
    assert torques[2] == pytest.approx(inertia * 2.0 * (1 - math.exp(-k * dt)) / dt, rel=1e-12)
    assert torques[3] == 0.0
    slow = fields.spin_torques(f[:1], np.array([SPIN_AT_REST / 2]), masses[:1], radii[:1])
    assert slow[0] == 0.0


def test_a_region_added_after_a_lookup_is_found_and_a_tie_goes_to_the_first_declared():
    """The compiled loops take the regions as one table, made again when a region is added; of
    two regions with the same centre line the first declared drives the body."""
    fields = ForceFields(1 / 150)
    fields.add_region(Straight(Pose(0, 0, 0, 0), 1.0), 0.1, -1, 1, 16.0, 0.5)
    points = np.array([[0.5, 0.0, 0.0], [2.5, 0.0, 0.0]])
    assert fields.which(points).tolist() == [0, -1]
    fields.add_region(Straight(Pose(2, 0, 0, 0), 1.0), 0.1, -1, 1, 16.0, 0.5)
    fields.add_region(Straight(Pose(2, 0, 0, 0), 1.0), 0.1, -1, 1, 16.0, -0.5)
    assert fields.which(points).tolist() == [0, 1]
    _, forces = fields.forces(points[1:], np.zeros((1, 3)), np.array([0.05]))
    assert forces[0, 0] > 0.0          # region 1's speed (+0.5), not region 2's


def test_a_spinning_bottle_in_the_engine_is_gripped_by_the_belts_surface():
    # Through the world's drive (bottles gripped at their centre): the spin decays at the belt's
    # rate; a frictionless bottle would keep it.
    with PhysicsWorld(150) as world:
        world.add_support(0.0, (0.0, -0.07, 3.0, 0.07))
        world.add_belt_field(Straight(Pose(0.0, 0.0, 0.0, 0.0), 3.0), 0.05, -0.02, 0.1, 16.0, 0.5)
        row = world.add_bottle((0.3, 0, 0), 0.03, 0.1, 0.05, "b")
        world.start()
        world.engine.call(pybullet.resetBaseVelocity, world.bodies.ids[row], [0.0, 0.0, 0.0], [0.0, 0.0, 5.0])
        world.step(30)
        assert abs(world.angular_velocities[row, 2]) < 5.0 * math.exp(-16.0 * 30 / 150) * 1.5
