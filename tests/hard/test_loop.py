"""The paper's loop for long: two bottles 20 cm apart round scenarios/paper/constant_distances.yaml for 5 simulated minutes.

    start ─► s1 ─► c1 ─► s2 ─► c2 ─► s3 ─► c3 ─► c4 ─► s4 ─► c5 ─► s5 ─► c6 ─┐
      ▲──────────────────────────────────────────────────────────────────────┘

`make stability` runs the hour, which fails today: the follower wobbles from ~480 s, falls over at
~715 s and lies stuck, and the leader runs into it. The bounds and what they were set from: tests/hard/cases.py, LOOP_*.
"""
from . import cases


def test_two_bottles_keep_their_spacing_round_the_papers_loop_for_five_minutes():
    cases.loop(cases.LOOP_SECONDS_SHORT).check()
