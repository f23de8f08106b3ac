"""A jam: 100 bottles queued against a closed stopper on a running belt (μ = 0.1), 30 simulated seconds.

    q099 … q002 q001 q000 ──►|stop|    belt 0.5 m/s, 7 cm lane, 150 Hz

`make stability` holds it for 10 minutes. The bounds and what they were set from: tests/hard/cases.py, JAM_*.
"""
import pytest

from . import cases


@pytest.mark.slow
def test_a_jam_of_100_bottles_at_a_closed_stopper_holds_still_and_gains_no_energy(tmp_path):
    cases.jam(tmp_path, cases.JAM_SECONDS_SHORT).check()
