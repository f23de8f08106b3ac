"""Tunnelling: bottles at 2 m/s into a closed 5 mm stopper, meeting it at eight phases of a tick, at 150 and 60 Hz.

    b0 ──► [======== belt0, 2 m/s ========|5 mm|]
    …      (each bottle offset by an eighth of a tick's travel)

The bounds and what they were set from: tests/hard/cases.py, TUNNEL_*.
"""
import pytest

from . import cases


@pytest.mark.parametrize("rate", [150, 60])
def test_a_bottle_at_2_m_s_does_not_pass_a_5_mm_gate(tmp_path, rate):
    cases.tunnelling(tmp_path, rate).check()


def test_the_checks_see_a_bottle_jump_a_gate_when_it_does(tmp_path):
    """The gate bounds are live: at 2.5 m/s, 41.7 mm a tick at 60 Hz — more than a radius and half the
    gate — bottles jump the 5 mm gate (and fall off the belt's end), and the checker names them."""
    result = cases.tunnelling(tmp_path, 60, speed=2.5)
    broken = {b.name: b.measured for b in result.bounds if not b.passed}
    assert broken["bottles through a closed gate"] >= 1 and broken["bottles the physics watch took out"] >= 1
    with pytest.raises(AssertionError, match=r"bottles through a closed gate \d"):
        result.check()
