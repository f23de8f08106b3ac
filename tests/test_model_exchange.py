"""Model-exchange FMUs integrated by the hub between communication points, checked against their analytical solutions.

    constant ──inflow──▶ tank (FMI 3 ME) ──full──▶ belt.drive.run          ball (FMI 2 ME) ──h, v, bounces──▶ record

The FMUs stand in for other exporters' (tests/fmu_models/foreign, hand-written C against the FMI
headers), model exchange only: `ball2` (FMI 2.0) is a ball dropped from 1 m that bounces with
restitution 0.7 — a state event at each impact — until a bounce is slower than 0.1 m/s; `tank3`
(FMI 3.0) is a tank's level, dx/dt = inflow − x/τ until its outlet closes at 3 s (a time event),
whose Boolean `full` turns at 0.15 m (a state event).
"""
import csv
import math

import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario

from .foreign_fmus import build
from .helpers import run_scenario

G, E, H0, V_MIN = 9.81, 0.7, 1.0, 0.1
TAU, INFLOW, THRESHOLD, T_CLOSE = 2.0, 0.1, 0.15, 3.0


@pytest.fixture(scope="module")
def foreign(tmp_path_factory):
    out = tmp_path_factory.mktemp("foreign")
    return {"ball2": build("ball2", 2, out), "tank3": build("tank3", 3, out), "enum2": build("enum2", 2, out)}


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def impacts():
    """The times of the ball's impacts, worked out from the free fall between them."""
    t, v = math.sqrt(2 * H0 / G), math.sqrt(2 * G * H0)
    out = [t]
    while E * v >= V_MIN:
        v *= E
        t += 2 * v / G
        out.append(t)
    return out


def ball_height(t):
    """h(t) of the bouncing ball: free fall, then a parabola between each two impacts, then lying."""
    times = impacts()
    if t < times[0]:
        return H0 - G * t * t / 2
    v = math.sqrt(2 * G * H0)
    for start, end in zip(times, times[1:]):
        v *= E
        if t < end:
            s = t - start
            return v * s - G * s * s / 2
    return 0.0


def tank_level(t, closes=T_CLOSE):
    """The tank's level from empty at a constant inflow: a first-order rise, then linear once the outlet closes."""
    rise = lambda s: INFLOW * TAU * (1 - math.exp(-s / TAU))
    return rise(t) if t < closes else rise(closes) + INFLOW * (t - closes)


def ball_scene(write_scenario, fmu, extra="", name="scene.yaml"):
    return write_scenario(f"""
        planthub: 1
        run: {{duration: 3.0, physics_rate: 100, communication_step: 0.01}}
        objects:
          ball: {{module: fmu, file: {fmu}{extra}}}
        record: [ball.logic.h, ball.logic.v, ball.logic.bounces]
        """, name)


