"""track_switch (fmus/nets/track_switch.pnml, the paper's fig. 8) through fmpy: positions, commands, animations."""

import random

from .petri_support import run_script, times_when

H = 0.01
POSITIONS = ("BasePos", "WorkingPos")
COMMANDS = ("MoveToBasePos", "MoveToWorkingPos")


def test_starts_in_base_position_without_animation(plant_net):
    out = plant_net("track_switch").outputs()
    assert (out["BasePos_marked"], out["WorkingPos_marked"]) == (True, False)
    assert not (out["BasePosStartAnim_marked"] or out["WorkingPosStartAnim_marked"])


def test_move_command_changes_position_then_starts_the_animation_once(plant_net):
    trace = run_script(plant_net("track_switch"), 5, H, {2: {"MoveToWorkingPos"}})
    assert times_when(trace, "WorkingPos_got") == [0.02], "the position (blade collision) changes in the step"
    assert times_when(trace, "WorkingPos_marked") == [0.02, 0.03, 0.04, 0.05]
    assert not any(out["BasePos_marked"] for t, out in trace if t >= 0.02)
    # The animation place holds its token for exactly the step after the move.
    assert times_when(trace, "WorkingPosStartAnim_got") == [0.03]
    assert times_when(trace, "WorkingPosStartAnim_marked") == [0.03]
    assert times_when(trace, "BasePosStartAnim_got") == []


def test_command_for_the_current_position_does_nothing(plant_net):
    trace = run_script(plant_net("track_switch"), 6, H, {1: {"MoveToBasePos"}, 3: {"MoveToBasePos"}})
    for _, out in trace:
        assert (out["BasePos_tokens"], out["WorkingPos_tokens"]) == (1, 0)
        assert not (out["BasePosStartAnim_marked"] or out["WorkingPosStartAnim_marked"])
        assert out["MoveToBasePos_tokens"] == 0, "tcb drops the command in the step it arrives"


def test_repeated_commands_do_not_accumulate(plant_net):
    # Three move-to-working commands in a row, then one move-to-base: the switch goes to base at once;
    # leftover tokens on MoveToWorkingPos would send it back to working.
    trace = run_script(plant_net("track_switch"), 10, H,
                       {1: {"MoveToWorkingPos"}, 2: {"MoveToWorkingPos"}, 3: {"MoveToWorkingPos"},
                        5: {"MoveToBasePos"}})
    assert times_when(trace, "WorkingPos_marked") == [0.01, 0.02, 0.03, 0.04]
    assert times_when(trace, "BasePos_got") == [0.05]
    assert times_when(trace, "WorkingPosStartAnim_got") == [0.02]
    assert times_when(trace, "BasePosStartAnim_got") == [0.06]
    assert all(out["MoveToWorkingPos_tokens"] == out["MoveToBasePos_tokens"] == 0 for _, out in trace)


def test_opposite_commands_in_one_step_move_to_the_other_position(plant_net):
    # In base, mtw moves and tcb drops the move-to-base; documented in fmus/README.md.
    out = plant_net("track_switch").step(H, {"MoveToBasePos", "MoveToWorkingPos"})
    assert (out["BasePos_marked"], out["WorkingPos_marked"]) == (False, True)
    assert out["MoveToBasePos_tokens"] == out["MoveToWorkingPos_tokens"] == 0


def test_invariants_under_random_commands(plant_net):
    switch = plant_net("track_switch")
    rng = random.Random(8)
    position, changes, animations = "BasePos", [], []
    for number in range(1, 501):
        out = switch.step(H, {c for c in COMMANDS if rng.random() < 0.1})
        assert out["BasePos_tokens"] + out["WorkingPos_tokens"] == 1, f"step {number}: one position"
        assert out["MoveToBasePos_tokens"] == out["MoveToWorkingPos_tokens"] == 0, f"step {number}: accumulation"
        assert out["BasePosAnimCtrl_tokens"] + out["WorkingPosAnimCtrl_tokens"] == 1
        now = "BasePos" if out["BasePos_marked"] else "WorkingPos"
        if now != position:
            changes.append((number, now))
            position = now
        for target in POSITIONS:
            if out[f"{target}StartAnim_got"]:
                animations.append((number, target))
    # Every change of position starts its animation exactly once, one step later.
    assert changes and animations == [(number + 1, target) for number, target in changes]
