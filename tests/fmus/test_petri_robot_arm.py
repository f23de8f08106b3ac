"""robot_arm (fmus/nets/robot_arm.net.yaml) through fmpy: the pick, carry, place, return sequence and its timing."""

import pytest

from .petri_support import run_script, times_when

H = 0.1
PHASES = ("Idle", "Picking", "Carrying", "Placing", "Returning")


def test_a_request_runs_the_phases_in_order_with_their_delays(plant_net):
    # Request in the step ending at 0.1 s; pick 1 s, carry 2 s, place 1 s, return 2 s (the defaults).
    trace = run_script(plant_net("robot_arm"), 80, H, {1: {"Request"}})
    starts = {phase: times_when(trace, f"{phase}_got") for phase in PHASES}
    assert starts == {"Picking": [0.1], "Carrying": [1.1], "Placing": [3.1], "Returning": [4.1], "Idle": [6.1]}
    assert times_when(trace, "Holding_got") == [1.1]
    assert times_when(trace, "Holding_marked") == pytest.approx([1.1 + 0.1 * k for k in range(30)])


def test_one_token_walks_through_the_phases(plant_net):
    trace = run_script(plant_net("robot_arm"), 150, H, {1: {"Request"}, 20: {"Request"}})
    for t, out in trace:
        assert sum(out[f"{phase}_tokens"] for phase in PHASES) == 1, f"t = {t}"


def test_requests_while_busy_wait_their_turn(plant_net):
    # The second request (2.0 s) waits on Request until the arm is idle again at 6.1 s and starts at once.
    trace = run_script(plant_net("robot_arm"), 140, H, {1: {"Request"}, 20: {"Request"}})
    assert times_when(trace, "Picking_got") == [0.1, 6.2]
    assert times_when(trace, "Idle_got") == [6.1, 12.2]


def test_no_request_no_motion(plant_net):
    trace = run_script(plant_net("robot_arm"), 50, H)
    assert all(out["Idle_marked"] and not out["Picking_marked"] for _, out in trace)


def test_phase_delays_are_parameters(plant_net):
    arm = plant_net("robot_arm", pick_delay=0.5, carry_delay=0.3, place_delay=0.2, home_delay=0.4)
    trace = run_script(arm, 30, H, {1: {"Request"}})
    assert {phase: times_when(trace, f"{phase}_got") for phase in PHASES[1:]} == {
        "Carrying": [0.6], "Placing": [0.9], "Returning": [1.1], "Picking": [0.1]}
    assert times_when(trace, "Idle_got") == [1.5]
