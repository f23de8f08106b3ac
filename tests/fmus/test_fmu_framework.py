"""The framework through the raw FMI API: independent instances, checked references and set rules, errors, logging."""

import pytest
from fmpy.fmi1 import FMICallException

from .fmu_support import VERSIONS


@pytest.fixture(params=VERSIONS, ids=lambda v: f"fmi{v}")
def version(request):
    return request.param


@pytest.fixture
def belt(fmu_build, open_instance, version):
    return lambda **kwargs: open_instance(fmu_build / f"belt_drive-fmi{version}.fmu", **kwargs)


@pytest.fixture
def probe(probe_build, open_instance, version):
    return lambda **kwargs: open_instance(probe_build / f"probe-fmi{version}.fmu", **kwargs)


def test_two_instances_in_one_process_do_not_share_state(belt):
    a, b = belt(name="a"), belt(name="b")
    assert a.slave.dll._handle == b.slave.dll._handle, "both instances must live in the same loaded library"
    a.initialize(ramp=1.0)
    b.initialize(ramp=0.0)
    a.set("run", True)
    a.set("speed_setpoint", 2.0)
    b.set("run", True)
    b.set("speed_setpoint", -1.0)
    for _ in range(3):
        a.step(0.1)
        b.step(0.1)
    assert a.get("speed") == pytest.approx(0.3, abs=1e-12)
    assert b.get("speed") == -1.0
    b.close()
    a.step(0.1)
    assert a.get("speed") == pytest.approx(0.4, abs=1e-12)


def test_probe_gets_and_sets_every_type(probe):
    p = probe()
    p.initialize(limit=2, label="plant")
    assert p.get("greeting") == "hello plant", "calculated output computed at initialization"
    p.set("x", 1.5)
    p.step(0.5)
    assert (p.get("y"), p.get("count"), p.get("time")) == (3.0, 1, 0.5)
    p.set("gain", -1.0)  # tunable: allowed in step mode
    p.set("label", "again")
    p.step(0.5)
    p.step(0.5)
    assert (p.get("y"), p.get("count"), p.get("greeting")) == (-1.5, 2, "hello again")
    p.set("enable", False)
    assert p.get("enable") is False


def test_calculated_output_can_be_read_during_initialization(probe):
    p = probe()
    p.set("label", "early")
    if p.version == 2:
        p.slave.setupExperiment(startTime=0.0)
    p.slave.enterInitializationMode()
    assert p.get("greeting") == "hello early"


def test_unknown_value_reference_is_an_error_naming_it(belt):
    b = belt()
    b.initialize()
    get = b.slave.getReal if b.version == 2 else b.slave.getFloat64
    with pytest.raises(FMICallException):
        get([99])
    assert b.errors[-1].endswith("unknown value reference 99 (this model has 0 to 5)")


def test_wrong_type_is_an_error_naming_the_variable(belt):
    b = belt()
    b.initialize()
    get = b.slave.getReal if b.version == 2 else b.slave.getFloat64
    with pytest.raises(FMICallException):
        get([b.variables["run"].valueReference])
    assert "value reference 1 is the Boolean variable 'run', not " in b.errors[-1]


@pytest.mark.parametrize("name, value, message", [
    ("speed", 1.0, "output 'speed' (value reference 4) cannot be set after initialization"),
    ("ramp", 1.0, "fixed parameter 'ramp' (value reference 3) cannot be set after initialization"),
    ("time", 1.0, "independent variable 'time' (value reference 0) cannot be set"),
    ("speed_setpoint", float("nan"), "'speed_setpoint' (value reference 2) cannot be nan"),
])
def test_set_rules_are_enforced_in_step_mode(belt, name, value, message):
    b = belt()
    b.initialize()
    with pytest.raises(FMICallException):
        b.set(name, value)
    assert message in b.errors[-1]


def test_values_outside_min_max_are_refused(belt, probe):
    b = belt()
    with pytest.raises(FMICallException):
        b.set("ramp", -0.5)
    assert "'ramp' (value reference 3) = -0.5 is below its minimum 0" in b.errors[-1]
    p = probe()
    with pytest.raises(FMICallException):
        p.set("limit", 11)
    assert "'limit' (value reference 5) = 11 is above its maximum 10" in p.errors[-1]


def test_error_state_refuses_steps_until_reset(belt):
    b = belt()
    b.initialize()
    with pytest.raises(FMICallException):
        b.set("speed", 1.0)
    with pytest.raises(FMICallException):
        b.step(0.1)
    assert "not allowed in the error state" in b.errors[-1]
    b.slave.reset()
    b.initialize(ramp=0.0)
    b.set("run", True)
    b.set("speed_setpoint", 0.7)
    b.step(0.1)
    assert b.get("speed") == 0.7


def test_step_from_another_time_is_refused(belt):
    b = belt()
    b.initialize()
    b.step(0.1)
    with pytest.raises(FMICallException):
        b.slave.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.1)
    assert "step from t = 0.5 but the instance is at t = 0.1" in b.errors[-1]


def test_call_in_wrong_phase_names_function_and_phase(belt):
    b = belt()
    with pytest.raises(FMICallException):
        b.step(0.1)
    assert b.errors[-1] == f"fmi{b.version}DoStep: not allowed in the instantiated state"


def test_wrong_token_refuses_to_instantiate(belt):
    messages = []
    with pytest.raises(Exception, match="instantiate"):
        belt(token="{00000000-0000-0000-0000-000000000000}", messages=messages)
    assert "does not match" in messages[-1][2]


def test_events_are_logged_only_when_their_category_is_on(belt):
    b = belt()
    b.initialize(ramp=0.0)
    b.set("run", True)
    b.set("speed_setpoint", 1.0)
    b.step(0.1)
    assert ("logEvents", "speed reached 1 m/s at t = 0.1 s") in [(c, m) for _, c, m in b.messages]
    b.slave.setDebugLogging(False, ["logEvents"])
    b.set("run", False)
    count = len(b.messages)
    b.step(0.1)
    assert len(b.messages) == count
    with pytest.raises(FMICallException):
        b.slave.setDebugLogging(True, ["logEverything"])
    assert "unknown log category 'logEverything'" in b.errors[-1]


def test_fmi2_messages_escape_printf_and_reference_characters(belt):
    # The FMI 2 logger takes the message as a printf format in which #...# names a variable.
    b = belt()
    with pytest.raises(FMICallException):
        b.slave.setDebugLogging(True, ["100% #1#"])
    expected = "'100%% ##1##'" if b.version == 2 else "'100% #1#'"
    assert expected in b.errors[-1]
