"""Every net's FMU (FMI 2 and 3) gives the interpreter's outputs, step by step, on seeded random inputs."""

import random

import pytest

from .fmu_support import VERSIONS
from .petri_support import PLANT_NETS, TEST_NETS, FMURunner, PythonRunner, load

STEPS = 400
STEP_SIZES = (0.01, 0.05, 0.1, 0.1, 0.25, 0.3, 0.0)


def random_start_values(net, rng):
    values = {f"{p.name}_initial": rng.choice([p.marking, 0, 1, 2]) for p in net.places}
    values.update({f"{t.name}_delay": rng.choice([t.delay, 0.0, 0.05, 0.3, 1.0]) for t in net.delayed})
    return values


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("version", VERSIONS, ids=lambda v: f"fmi{v}")
@pytest.mark.parametrize("name", PLANT_NETS + TEST_NETS)
def test_fmu_and_interpreter_agree_step_by_step(request, open_instance, name, version, seed):
    build_dir = request.getfixturevalue("fmu_build" if name in PLANT_NETS else "net_test_build")
    net = load(name)
    rng = random.Random(f"{name}-{seed}")  # the same inputs for both FMI versions
    start_values = random_start_values(net, rng)
    density = rng.choice([0.05, 0.3, 0.6])
    python = PythonRunner(net, start_values)
    fmu = FMURunner(open_instance(build_dir / f"{name}-fmi{version}.fmu"), net, start_values)
    assert fmu.outputs() == python.outputs(), "after initialization"
    fired = set()
    for number in range(1, STEPS + 1):
        h = rng.choice(STEP_SIZES)
        put = {place.name for place in net.places if rng.random() < density}
        expected = python.step(h, put)
        assert fmu.step(h, put) == expected, f"step {number} (t = {python.time:g} s, put {sorted(put)})"
        fired.update(python.interpreter.fired)
    if net.transitions:
        assert fired, "the inputs never fired a transition: the comparison would prove little"


@pytest.mark.parametrize("name", PLANT_NETS + TEST_NETS)
def test_the_random_inputs_fire_every_transition(name):
    # Otherwise a transition's generated C would go untested by the comparison above.
    net = load(name)
    fired = set()
    for seed in (1, 2, 3):
        rng = random.Random(f"{name}-{seed}")
        python = PythonRunner(net, random_start_values(net, rng))
        density = rng.choice([0.05, 0.3, 0.6])
        for _ in range(STEPS):
            h = rng.choice(STEP_SIZES)
            python.step(h, {place.name for place in net.places if rng.random() < density})
            fired.update(python.interpreter.fired)
    assert fired == {t.name for t in net.transitions}
