"""FMU logic slaves saved, stepped on and restored (same instance, a new one, a worker) give the same outputs bit for bit."""
import struct

import msgpack
import pytest

from hub.core.errors import CheckpointError
from hub.logic.fmi import FmuSlave, inspect_fmu
from hub.logic.fmi_me import Integration, open_fmu
from hub.logic.isolated import IsolatedFmu
from hub.logic.ssp import read_ssp, start_values
from hub.logic.ssp_slave import SspSlave

from .fmus.fmu_support import TEST_MODELS_DIR, build
from .foreign_fmus import build as build_foreign
from .foreign_fmus import build_python_fmu
from .helpers import ROOT
from .ssp_archives import write_ssp

BUILT = ROOT / "build" / "fmus"
H = 0.02
SAVED_AT, END = 40, 110   # communication points: saved at the first, run on to the second

ROBOT_OUTPUTS = ["Request_tokens", "Idle_marked", "Picking_got", "Carrying_marked", "Placing_got", "Returning_tokens",
                 "Holding_marked"]
# model → (inputs, the inputs at point k, outputs, parameters): each input changes often, so that
# the steps after the checkpoint depend on the state (a ramp halfway, a timer armed, a cycle under way).
CASES = {
    "belt_drive": (["run", "speed_setpoint"], lambda k: [k % 37 < 25, 0.3 + 0.1 * (k % 5)], ["speed", "running"],
                   {"ramp": 0.7}),
    "timer": (["start"], lambda k: [k % 23 < 3], ["elapsed", "remaining"], {"period": 0.3}),
    "robot_arm": (["Request_put"], lambda k: [k % 45 == 0], ROBOT_OUTPUTS, {"pick_delay": 0.3, "carry_delay": 0.1}),
}


@pytest.fixture(scope="module")
def fmus():
    """The project's FMUs, brought up to date (free after `make fmus`)."""
    return build(BUILT)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    """The test-only `probe` model (a string input and output) for FMI 2 and 3."""
    return build(tmp_path_factory.mktemp("probe"), models_dir=TEST_MODELS_DIR)


@pytest.fixture(scope="module")
def foreign(tmp_path_factory):
    out = tmp_path_factory.mktemp("foreign")
    return {"ball2": build_foreign("ball2", 2, out), "enum2": build_foreign("enum2", 2, out),
            "typed3": build_foreign("typed3", 3, out)}


@pytest.fixture(scope="module")
def python_fmu(tmp_path_factory):
    """tests/fmu_models/python/belt_drive_py.py exported by PythonFMU, whose description declares no FMU state."""
    return build_python_fmu(tmp_path_factory.mktemp("pythonfmu"))


def bits(rows):
    """Rows of outputs with every float as its 64 bits: == then tells 0.0 from −0.0 and compares bit for bit."""
    return [[struct.pack("<d", v) if isinstance(v, float) else v for v in row] for row in rows]


def run(slave, inputs, first, last):
    """Step `slave` through points first → last with `inputs(k)` at point k: the outputs after each step."""
    out = []
    for k in range(first, last):
        slave.set_inputs(inputs(k))
        slave.step(k * H, H)
        out.append(slave.outputs())
    return bits(out)


def slave_of(path, name, case, kind=FmuSlave):
    inputs, _, outputs, parameters = case
    return kind(inspect_fmu(path), name, inputs, outputs, parameters)


@pytest.fixture
def closing():
    made = []
    yield lambda slave: made.append(slave) or slave
    for slave in made:
        slave.close()


def check_round_trip(make, inputs, closing):
    """Save at SAVED_AT, run on; restore into the same slave and into a new one: the same outputs, bit for bit."""
    first = closing(make("first"))
    run(first, inputs, 0, SAVED_AT)
    at_save = bits([first.outputs()])
    state = first.save()
    expected = run(first, inputs, SAVED_AT, END)
    assert len({tuple(map(repr, row)) for row in expected}) > 3   # the logic really moved after the save

    first.restore(state)
    assert bits([first.outputs()]) == at_save and first.time == SAVED_AT * H
    assert run(first, inputs, SAVED_AT, END) == expected

    fresh = closing(make("fresh"))
    fresh.restore(state)
    assert bits([fresh.outputs()]) == at_save
    assert run(fresh, inputs, SAVED_AT, END) == expected
    return state


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("model", sorted(CASES))
def test_a_restored_fmu_steps_on_bit_for_bit(fmus, model, version, closing):
    case = CASES[model]
    check_round_trip(lambda name: slave_of(fmus / f"{model}-fmi{version}.fmu", name, case), case[1], closing)


