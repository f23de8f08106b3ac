"""A switch blade turned solid onto a bottle standing under it (the switch's own wait for a clear way switched off).

             ╭─ blade          a bottle 6–28 mm under it, its axis inside the arc: pushed into the branch
      ───────╯ ● ───────►      or outside it: pushed on downstream
      [== main ┬  ┬ ==] ► main_end
               │▼ │ ► branch_end

The bounds and what they were set from: tests/hard/cases.py, BLADE_*.
"""
from . import cases


def test_a_blade_turned_solid_onto_a_standing_bottle_pushes_it_out_to_its_side_gently(tmp_path):
    cases.blade_onto_bottle(tmp_path).check()
