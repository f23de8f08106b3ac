"""A full belt stopped at once: 40 bottles 0.5 mm apart riding at 0.5 m/s, the belt's run set false at 1.5 s.

    f39 … f01 f00 ──► [======== belt_simple: 0.5 m/s → 0 at 1.5 s ========]
    p39 … p01 p00 ──► [======== belt_base_point ========]

The bounds and what they were set from: tests/hard/cases.py, FULL_*.
"""
from . import cases


def test_a_full_belt_stopped_at_once_comes_to_rest_upright_without_gaining_energy(tmp_path):
    cases.full_belt_stop(tmp_path).check()
