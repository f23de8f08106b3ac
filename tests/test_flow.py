"""Flow rules: the four execution conditions, continuous and singular mode, re-arming."""
import pytest

from hub.core.flow import Condition, Flow, Mode
from hub.core.signals import Signals
from hub.core.slots import Slot

SOURCE, TARGET, REARM = 0, 1, 2


def make_signals():
    return Signals([Slot.source("s", "real"), Slot.target("t", "real"), Slot.source("r", "void")])


def step(signals, source_active, target_active, value=None, rearm=False):
    signals.begin_step()
    if source_active:
        signals.emit(SOURCE, value)
    elif value is not None:
        signals.values[SOURCE] = value
    signals.active[TARGET] = target_active
    if rearm:
        signals.emit(REARM)


# A flow runs through `run(signals)`, or through the closure `runner(signals)` a plant's plan calls.
BY_RUN = lambda flow, signals: flow.run(signals)          # noqa: E731
BY_RUNNER = lambda flow, signals: flow.runner(signals)()  # noqa: E731


@pytest.mark.parametrize("run", [BY_RUN, BY_RUNNER], ids=["run", "runner"])
@pytest.mark.parametrize("condition, runs_when", [
    (Condition.SOURCE, {(True, True), (True, False)}),
    (Condition.TARGET, {(True, True), (False, True)}),
    (Condition.BOTH, {(True, True)}),
    (Condition.EITHER, {(True, True), (True, False), (False, True)}),
])
def test_execution_condition(condition, runs_when, run):
    for src in (False, True):
        for tgt in (False, True):
            signals = make_signals()
            flow = Flow(SOURCE, TARGET, condition)
            step(signals, src, tgt, value=2.5)
            executed = run(flow, signals)
            assert executed == ((src, tgt) in runs_when), (condition, src, tgt)
            assert signals.updated[TARGET] == executed
            assert signals.values[TARGET] == (2.5 if executed else 0.0)


def test_target_condition_pulls_the_held_source_value():
    signals = make_signals()
    flow = Flow(SOURCE, TARGET, Condition.TARGET)
    step(signals, source_active=True, target_active=False, value=1.0)
    assert not flow.run(signals)
    step(signals, source_active=False, target_active=True)
    assert flow.run(signals)
    assert signals.values[TARGET] == 1.0


@pytest.mark.parametrize("run", [BY_RUN, BY_RUNNER], ids=["run", "runner"])
def test_continuous_flow_runs_every_step(run):
    signals = make_signals()
    flow = Flow(SOURCE, TARGET)
    for n in range(3):
        step(signals, True, True, value=float(n))
        assert run(flow, signals)
        assert signals.values[TARGET] == float(n)


@pytest.mark.parametrize("run", [BY_RUN, BY_RUNNER], ids=["run", "runner"])
def test_singular_flow_runs_once_until_rearmed(run):
    signals = make_signals()
    flow = Flow(SOURCE, TARGET, mode=Mode.SINGULAR, rearm=REARM)
    step(signals, True, True, value=1.0)
    assert run(flow, signals)
    step(signals, True, True, value=2.0)
    assert not run(flow, signals)
    assert signals.values[TARGET] == 1.0 and not signals.updated[TARGET]
    # Re-armed in this step: it is judged after re-arming, so it executes in the same step.
    step(signals, True, True, value=3.0, rearm=True)
    assert run(flow, signals)
    assert signals.values[TARGET] == 3.0
    step(signals, True, True, value=4.0)
    assert not run(flow, signals)


def test_singular_flow_without_rearm_slot_stays_disarmed():
    signals = make_signals()
    flow = Flow(SOURCE, TARGET, mode=Mode.SINGULAR)
    step(signals, True, True, value=1.0)
    assert flow.run(signals)
    for _ in range(5):
        step(signals, True, True, value=9.0)
        assert not flow.run(signals)


def test_a_singular_flow_stays_armed_while_its_condition_fails():
    signals = make_signals()
    flow = Flow(SOURCE, TARGET, mode=Mode.SINGULAR)
    step(signals, False, True)
    assert not flow.run(signals)
    step(signals, True, True, value=5.0)
    assert flow.run(signals)


def test_begin_step_clears_activity_and_keeps_values():
    signals = make_signals()
    step(signals, True, True, value=7.0)
    Flow(SOURCE, TARGET).run(signals)
    signals.begin_step()
    assert signals.active == [False, True, False]
    assert signals.updated == [False, False, False]
    assert signals.values[SOURCE] == 7.0 and signals.values[TARGET] == 7.0