@pytest.mark.parametrize("version", [2, 3])
def test_string_variables_are_part_of_the_state(probe, version, closing):
    """probe: greeting = "hello " + label, count counts enabled steps; the label changes after the save."""
    case = (["x", "enable", "label"], lambda k: [0.5 * k - 7.0, k % 3 != 0, f"label {k // 7}"],
            ["y", "count", "greeting"], {"limit": 10})
    path = probe / f"probe-fmi{version}.fmu"
    check_round_trip(lambda name: slave_of(path, name, case), case[1], closing)


@pytest.mark.parametrize("model, version", [("belt_drive", 2), ("robot_arm", 3)])
def test_an_isolated_fmu_saves_and_restores_through_its_worker(fmus, model, version, closing):
    case, path = CASES[model], fmus / f"{model}-fmi{version}.fmu"
    state = check_round_trip(lambda name: slave_of(path, name, case, IsolatedFmu), case[1], closing)
    # The worker's bytes are an FmuSlave's: they restore in the hub's process, and back.
    here = closing(slave_of(path, "here", case))
    here.restore(state)
    expected = run(here, case[1], SAVED_AT, END)
    there = closing(slave_of(path, "there", case, IsolatedFmu))
    there.restore(here.save())
    assert run(there, case[1], END, END + 30) == run(here, case[1], END, END + 30)
    assert expected


def test_an_ssp_saves_every_component(closing, tmp_path, fmus):
    system = read_ssp(write_ssp(tmp_path / "timer_belt.ssp"))
    inputs = lambda k: [k % 50 in (3, 4), k % 70 > 5]   # blocked, go

    def make(name):
        return SspSlave(system, name, ["blocked", "go"], ["speed", "running", "done"], start_values(system, {}))

    check_round_trip(make, inputs, closing)


def test_model_exchange_with_euler_restores_its_solver_too(foreign, closing):
    interface = inspect_fmu(foreign["ball2"])
    euler = Integration(interface="model-exchange", solver="euler", max_step=0.005)
    make = lambda name: open_fmu(interface, name, [], ["h", "v", "bounces"], {}, integration=euler)
    check_round_trip(make, lambda k: [], closing)


def test_model_exchange_with_cvode_refuses_to_save(foreign, closing):
    interface = inspect_fmu(foreign["ball2"])
    ball = closing(open_fmu(interface, "ball", [], ["h"], {}, integration=Integration(interface="model-exchange")))
    with pytest.raises(CheckpointError) as info:
        ball.save()
    assert str(info.value) == (
        f"FMU instance 'ball' ({foreign['ball2']}): cannot save its state: it is integrated with cvode, whose history "
        f"between communication points (order, step size, Nordsieck array) fmpy's CVODE binding cannot save, so a "
        f"restored run would not be bit-identical; integrate it with solver: euler to checkpoint it")


def refusal(path, name, flag):
    return (f"FMU instance {name!r} ({path}): cannot save its state: its modelDescription.xml does not declare "
            f"{flag}=\"true\" for co-simulation, so it cannot be checkpointed")


def test_a_third_party_fmu_that_cannot_save_is_named_with_its_missing_flag(python_fmu, foreign, closing):
    case = CASES["belt_drive"]
    py = closing(slave_of(python_fmu, "py", case))
    run(py, case[1], 0, 5)
    with pytest.raises(CheckpointError) as info:
        py.save()
    assert str(info.value) == refusal(python_fmu, "py", "canGetAndSetFMUstate")
    with pytest.raises(CheckpointError) as info:
        py.restore(b"anything")
    assert str(info.value) == refusal(python_fmu, "py", "canGetAndSetFMUstate").replace("cannot save", "cannot restore")
    typed = closing(FmuSlave(inspect_fmu(foreign["typed3"]), "typed", [], [], {}))
    with pytest.raises(CheckpointError) as info:
        typed.save()
    assert str(info.value) == refusal(foreign["typed3"], "typed", "canGetAndSetFMUState")   # FMI 3's spelling
    isolated = closing(slave_of(python_fmu, "py2", case, IsolatedFmu))
    with pytest.raises(CheckpointError) as info:
        isolated.save()
    assert str(info.value) == refusal(python_fmu, "py2", "canGetAndSetFMUstate")


