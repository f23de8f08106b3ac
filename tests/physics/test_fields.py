"""The belt force field: exact exponential velocity update, stable at any k·dt."""
import math

import numpy as np
import pytest

from hub.physics.fields import ForceFields


def drive(k, dt, steps, speed=0.5, mass=0.05, v0=0.0):
    """Integrate one free body under the field alone, as the physics engine would (v += F/m·dt)."""
    fields = ForceFields(dt)
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
