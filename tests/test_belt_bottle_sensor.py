"""The shipped first scenario: the barrier's enter time against the analytical solution.

    bottle ──► [========== belt 2 m, 0.5 m/s ==========|barrier 1.5 m|=====]

A bottle at rest accelerates as v(t) = v_tar·(1 − e^(−k·t)), so its leading edge has moved
s(t) = v_tar·(t − (1 − e^(−k·t))/k) and breaks the beam when s reaches the beam's near face.
"""
import math
import subprocess
import sys

import pytest

from hub.core.errors import SimulationError
from hub.scenario.checker import load_scenario

from .helpers import ROOT, run_scenario

SCENARIO = ROOT / "scenarios" / "belt_bottle_sensor.yaml"


def analytical_enter_time(scenario) -> float:
    objects = {o.name: o.params for o in scenario.objects}
    belt, bottle, barrier = objects["belt"], objects["bottle"], objects["barrier"]
    gap = (barrier["position"][0] - barrier["size"][0] / 2) - (bottle["position"][0] + bottle["radius"])
    v, k = belt["speed"], belt["k"]
    lo, hi = 0.0, 100.0
    for _ in range(200):
        t = (lo + hi) / 2
        lo, hi = (t, hi) if v * (t - (1 - math.exp(-k * t)) / k) < gap else (lo, t)
    return hi


def enter_time(out):
    lines = (out / "events.csv").read_text().splitlines()
    enters = [line.split(",") for line in lines[1:] if ",barrier.trigger.on_enter," in line]
    assert len(enters) == 1 and enters[0][3] == "bottle"
    return float(enters[0][0])


@pytest.mark.parametrize("overrides", [
    {"run.physics_rate": 60},
    {"run.physics_rate": 150},
    {"run.physics_rate": 1000},
    # k·dt = 2.5: the explicit update of the paper's law would diverge here.
    {"run.physics_rate": 60, "objects.belt.k": 150.0},
    # A coarse communication step: the trigger's latch still gives the exact tick.
    {"run.physics_rate": 150, "run.communication_step": 0.2},
], ids=["60Hz", "150Hz", "1000Hz", "k*dt=2.5", "comm-step-0.2s"])
def test_enter_time_matches_the_analytical_value_within_one_percent(tmp_path, overrides):
    scenario, _, _ = run_scenario(SCENARIO, tmp_path, overrides)
    expected = analytical_enter_time(scenario)
    measured = enter_time(tmp_path)
    assert measured == pytest.approx(expected, rel=0.01)


def test_the_papers_explicit_law_errs_by_its_first_order_and_diverges_past_k_dt_2(tmp_path):
    """`run.integrator: explicit` (for comparison only): at 150 Hz, k·dt = 0.107, the bottle runs a
    little ahead of the exact curve (its velocity error shrinks by 1 − k·dt, not e^(−k·dt), a
    tick), so it breaks the beam a tick or two early; at k·dt = 2.5 the field throws it back and
    forth ever harder until the physics watch stops the run. The exact update (the default) holds
    at both (test above)."""
    scenario, _, _ = run_scenario(SCENARIO, tmp_path / "explicit", {"run.integrator": "explicit"})
    expected, exact = analytical_enter_time(scenario), 1 / 150
    assert -3 * exact <= enter_time(tmp_path / "explicit") - expected < 0
    with pytest.raises(SimulationError, match=r"bottle .bottle., tick \d+ .*: it moves at [\d.]+ m/s, above"):
        run_scenario(SCENARIO, tmp_path / "diverges",
                     {"run.integrator": "explicit", "run.physics_rate": 60, "objects.belt.k": 150.0})


def test_solver_iterations_reach_the_engine(tmp_path):
    from hub.run.plant import Plant
    with Plant(load_scenario(SCENARIO, {"run.solver_iterations": 7})) as plant:
        assert plant.world.engine.solver_iterations == 7


def test_bottle_stays_upright_and_on_the_belt(tmp_path):
    run_scenario(SCENARIO, tmp_path, {"run.duration": 3.5, "record": ["bottle.body.position", "bottle.body.tilt"]})
    header, *rows = (tmp_path / "recording.csv").read_text().splitlines()
    columns = [c.strip('"') for c in header.split(",")]
    y, z = columns.index("bottle.body.position.y"), columns.index("bottle.body.position.z")
    tilt = columns.index("bottle.body.tilt")
    for row in rows:
        cells = [float(c) for c in row.split(",")]
        # It rocks by under 0.6° at 150 Hz: Bullet finds the contact points of a base sliding
        # over the fixed floor anew as it slides (a bump at a seam tips it over, 90°).
        assert abs(cells[y]) < 1e-3 and cells[tilt] < 1.0
        # Bullet lets a sliding cylinder ride about 2 mm deep at 150 Hz (0.1 mm at 1000 Hz).
        assert abs(cells[z] - 0.05) < 3e-3


def test_same_scenario_twice_gives_bit_identical_recordings(tmp_path):
    run_scenario(SCENARIO, tmp_path / "a")
    run_scenario(SCENARIO, tmp_path / "b")
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_cli_run_prints_the_enter_time_in_its_summary(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "hub", "run", str(SCENARIO), "--out", str(tmp_path)],
        capture_output=True, text=True, check=True, cwd=ROOT,
    )
    expected = analytical_enter_time(load_scenario(SCENARIO))
    line = next(text for text in proc.stdout.splitlines() if "barrier.trigger.on_enter" in text)
    shown = float(line.split("first at")[1].split()[0])
    assert shown == pytest.approx(expected, rel=0.01)
    assert "real-time factor" in proc.stdout and "simulated    3.500 s" in proc.stdout
    assert proc.stderr == ""
