"""timer: fires on exactly the step in which its period has passed, with no float drift, once per rising edge."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from .fmu_support import VERSIONS


def simulate(fmu, period, step, stop_time, start_rows):
    signals = np.array(start_rows, dtype=[("time", float), ("start", np.bool_)])
    result = simulate_fmu(str(fmu), stop_time=stop_time, output_interval=step, input=signals,
                          start_values={"period": period}, output=["elapsed", "remaining"])
    return result["time"], result["elapsed"], result["remaining"]


def naive_steps_until(period, step):
    """Steps a timer that accumulates the step size in a double needs to fire."""
    elapsed, steps = 0.0, 0
    while elapsed < period:
        elapsed += step
        steps += 1
    return steps


@pytest.mark.parametrize("version", VERSIONS)
def test_fires_on_the_exact_step(fmu_build, version):
    # start rises at 0.2 s; period 0.8 s = 8 steps of 0.1 s, so elapsed is true at 1.0 s and only there.
    # Summing 0.1 eight times gives 0.7999999999999999: a float accumulator would fire one step late.
    assert naive_steps_until(0.8, 0.1) == 9
    time, elapsed, remaining = simulate(fmu_build / f"timer-fmi{version}.fmu", period=0.8, step=0.1,
                                        stop_time=1.5,
                                        start_rows=[(0.0, False), (0.2, False), (0.2, True), (1.5, True)])
    assert [round(t, 9) for t in time[elapsed]] == [1.0]
    expected_remaining = [0.0, 0.0, 0.0, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.0] + [0.0] * 5
    np.testing.assert_allclose(remaining, expected_remaining, atol=1e-12)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("period, step", [(0.3, 0.1), (1.0, 0.1), (1.1, 0.1), (1.0, 0.01), (2.5, 0.05), (0.0, 0.1)])
def test_period_of_n_steps_fires_on_step_n(fmu_build, version, period, step):
    # All but 0.3 s, 1.0 s / 0.01 s and 0 s fire one step late with a float accumulator (naive_steps_until).
    n = round(period / step)
    time, elapsed, _ = simulate(fmu_build / f"timer-fmi{version}.fmu", period=period, step=step,
                                stop_time=period + 5 * step, start_rows=[(0.0, True), (1.0, True)])
    # The edge is seen in the step that starts at 0 s; with period 0 it fires in that same step.
    assert list(np.flatnonzero(elapsed)) == [max(n, 1)]


@pytest.mark.parametrize("version", VERSIONS)
def test_fires_once_per_rising_edge_and_retriggers(fmu_build, version):
    # Edges at 0.0 s and 0.5 s (start falls at 0.4 s): the first run fires at 0.3 s; the second at 0.8 s.
    # start held high does not fire again.
    time, elapsed, _ = simulate(fmu_build / f"timer-fmi{version}.fmu", period=0.3, step=0.1, stop_time=2.0,
                                start_rows=[(0.0, True), (0.4, True), (0.4, False), (0.5, False), (0.5, True),
                                            (2.0, True)])
    assert [round(t, 9) for t in time[elapsed]] == [0.3, 0.8]


@pytest.mark.parametrize("version", VERSIONS)
def test_edge_while_running_restarts_the_period(fmu_build, version):
    # Edge at 0.0 s, second edge at 0.2 s before the 0.5 s period ran out: it fires at 0.7 s only.
    time, elapsed, _ = simulate(fmu_build / f"timer-fmi{version}.fmu", period=0.5, step=0.1, stop_time=1.5,
                                start_rows=[(0.0, True), (0.1, True), (0.1, False), (0.2, False), (0.2, True),
                                            (1.5, True)])
    assert [round(t, 9) for t in time[elapsed]] == [0.7]
