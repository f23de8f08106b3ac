"""The firing rule, puts and delays, hand-computed, on the interpreter and on both FMI builds of the test nets."""

import pytest

from .petri_support import run_script, times_when

H = 0.1


def tokens(outputs, *places):
    return tuple(outputs[f"{place}_tokens"] for place in places)


def test_forward_conflict_fires_both_transitions(run_net):
    # The paper's fig. 3: one token on P enables to_A and to_B; both fire, P gives up its one token once.
    out = run_net("conflicts", P_initial=1).step(H)
    assert tokens(out, "P", "A", "B") == (0, 1, 1)
    assert (out["A_got"], out["B_got"], out["P_got"]) == (True, True, False)


def test_a_contested_place_loses_no_more_than_it_holds(run_net):
    # Q = 3: two transitions take 2 each; both fire, Q stops at 0 rather than -1.
    out = run_net("conflicts", Q_initial=3).step(H)
    assert tokens(out, "Q", "QA", "QB") == (0, 1, 1)


def test_without_conflict_a_step_is_the_ordinary_concurrent_step(run_net):
    # Q = 5 covers both takes: 5 - 2 - 2 = 1, as in standard step semantics; 1 < 2 enables neither again.
    net = run_net("conflicts", Q_initial=5)
    assert tokens(net.step(H), "Q", "QA", "QB") == (1, 1, 1)
    assert tokens(net.step(H), "Q", "QA", "QB") == (1, 1, 1)


def test_a_transition_fires_at_most_once_per_step(run_net):
    # Q = 8 would let each transition fire twice; each fires once per step, so it takes two steps.
    net = run_net("conflicts", Q_initial=8)
    assert tokens(net.step(H), "Q", "QA", "QB") == (4, 1, 1)
    assert tokens(net.step(H), "Q", "QA", "QB") == (0, 2, 2)


def test_a_token_given_to_a_contested_place_survives_the_conflict(run_net):
    # R = 1 is taken by two transitions while refill_R gives one: take first (1 - 2 -> 0), then give (+1).
    out = run_net("conflicts", R_initial=1, S_initial=1).step(H)
    assert tokens(out, "R", "RA", "RB", "S") == (1, 1, 1, 0)
    assert out["R_got"]


def test_a_self_loop_only_tests_its_place(run_net):
    # read_U (U -> U + UA) and take_U (U -> UB) both fire; the self-loop cannot put back the token take_U took.
    out = run_net("conflicts", U_initial=1).step(H)
    assert tokens(out, "U", "UA", "UB") == (0, 1, 1)
    assert not out["U_got"], "a test is not an arrival"


def test_put_is_one_token_per_step_in_which_it_is_true(run_net):
    net = run_net("places_only")
    trace = run_script(net, 5, H, {1: {"Counter"}, 2: {"Counter"}, 3: {"Counter"}, 5: {"Preset"}})
    assert [out["Counter_tokens"] for _, out in trace] == [1, 2, 3, 3, 3]
    assert [out["Counter_got"] for _, out in trace] == [True, True, True, False, False]
    assert [out["Preset_tokens"] for _, out in trace] == [2, 2, 2, 2, 3]


def test_initial_marking_before_the_first_step(run_net):
    out = run_net("places_only", Counter_initial=4).outputs()
    assert (out["Counter_tokens"], out["Counter_marked"], out["Counter_got"]) == (4, True, False)
    assert (out["Preset_tokens"], out["Preset_marked"]) == (2, True)


def test_a_put_token_can_leave_in_the_same_step(run_net):
    # Puts come before the firing round: the token arrives (P_got) and moves on at once.
    out = run_net("conflicts").step(H, {"P"})
    assert tokens(out, "P", "A", "B") == (0, 1, 1)
    assert out["P_got"] and not out["P_marked"]


def test_one_firing_round_per_step(run_net):
    # C1 -> C2 -> C3 -> C4: a token moves one transition per step; delay 0 and a delay shorter than the step
    # (0.001 s) fire in the first step they are enabled.
    trace = run_script(run_net("timing"), 4, H, {1: {"C1"}})
    assert [tokens(out, "C1", "C2", "C3", "C4") for _, out in trace] == [
        (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1), (0, 0, 0, 1)]


def test_a_step_of_size_zero_is_still_an_update_step(run_net):
    assert tokens(run_net("timing").step(0.0, {"C1"}), "C1", "C2") == (0, 1)


def test_delay_fires_on_the_exact_step_without_float_drift(run_net):
    # Go put in step 1 -> Waiting at 0.1 s; finish (0.8 s) fires in the step that ends at 0.9 s. The importer's
    # time is 0.1 added up, 0.8999999999999999 there: a float comparison would fire a step late.
    trace = run_script(run_net("timing"), 12, H, {1: {"Go"}})
    assert times_when(trace, "Done_got") == [0.9]
    assert times_when(trace, "Waiting_marked") == pytest.approx([0.1 * k for k in range(1, 9)])


def test_delay_restarts_when_the_transition_is_disabled(run_net):
    # Hold inhibits finish in step 5 (0.4 to 0.5 s): the wait starts again at 0.5 s and ends at 1.3 s.
    trace = run_script(run_net("timing"), 16, H, {1: {"Go"}, 5: {"Hold"}})
    assert times_when(trace, "Done_got") == [1.3]


def test_delay_parameter_sets_the_time(run_net):
    # 0.25 s from 0.1 s: the first step ending at or after 0.35 s ends at 0.4 s.
    trace = run_script(run_net("timing", finish_delay=0.25), 6, H, {1: {"Go"}})
    assert times_when(trace, "Done_got") == [0.4]


def test_a_delayed_self_loop_is_a_clock(run_net):
    # beat: Clock -> Clock + Tick after 0.3 s: enabled from 0 s, fires at 0.3 s, waits again from there.
    trace = run_script(run_net("timing"), 12, H)
    assert times_when(trace, "Tick_got") == [0.3, 0.6, 0.9, 1.2]
    assert trace[-1][1]["Tick_tokens"] == 4
    assert not any(out["Clock_got"] for _, out in trace)


def test_delays_follow_variable_step_sizes(run_net):
    # finish waits 0.8 s from 0.1 s: steps of 0.1, 0.5, 0.05, 0.05, 0.1 end at 0.1, 0.6, 0.65, 0.7, 0.8, 0.9.
    net = run_net("timing")
    ends = []
    for h, put in [(0.1, {"Go"}), (0.5, ()), (0.05, ()), (0.05, ()), (0.1, ()), (0.1, ()), (0.1, ())]:
        if net.step(h, put)["Done_got"]:
            ends.append(round(net.time, 9))
    assert ends == [0.9]


def test_a_place_beyond_an_fmi_integer_is_an_error(run_net):
    net = run_net("places_only", Counter_initial=2**31 - 1)
    with pytest.raises((OverflowError, RuntimeError), match="place Counter would hold 2147483648 tokens"):
        net.step(H, {"Counter"})
