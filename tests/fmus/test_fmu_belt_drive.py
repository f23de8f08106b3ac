"""belt_drive: the speed ramps to the setpoint while running and back to 0 when stopped, at the hand-computed times."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from .fmu_support import VERSIONS

STEP = 0.1


def simulate(fmu, ramp, signal_rows, stop_time):
    signals = np.array(signal_rows, dtype=[("time", float), ("run", np.bool_), ("speed_setpoint", float)])
    result = simulate_fmu(str(fmu), stop_time=stop_time, output_interval=STEP, input=signals,
                          start_values={"ramp": ramp}, output=["speed", "running"])
    return result["time"], result["speed"], result["running"]


@pytest.mark.parametrize("version", VERSIONS)
def test_ramps_up_to_setpoint_and_down_after_stop(fmu_build, version):
    # run from 0 s to 3 s, setpoint 1 m/s, ramp 0.5 m/s^2: +0.05 m/s per 0.1 s step,
    # so 1 m/s is reached at exactly 2.0 s; after the stop at 3.0 s, 0 m/s at exactly 5.0 s.
    time, speed, running = simulate(fmu_build / f"belt_drive-fmi{version}.fmu", ramp=0.5, stop_time=6.0,
                                    signal_rows=[(0.0, True, 1.0), (3.0, True, 1.0), (3.0, False, 1.0),
                                                 (6.0, False, 1.0)])
    k = np.arange(61)
    expected = np.where(k <= 30, np.minimum(0.05 * k, 1.0), np.maximum(1.0 - 0.05 * (k - 30), 0.0))
    np.testing.assert_allclose(time, STEP * k, atol=1e-12)
    np.testing.assert_allclose(speed, expected, atol=1e-12)
    assert speed[19] < 1.0 and speed[20] == 1.0, "setpoint reached at 2.0 s, not earlier or later"
    assert speed[49] > 0.0 and speed[50] == 0.0, "standstill reached at 5.0 s, not earlier or later"
    assert not running[0], "a belt at rest before the first step is not running"
    assert running[1:50].all() and not running[50:].any(), "running while it moves, including the ramp down"


@pytest.mark.parametrize("version", VERSIONS)
def test_zero_ramp_follows_setpoint_at_once(fmu_build, version):
    time, speed, running = simulate(fmu_build / f"belt_drive-fmi{version}.fmu", ramp=0.0, stop_time=1.0,
                                    signal_rows=[(0.0, True, 0.8), (0.5, True, 0.8), (0.5, True, -0.3),
                                                 (0.7, True, -0.3), (0.7, False, -0.3), (1.0, False, -0.3)])
    # Inputs at t act during the step t -> t + 0.1, so outputs follow one step later.
    expected = [0.0, 0.8, 0.8, 0.8, 0.8, 0.8, -0.3, -0.3, 0.0, 0.0, 0.0]
    assert list(speed) == expected
    assert list(running) == [s != 0.0 for s in expected]


@pytest.mark.parametrize("version", VERSIONS)
def test_setpoint_change_while_running_ramps_to_new_setpoint(fmu_build, version):
    # ramp 1 m/s^2 = 0.1 m/s per step: 0.6 m/s at exactly 0.6 s; the setpoint drops to 0.2 m/s at 1.0 s
    # and the speed falls to it by exactly 1.4 s.
    _, speed, _ = simulate(fmu_build / f"belt_drive-fmi{version}.fmu", ramp=1.0, stop_time=2.0,
                           signal_rows=[(0.0, True, 0.6), (1.0, True, 0.6), (1.0, True, 0.2), (2.0, True, 0.2)])
    expected = [min(0.1 * k, 0.6) for k in range(11)] + [0.5, 0.4, 0.3, 0.2, 0.2, 0.2, 0.2, 0.2, 0.2, 0.2]
    np.testing.assert_allclose(speed, expected, atol=1e-12)
    assert speed[14] == 0.2 and speed[6] == 0.6
