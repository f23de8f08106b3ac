"""The paper's test 3: two bottles 20 cm apart go round a closed loop of 6 curves and 5 straights for 50 s.

    start ─► s1 5.0 m ─► c1 ─► s2 1.0 m ─► c2 ─► s3 3.0 m ─► c3 ─► c4 (left) ─► s4 1.2 m ─► c5 ─► s5 0.2 m ─► c6 ─┐
      ▲──────────────────────────────────────────────────────────────────────────────────────────────────────┘

The paper saw the Manhattan distance between 15.8 and 22.4 cm (variance 1.6 cm²). Ours holds the
distance along the loop to within ±0.05 cm of 20 cm, and the Manhattan distance to within
±0.1 cm of what the geometry of the curves alone makes of 20 cm.
"""
import numpy as np

from hub.reports import paper
from hub.reports.runs import run


def test_the_loop_closes_and_has_the_papers_shape(distances_run):
    objects = {o.name: o for o in distances_run.scenario.objects}
    curves = [o.params["turn"] for o in objects.values() if o.module_name == "curve"]
    straights = [o.params["length"] for o in objects.values() if o.module_name == "conveyor"]
    assert sorted(curves) == ["left"] + ["right"] * 5
    assert len(straights) == 5 and min(straights) == 0.2 and max(straights) == 5.0
    _, closure = paper.chain(distances_run.fields)
    assert closure < 1e-9


def test_the_spacing_along_the_loop_stays_within_half_a_millimetre_for_50_seconds(distances_run):
    d = paper.distances(distances_run)
    assert d.time[-1] == 50.0 and d.on_belt
    assert d.time[-1] * 0.5 > d.loop_length     # round the loop at least once
    assert np.max(np.abs(d.gap - 0.2)) < 5e-4
    assert np.max(np.abs(d.manhattan - d.reference)) < 1e-3
    # The Manhattan distance itself swings with the geometry of the curves, as it did in the paper.
    assert np.max(d.manhattan) > 0.27


def test_no_bottle_touches_a_rail_or_tips(distances_run):
    d = paper.distances(distances_run)
    assert np.max(np.abs(d.lateral)) < 2e-3       # 2 cm of play either side
    assert np.max(d.tilt) < 1.0


def test_the_same_loop_twice_gives_bit_identical_recordings(distances_run, tmp_path):
    run(paper.DISTANCES, tmp_path / "again")
    for name in ("recording.csv", "events.csv"):
        assert (distances_run.directory / name).read_bytes() == (tmp_path / "again" / name).read_bytes()
