"""belt_run_stop (fmus/nets/belt_run_stop.pnml) through fmpy: run and stop commands, stop wins."""

import pytest

from .petri_support import run_script

H = 0.01


def running(trace):
    return [out["Running_marked"] for _, out in trace]


def test_run_and_stop(plant_net):
    trace = run_script(plant_net("belt_run_stop"), 6, H, {2: {"Run"}, 3: {"Run"}, 5: {"Stop"}, 6: {"Stop"}})
    assert running(trace) == [False, True, True, True, False, False]
    for _, out in trace:
        assert out["Running_tokens"] + out["Stopped_tokens"] == 1
        assert out["Run_tokens"] == out["Stop_tokens"] == 0, "commands are used or dropped in their step"


@pytest.mark.parametrize("running_before", [False, True])
def test_stop_wins_over_run_in_the_same_step(plant_net, running_before):
    belt = plant_net("belt_run_stop", Running_initial=int(running_before), Stopped_initial=int(not running_before))
    out = belt.step(H, {"Run", "Stop"})
    assert (out["Running_marked"], out["Stopped_marked"]) == (False, True)
    assert out["Run_tokens"] == out["Stop_tokens"] == 0
    assert not belt.step(H)["Running_marked"], "no run command was left over"