def test_an_fmi2_bouncing_ball_follows_its_analytical_solution(foreign, write_scenario, tmp_path):
    """CVODE (the default) locates every impact: the height within 0.1 mm of the exact one at every
    point, and the count of bounces right at every point but one within 1 ms of an impact."""
    run_scenario(ball_scene(write_scenario, foreign["ball2"]), tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert len(data) == 301
    times = impacts()
    assert len(times) == 11
    for row in data:
        t = float(row["time"])
        assert abs(float(row["ball.logic.h"]) - ball_height(t)) < 1e-4, t
        if all(abs(t - hit) > 1e-3 for hit in times):
            assert int(row["ball.logic.bounces"]) == sum(hit <= t for hit in times), t
    assert data[-1]["ball.logic.h"] == "0.0" and data[-1]["ball.logic.bounces"] == "11"


def test_explicit_euler_is_the_fixed_step_choice_with_its_own_error(foreign, write_scenario, tmp_path):
    """solver: euler, max_step 1 ms: the free fall within 3 mm of the exact height and the first impact at
    the same point; the error then grows with each bounce, as an explicit method's does."""
    path = ball_scene(write_scenario, foreign["ball2"], ", solver: euler, max_step: 0.001")
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    first = impacts()[0]
    for row in data:
        t = float(row["time"])
        if t < first:
            assert abs(float(row["ball.logic.h"]) - ball_height(t)) < 3e-3, t
    hit = next(float(r["time"]) for r in data if r["ball.logic.bounces"] == "1")
    assert hit == pytest.approx(math.ceil(first / 0.01) * 0.01)


@pytest.mark.parametrize("where", [", runs: child", ", runs: bus"])
def test_a_model_exchange_fmu_gives_the_same_results_in_every_transport(foreign, write_scenario, tmp_path, where):
    """In a child process and served over the bus, the same recording as in the hub, byte for byte."""
    run_scenario(ball_scene(write_scenario, foreign["ball2"]), tmp_path / "hub")
    run_scenario(ball_scene(write_scenario, foreign["ball2"], where, "other.yaml"), tmp_path / "other")
    assert (tmp_path / "other" / "recording.csv").read_bytes() == (tmp_path / "hub" / "recording.csv").read_bytes()


@pytest.mark.parametrize("closes", [T_CLOSE, 3.01])
def test_an_fmi3_tank_model_drives_the_plant(foreign, write_scenario, tmp_path, closes):
    """A plant-side model: the level within 0.1 mm of the exact one over the input event at 0 s, the
    state event (full at 2.7726 s) and the time event (the outlet closing at 3 s, on a point, or at
    3.01 s, between two); its equations never evaluated past a point; `full` starts the belt."""
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 4.0, physics_rate: 100, communication_step: 0.02}}
        objects:
          tank: {{module: fmu, file: {foreign["tank3"]}, parameters: {{t_close: {closes}}}}}
          inflow: {{module: constant, type: real, value: {INFLOW}}}
          belt: {{module: conveyor, position: [0, 0, 0], length: 1.0, speed: 0.2, running: false}}
        flows:
          - {{from: inflow.value.out, to: tank.logic.inflow, when: target}}
          - {{from: tank.logic.full, to: belt.drive.run}}
        record: [tank.logic.level, tank.logic.full, tank.logic.latest, belt.drive.running]
        """)
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    for row in data:
        t = float(row["time"])
        assert abs(float(row["tank.logic.level"]) - tank_level(t, closes)) < 1e-4, t
        assert float(row["tank.logic.latest"]) <= t + 1e-9, t   # CVODE stopped at the point, not past it
    full_at = -TAU * math.log(1 - THRESHOLD / (INFLOW * TAU))    # 2.7726 s
    first = next(float(r["time"]) for r in data if r["tank.logic.full"] == "1")
    assert first == pytest.approx(math.ceil(full_at / 0.02) * 0.02)
    assert all(r["tank.logic.full"] == "1" for r in data if float(r["time"]) >= first)
    started = next(float(r["time"]) for r in data if r["belt.drive.running"] == "1")
    assert started == pytest.approx(first + 0.02)   # the belt's drive takes the flow's value at the next tick


def errors(path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p).split(": ", 1)[1] for p in info.value.problems]


def test_interface_and_solver_settings_are_checked(foreign, write_scenario):
    enum2, ball2 = foreign["enum2"], foreign["ball2"]
    path = write_scenario(f"""
        planthub: 1
        objects:
          a: {{module: fmu, file: {enum2}, interface: model-exchange}}
          b: {{module: fmu, file: {enum2}, solver: cvode, tolerance: 0.001}}
          c: {{module: fmu, file: {ball2}, solver: euler}}
          d: {{module: fmu, file: {ball2}, interface: co-simulation}}
          e: {{module: fmu, file: {ball2}, runs: bus, launch: false, solver: euler, max_step: 0.001}}
        """)
    assert errors(path) == [
        "objects.a.interface: enum2.fmu offers no model-exchange interface with a binary for this platform "
        "(it offers: co-simulation)",
        "objects.b.solver: solver is for a model-exchange FMU, which the hub integrates; enum2.fmu runs as "
        "co-simulation and steps itself",
        "objects.b.tolerance: tolerance is for a model-exchange FMU, which the hub integrates; enum2.fmu runs as "
        "co-simulation and steps itself",
        "objects.c.solver: euler takes fixed steps: give their length as max_step",
        "objects.d.interface: ball2.fmu offers no co-simulation interface with a binary for this platform "
        "(it offers: model-exchange)",
        "objects.e.solver: solver is given to the joining process (`planthub serve-fmu --solver …`): with "
        "launch: false the hub cannot set it",
        "objects.e.max_step: max_step is given to the joining process (`planthub serve-fmu --max-step …`): with "
        "launch: false the hub cannot set it",
    ]