def test_an_ssp_with_a_component_that_cannot_save_refuses_whole(python_fmu, fmus, tmp_path, closing):
    archive = write_ssp(tmp_path / "py.ssp", fmus={"resources/timer.fmu": fmus / "timer-fmi2.fmu",
                                                   "resources/belt_drive.fmu": python_fmu})
    system = read_ssp(archive)
    ssp = closing(SspSlave(system, "ctl", ["blocked", "go"], ["speed", "running", "done"], start_values(system, {})))
    with pytest.raises(CheckpointError) as info:
        ssp.save()
    assert str(info.value).startswith("SSP instance 'ctl': a component cannot save its state: FMU instance "
                                      "'ctl.drive' (")
    assert "does not declare canGetAndSetFMUstate=\"true\"" in str(info.value)


def repacked(state: bytes, **changes) -> bytes:
    saved = msgpack.unpackb(state, raw=False)
    saved.update(changes)
    return msgpack.packb(saved, use_bin_type=True)


@pytest.mark.parametrize("version", [2, 3])
def test_bad_bytes_are_refused_naming_the_instance_and_the_cause(fmus, version, closing):
    case, other = CASES["timer"], CASES["belt_drive"]
    timer = closing(slave_of(fmus / f"timer-fmi{version}.fmu", "tick", case))
    run(timer, case[1], 0, SAVED_AT)
    good = timer.save()
    expected = run(timer, case[1], SAVED_AT, END)
    drive = closing(slave_of(fmus / f"belt_drive-fmi{version}.fmu", "drive", other))
    fmu_bytes = msgpack.unpackb(good, raw=False)["fmu"]
    prefix = "fmi2DeSerializeFMUstate" if version == 2 else "fmi3DeserializeFMUState"
    where = f"FMU instance 'tick' (timer-fmi{version}.fmu)"

    def refused(slave, data):
        with pytest.raises(CheckpointError) as info:
            slave.restore(data)
        return str(info.value)

    assert refused(timer, good[:-3]).startswith(f"{where}: the saved state cannot be read (")
    assert refused(timer, msgpack.packb({"format": "other"})) == (
        f"{where}: the saved state is not an FMU slave's (planthub.fmu-slave/1)")
    assert refused(drive, good) == (
        f"FMU instance 'drive' (belt_drive-fmi{version}.fmu): the saved state is of another FMU (guid "
        f"{inspect_fmu(fmus / f'timer-fmi{version}.fmu').guid}, co-simulation), not of this one (guid "
        f"{inspect_fmu(fmus / f'belt_drive-fmi{version}.fmu').guid}, co-simulation)")
    # The FMU's own bytes damaged inside a sound envelope: the FMU finds it and says why.
    corrupt = bytearray(fmu_bytes)
    corrupt[len(corrupt) // 2] ^= 0x40
    cases = {
        bytes(corrupt): "the serialized FMU state is corrupt (its checksum does not match)",
        fmu_bytes[:-1]: f"wrong size: the serialized FMU state says it has {len(fmu_bytes)} bytes but "
                        f"{len(fmu_bytes) - 1} were given (truncated or extended)",
        b"NOTSTATE" + fmu_bytes[8:]: "the bytes are not a serialized FMU state of this framework (bad magic)",
        fmu_bytes[:10]: "10 bytes are too few for a serialized FMU state (truncated?)",
    }
    for data, cause in cases.items():
        message = refused(timer, repacked(good, fmu=data))
        assert message.startswith(f"{where} at t = ") and f"{prefix} returned error" in message
        assert f"{prefix}: {cause}" in message
    # Another model's FMU bytes passed off as this one's: the token inside tells.
    drive_bytes = msgpack.unpackb(drive.save(), raw=False)["fmu"]
    message = refused(timer, repacked(good, fmu=drive_bytes))
    assert f"{prefix}: the serialized FMU state is of model 'belt_drive' (token " in message
    assert "not of this model 'timer' (token " in message
    # A failed restore leaves the instance in FMI's error state; a good state still brings it back.
    timer.restore(good)
    assert run(timer, case[1], SAVED_AT, END) == expected
