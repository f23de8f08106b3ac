"""A stiff FMU at a 100 ms communication step: a 1 ms lag integrated inside the FMU drives a belt.

    start.clock.fire (0.5 s) ──► fast (0.4) ──► lag.logic.u ◄── slow (0.1) ◄── barrier.on_enter
    lag.logic.y ──► belt.drive.speed ──► the bottle rides to the barrier

The lag (tests/fmus/models/stiff_lag) has tau = 1 ms and integrates itself by explicit Euler with
0.1 ms steps: 1000 internal steps in one 100 ms communication step, 67 in one tick (6.67 ms).
What to expect, before measuring:

- Inside the FMU, nothing to fear: dt/tau = 0.1 is stable and monotone, and after 100 tau the
  gap is gone (0.9^1000 ~ 1e-46). For the piecewise-constant input the FMU gets, its output at
  every 100 ms point is the exact lag's to a few ulps. At one tick (6.67 tau) the gap left after
  a step is 8.9e-4 with Euler against e^(-6.67) = 1.27e-3 exact: 1.5e-4 of a 0.4 step.
- Against a one-tick communication step, the error is latency, not integration. A change of the
  input reaches the belt after the input's sample-and-hold (0 for the clock's step on the grid,
  up to h for the barrier's, which comes at whatever tick the bottle arrives) plus one
  communication step (the lag's output is sensed at the next point): h = 15 ticks against 1.
  So the bottle falls 0.4 m/s × 14 ticks = 37.33 mm behind after the step up, and the recorded
  outputs differ by the full step height at the points in between the two runs' changes.
"""
import csv
import math

import pytest

from hub.core.errors import SimulationError

from ..fmus.fmu_support import TEST_MODELS_DIR, build
from ..helpers import ROOT, run_scenario

SCENE = ROOT / "tests" / "hard" / "scenes" / "stiff_fmu.yaml"
RATE = 150
H = 15                  # ticks of the scene's 100 ms communication step
TAU = 0.001             # s, the scene's lag
HIGH, LOW = 0.4, 0.1    # the two inputs: the clock's step up, the barrier's step down
ULPS = 1e-15            # a few ulps of values below 1


@pytest.fixture(scope="module")
def lag_fmus(tmp_path_factory):
    """The stiff_lag test model built for FMI 2 and 3 (with the other models of tests/fmus/models)."""
    return build(tmp_path_factory.mktemp("stiff_lag"), models_dir=TEST_MODELS_DIR)


def run(lag_fmus, out, step_ticks=H, version=2, **overrides):
    """Run the scene; return (recording as {tick: row of floats}, events.csv rows)."""
    run_scenario(SCENE, out, {"objects.lag.file": str(lag_fmus / f"stiff_lag-fmi{version}.fmu"),
                              "run.communication_step": step_ticks / RATE, **overrides})
    with open(out / "recording.csv", newline="") as f:
        rows = {round(float(r["time"]) * RATE): {k: float(v) for k, v in r.items()} for r in csv.DictReader(f)}
    with open(out / "events.csv", newline="") as f:
        return rows, list(csv.DictReader(f))


@pytest.fixture(scope="module")
def runs(lag_fmus, tmp_path_factory):
    """The scene at its 100 ms step ("coarse") and at one tick ("fine")."""
    return {"coarse": run(lag_fmus, tmp_path_factory.mktemp("coarse")),
            "fine": run(lag_fmus, tmp_path_factory.mktemp("fine"), step_ticks=1)}


def series(rows, slot):
    return [(tick, rows[tick][slot]) for tick in sorted(rows)]


def enter_tick(events):
    (tick,) = [int(e["tick"]) for e in events if e["slot"] == "barrier.trigger.on_enter"]
    return tick


def test_the_lag_is_finite_never_overshoots_and_settles_within_one_step(runs):
    for name, step, substeps in (("coarse", H, 1000), ("fine", 1, 67)):
        rows, events = runs[name]
        ticks = sorted(rows)
        assert ticks == list(range(0, 3 * RATE + 1, step))
        y = [rows[t]["lag.logic.y"] for t in ticks]
        u = [rows[t]["lag.logic.u"] for t in ticks]
        assert all(math.isfinite(v) for v in y)
        assert {rows[t]["lag.logic.substeps"] for t in ticks[1:]} == {substeps}
        # A lag moves from where it was towards its held input and never past it: every output lies
        # between the previous output and the input of the step (within ULPS; measured: exactly).
        for k in range(len(ticks) - 1):
            assert min(y[k], u[k]) - ULPS <= y[k + 1] <= max(y[k], u[k]) + ULPS, (name, ticks[k + 1])
        assert max(y) <= HIGH + ULPS            # measured: 0.3999999999999998 (coarse), ...74 (fine)
        after_down = [rows[t]["lag.logic.y"] for t in ticks if t > enter_tick(events) + 2 * H]
        assert min(after_down) >= LOW - ULPS    # measured: 0.10000000000000006 (coarse)
        assert y[-1] == pytest.approx(LOW, abs=ULPS)
    coarse, _ = runs["coarse"]
    # Settled one 100 ms step after the step at 0.5 s: the first point after it shows the input.
    assert coarse[75]["lag.logic.y"] == 0.0
    assert coarse[90]["lag.logic.y"] == pytest.approx(HIGH, abs=ULPS)   # measured: 2.2e-16 off


