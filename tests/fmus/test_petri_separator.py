"""separator (fmus/nets/separator.net.yaml, the paper's figs. 9-11) through fmpy: cycles, blocking, gates."""

import random

import pytest

from .petri_support import run_script, times_when

H = 0.01


def test_one_cycle_per_start(plant_net):
    # B326 sees a bottle in step 1 only: BP opens (WorkingPos) for release_delay = 0.5 s, then it is ready
    # again rearm_delay = 0.5 s later; no second cycle.
    trace = run_script(plant_net("separator"), 300, H, {1: {"B326"}})
    assert times_when(trace, "WorkingPos_got") == [0.01]
    assert times_when(trace, "BasePos_got") == [0.51]
    assert times_when(trace, "Ready_got") == [1.01]
    assert len(times_when(trace, "WorkingPos_marked")) == 50


def test_a_waiting_queue_runs_one_cycle_per_period(plant_net):
    # A bottle stays at B326 the whole time: a cycle every release + rearm + the step that starts it.
    separator = plant_net("separator", release_delay=0.2, rearm_delay=0.3)
    trace = run_script(separator, 200, H, {number: {"B326"} for number in range(1, 201)})
    assert times_when(trace, "WorkingPos_got") == pytest.approx([0.01, 0.52, 1.03, 1.54])
    assert times_when(trace, "BasePos_got") == pytest.approx([0.21, 0.72, 1.23, 1.74])


@pytest.mark.parametrize("blocker", ["B327", "B321"])
def test_no_start_while_the_section_behind_is_occupied(plant_net, blocker):
    # B326 all along; the blocker sees a bottle in steps 1 to 10: the cycle starts in step 11.
    puts = {number: {"B326"} | ({blocker} if number <= 10 else set()) for number in range(1, 31)}
    trace = run_script(plant_net("separator"), 30, H, puts)
    assert times_when(trace, "WorkingPos_got") == [0.11]


def test_gates_are_never_both_open_and_start_only_when_allowed(plant_net):
    separator = plant_net("separator", release_delay=0.05, rearm_delay=0.03)
    rng = random.Random(4)
    cycles = 0
    for number in range(1, 1001):
        put = {sensor for sensor, chance in (("B326", 0.5), ("B327", 0.3), ("B321", 0.3)) if rng.random() < chance}
        out = separator.step(H, put)
        assert out["BasePos_marked"] != out["WorkingPos_marked"], f"step {number}: exactly one gate closed"
        if out["WorkingPos_got"]:
            cycles += 1
            assert put & {"B326", "B327", "B321"} == {"B326"}, f"step {number}: started while blocked"
    assert cycles > 20
