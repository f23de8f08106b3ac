"""A 20 g bottle put on a belt running at 1.0 m/s, gripped at its centre of mass and at its base (the paper's test 2, harder).

    simple ──►     [==== 1.0 m/s, k = 16/s ====]
    base_point ──► [==== 1.0 m/s, gain 0.15 N·s/m ====]
    base_body ──►  [==== 1.0 m/s, gain 0.15 N·s/m ====]

The bounds and what they were set from: tests/hard/cases.py, LIGHT_*.
"""
from . import cases


def test_a_20_g_bottle_put_on_a_belt_at_1_m_s_rocks_and_rights_itself(tmp_path):
    cases.light_bottle(tmp_path).check()