def exact_lag(rows, h):
    """The analytical lag at the points for the input the FMU got: u at point k, held to k + 1."""
    ticks = sorted(rows)
    y = [rows[ticks[0]]["lag.logic.y"]]
    for t in ticks[:-1]:
        u = rows[t]["lag.logic.u"]
        y.append(u + (y[-1] - u) * math.exp(-h / TAU))
    return dict(zip(ticks, y))


def test_the_lag_at_the_points_against_the_analytical_solution(runs):
    coarse, _ = runs["coarse"]
    exact = exact_lag(coarse, H / RATE)
    error = max(abs(coarse[t]["lag.logic.y"] - exact[t]) for t in coarse)
    assert error <= ULPS                   # measured: 2.2e-16 (a few ulps: Euler's fixed point in doubles)
    # At one tick the FMU's Euler is visible in the first point after each step: 67 steps of
    # a = (h/67)/tau leave (1 - a)^67 of the gap, the exact lag e^(-h/tau).
    fine, _ = runs["fine"]
    exact = exact_lag(fine, 1 / RATE)
    error = max(abs(fine[t]["lag.logic.y"] - exact[t]) for t in fine)
    a = (1 / RATE / 67) / TAU
    predicted = HIGH * abs((1 - a) ** 67 - math.exp(-1 / RATE / TAU))
    assert error == pytest.approx(predicted, rel=1e-6)   # measured: 1.52e-4 (after the 0.4 step)
    assert error <= 2e-4


def first_tick(rows, after, condition):
    return next(t for t in sorted(rows) if t >= after and condition(rows[t]))


def test_error_against_a_one_tick_step_is_the_latency_of_the_coupling(runs):
    (coarse, coarse_events), (fine, fine_events) = runs["coarse"], runs["fine"]
    common = sorted(set(coarse) & set(fine))
    assert len(common) == 31
    fine_enter, coarse_enter = enter_tick(fine_events), enter_tick(coarse_events)   # measured: 283, 297

    # The lag's output: equal at every common point (the lag settles within any step of either
    # run) but those where one run's output already shows the barrier's step down and the other's
    # not yet; there they differ by the full step HIGH − LOW.
    coarse_down = first_tick(coarse, coarse_enter, lambda r: r["lag.logic.y"] < HIGH - 1e-3)
    fine_down = first_tick(fine, fine_enter, lambda r: r["lag.logic.y"] < HIGH - 1e-3)
    assert fine_down - fine_enter == 1                               # the lag's answer one tick on
    # The coarse run samples the event at its next point (3 ticks later here) and answers one step on.
    assert coarse_down == -(-coarse_enter // H) * H + H              # 315 = 300 + 15
    dy = {t: abs(coarse[t]["lag.logic.y"] - fine[t]["lag.logic.y"]) for t in common}
    assert {t for t in common if dy[t] > ULPS} == {t for t in common if fine_down <= t < coarse_down}  # {285, 300}
    assert max(dy[t] for t in common if not fine_down <= t < coarse_down) <= ULPS   # measured: 5.6e-17
    assert max(dy.values()) == pytest.approx(HIGH - LOW, abs=ULPS)   # measured: 0.2999999999999997

    # The bottle: after the step up it rides 14 ticks less at 0.4 m/s in the coarse run (the belt
    # gets the lag's output 15 ticks after 0.5 s instead of 1).
    dx = {t: coarse[t]["bottle.body.position.x"] - fine[t]["bottle.body.position.x"] for t in common}
    behind = HIGH * (H - 1) / RATE                                   # 37.33 mm
    for t in common:
        if 1.2 * RATE <= t <= fine_enter:                            # the bottle's own lag (k = 16/s) has settled
            assert dx[t] == pytest.approx(-behind, abs=1e-5)         # measured: -37.331 mm
    # So it reaches the barrier 14 ticks later and rides on at 0.4 m/s for coarse_down − coarse_enter
    # = 18 ticks after it, not 1: at the end it is ahead by 0.3 m/s × 17 ticks − 0.1 m/s × 14 ticks.
    assert coarse_enter - fine_enter == H - 1
    ahead = (HIGH - LOW) * ((coarse_down - coarse_enter) - (fine_down - fine_enter)) / RATE \
        - LOW * (coarse_enter - fine_enter) / RATE                   # 24.67 mm
    assert dx[common[-1]] == pytest.approx(ahead, abs=1e-5)          # measured: 24.667 mm
    # Bound: no more than the largest step height times one communication step.
    assert max(abs(d) for d in dx.values()) <= HIGH * H / RATE       # measured: 37.33 mm <= 40 mm


def test_fmi3_build_gives_the_same_recording(lag_fmus, tmp_path):
    run(lag_fmus, tmp_path / "fmi2")
    run(lag_fmus, tmp_path / "fmi3", version=3)
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "fmi2" / name).read_bytes() == (tmp_path / "fmi3" / name).read_bytes()


def test_an_internal_step_past_the_stability_limit_stops_the_run(lag_fmus, tmp_path):
    # Explicit Euler diverges once dt >= 2 tau; the FMU refuses rather than feed the belt a blow-up.
    with pytest.raises(SimulationError) as info:
        run(lag_fmus, tmp_path, **{"objects.lag.parameters.internal_step": 0.002})
    assert ("FMU instance 'lag' (stiff_lag-fmi2.fmu) at t = 0 s: fmi2DoStep returned error" in str(info.value)
            and "internal_step = 0.002 s is not below 2 * tau = 0.002 s: explicit Euler would diverge"
            in str(info.value))
