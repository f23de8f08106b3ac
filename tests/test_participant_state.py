"""A participant's whole state saved and restored, in the hub's process and over the bus (a real Zenoh session on loopback), the bytes of either transport restored by the other; failures named."""
from __future__ import annotations

import contextlib
import json
import struct
import sys

import jsonschema
import pytest

from hub.bus import wire
from hub.bus.lockstep import Lockstep, RemoteSpec, pid_of
from hub.bus.session import Bus
from hub.bus.settings import BusSettings
from hub.core.errors import CheckpointError
from hub.core.slots import SlotType
from hub.logic.inprocess import InProcessSlave
from hub.logic.participant_state import pack_state, read_state
from hub.logic.remote import RemoteSlave
from modules.plant_control import PlantControl
from tests.participants.stateful import INPUTS, KINDS, OUTPUTS

from .helpers import ROOT

RUN = "state_test"
RATE = 100
STEP = 1   # tick per communication step
SPEC = RemoteSpec("counter", tuple((n, SlotType(k)) for n, k in INPUTS.items()),
                  tuple((n, SlotType(k)) for n, k in OUTPUTS.items()), parameters={"keep": 2}, join_timeout=30.0)
LANES = ["A", "B", "C", "D", "E"]
CONTROL = RemoteSpec(
    "control", tuple([(f"r{i}_read", SlotType.VOID) for i in range(1, 6)]
                     + [(f"r{i}_destination", SlotType.STRING) for i in range(1, 6)]),
    tuple([(f"sw{i}_work", SlotType.VOID) for i in range(1, 6)] + [(f"sw{i}_base", SlotType.VOID) for i in range(1, 6)]),
    join_timeout=30.0)


def counter_inputs(k: int) -> list:
    return [k * 0.37 + 1e-3, k % 3 == 0, f"L{k % 4}"]


def control_inputs(k: int) -> list:
    """Reader i reads a bottle every few steps, for a lane that changes with k."""
    return [(k + i) % 4 == 0 for i in range(5)] + [LANES[(k * 7 + i) % 5] if (k + i) % 4 == 0 else "" for i in range(5)]


def drive(slave, first: int, last: int, inputs=counter_inputs) -> list[bytes]:
    """Steps `first` … `last` - 1; each point's outputs as bytes (every bit of every value)."""
    out = []
    for k in range(first, last):
        slave.set_inputs(inputs(k))
        slave.step(k * STEP / RATE, STEP / RATE)
        out.append(wire.pack([list(v) if isinstance(v, tuple) else v for v in slave.outputs()]))
    return out


def in_process(kind: str = "counter", spec: RemoteSpec = SPEC):
    logic = PlantControl(LANES) if kind == "control" else KINDS[kind]()
    return InProcessSlave(spec, logic)


DRIVE = RemoteSpec("drive", (("run", SlotType.BOOL), ("speed_setpoint", SlotType.REAL)),
                   (("speed", SlotType.REAL), ("running", SlotType.BOOL)), parameters={"ramp": 0.5}, join_timeout=30.0)


def drive_inputs(k: int) -> list:
    return [k % 40 < 25, 0.1 + (k % 7) * 0.05]


@contextlib.contextmanager
def on_bus(kind: str = "counter", spec: RemoteSpec = SPEC, lease: float = 1.0):
    """A slave whose participant process the lockstep launches (and stops, whatever happens)."""
    if kind == "control":
        command = (sys.executable, "-m", "modules.plant_control", "--lanes", ",".join(LANES))
    elif kind == "from_the_doc":
        command = (sys.executable, "-m", "tests.participants.from_the_doc")
    else:
        command = (sys.executable, "-m", "tests.participants.stateful", kind)
    spec = RemoteSpec(spec.name, spec.inputs, spec.outputs, spec.parameters, command=command, cwd=str(ROOT),
                      join_timeout=spec.join_timeout)
    slave = RemoteSlave(spec, RATE)
    with Bus(BusSettings(lease=lease)) as bus:
        lockstep = Lockstep(bus, RUN, [slave], lease=lease, on_loss="stop", rate=RATE)
        try:
            lockstep.start()
            assert pid_of(slave) is not None   # a process of its own, on the bus
            yield slave
        finally:
            lockstep.close("test over")


def test_in_process_a_restored_participant_steps_on_bit_for_bit():
    slave = in_process()
    drive(slave, 0, 12)
    state = slave.save()
    later = drive(slave, 12, 30)
    slave.restore(state)
    assert drive(slave, 12, 30) == later
    fresh = in_process()   # a slave made the same way, never stepped: the same again
    fresh.restore(state)
    assert drive(fresh, 12, 30) == later
    assert fresh.logic.alias is fresh.logic.seen   # shared before the save, shared after the restore


def test_over_the_bus_a_restored_participant_steps_on_bit_for_bit_and_matches_in_process():
    reference = in_process()
    expected = drive(reference, 0, 30)
    with on_bus() as slave:
        assert drive(slave, 0, 12) == expected[:12]
        state = slave.save()
        later = drive(slave, 12, 30)
        slave.restore(state)
        again = drive(slave, 12, 30)
        assert slave.save() == slave.save()   # saving changes nothing: twice at one point, the same bytes
    assert later == again == expected[12:]


def test_a_state_saved_in_process_resumes_over_the_bus_and_back():
    """Saved with the logic in the hub, restored into a participant process that has just joined
    (its slave never stepped), and the other way round: the run goes on as if nothing had moved."""
    slave = in_process()
    drive(slave, 0, 15)
    state = slave.save()
    expected = drive(slave, 15, 30)
    with on_bus() as remote:
        remote.restore(state)
        assert drive(remote, 15, 30) == expected
        saved_on_bus = remote.save()
    back = in_process()
    back.restore(saved_on_bus)
    assert drive(back, 30, 40) == drive(slave, 30, 40)


def test_after_a_restore_the_outputs_are_those_of_the_saved_point_events_included():
    slave = in_process()
    outputs = []
    for k in range(12):   # up to a step at which the queue popped: the event is in that step's outputs
        outputs = drive(slave, k, k + 1)[0]
        if wire.unpack(outputs)[3]:
            break
    state = slave.save()
    drive(slave, k + 1, k + 5)
    with on_bus() as remote:
        remote.restore(state)
        assert wire.pack([list(v) if isinstance(v, tuple) else v for v in remote.outputs()]) == outputs
    slave.restore(state)
    assert wire.pack([list(v) if isinstance(v, tuple) else v for v in slave.outputs()]) == outputs
    assert wire.unpack(outputs)[3] is True


def test_the_plant_control_participant_saves_and_restores_with_the_default():
    """The bottling plant's router (modules/plant_control.py), in the hub and launched on the bus."""
    slave = in_process("control", CONTROL)
    drive(slave, 0, 9, control_inputs)
    state = slave.save()
    later = drive(slave, 9, 40, control_inputs)
    assert any(b"\xc3" in point for point in later)   # it did command switches (msgpack true)
    slave.restore(state)
    assert drive(slave, 9, 40, control_inputs) == later
    with on_bus("control", CONTROL) as remote:
        remote.restore(state)
        assert drive(remote, 9, 40, control_inputs) == later
        drive(remote, 40, 50, control_inputs)
        remote.restore(state)
        assert drive(remote, 9, 40, control_inputs) == later


def test_a_participant_written_from_the_wire_document_saves_and_restores_its_own_bytes():
    """tests/participants/from_the_doc.py: save and restore from schemas/wire.md item 9 alone, with
    a state of its own making (not pickle)."""
    with on_bus("from_the_doc", DRIVE) as remote:
        drive(remote, 0, 30, drive_inputs)
        state = remote.save()
        later = drive(remote, 30, 90, drive_inputs)
        remote.restore(state)
        assert drive(remote, 30, 90, drive_inputs) == later
    assert len(set(later)) > 10   # the ramp moved


def test_a_participant_whose_state_cannot_be_saved_is_named():
    slave = in_process("unsaveable")
    drive(slave, 0, 3)
    with pytest.raises(CheckpointError) as info:
        slave.save()
    assert str(info.value) == (
        "participant 'counter' (in-process) could not save its state: Unsaveable cannot save attribute 'guard' "
        "(TypeError: cannot pickle '_thread.lock' object); override save_state and restore_state for state that "
        "pickle cannot take")
    with on_bus("unsaveable") as remote:
        drive(remote, 0, 3)
        with pytest.raises(CheckpointError) as info:
            remote.save()
        assert str(info.value).startswith(
            "participant 'counter' could not save its state: Unsaveable cannot save attribute 'guard' "
            "(TypeError: cannot pickle '_thread.lock' object); override save_state and restore_state for state "
            "that pickle cannot take (at t = 0.03 s)")
        assert len(drive(remote, 3, 6)) == 3   # a failed save ends nothing: the run may go on


def test_a_participant_that_never_answers_a_save_is_named_within_the_lease():
    """An older participant does not know the message: it never answers, and the hub stops waiting at the lease."""
    with on_bus("old", lease=0.5) as remote:
        drive(remote, 0, 2)
        with pytest.raises(CheckpointError) as info:
            remote.save()
        assert str(info.value).startswith(
            "participant 'counter' did not answer the save request within its lease of 0.5 s (at t = 0.02 s): "
            "it is frozen, or an older participant that does not know the message (schemas/wire.md, "
            "\"Save and restore\")")
        assert len(drive(remote, 2, 4)) == 2


def test_a_state_that_does_not_fit_is_refused_before_it_reaches_the_participant():
    slave = in_process()
    drive(slave, 0, 3)
    state = slave.save()
    other = RemoteSpec("other", SPEC.inputs, SPEC.outputs)
    with pytest.raises(CheckpointError, match="the state of participant 'counter'"):
        InProcessSlave(other, KINDS["counter"]()).restore(state)
    with pytest.raises(CheckpointError, match=r"^participant 'control' \(in-process\): the saved state does not fit"):
        in_process("control", CONTROL).restore(state)
    with pytest.raises(CheckpointError, match="Counter cannot read the saved state"):
        slave.restore(pack_state(SPEC, [], read_state(SPEC, state, "x")[1], b"\x80\x05junk"))
    with pytest.raises(CheckpointError, match="the saved state is a Counter's"):
        InProcessSlave(SPEC, KINDS["old"]()).restore(state)


# --- the messages, as schemas/wire.md and wire.schema.json give them --------------------------
SCHEMA = json.loads((ROOT / "schemas" / "wire.schema.json").read_text())


@pytest.mark.parametrize("definition, body", [
    ("checkpoint", wire.save_request(3, 11)),
    ("checkpoint", wire.restore_request(4, -1, b"\x00\x01")),
    ("checkpoint_answer", wire.saved_answer(3, 11, b"state")),
    ("checkpoint_answer", wire.restored_answer(4, -1)),
    ("checkpoint_answer", wire.checkpoint_error("save", 3, 11, "cannot", "File x")),
])
def test_save_and_restore_messages_follow_the_schema(definition, body):
    message = wire.unpack(body)
    for key, value in message.items():   # JSON Schema has no type for raw bytes
        if isinstance(value, bytes):
            message[key] = "bytes"
    jsonschema.Draft202012Validator({**SCHEMA, "$ref": f"#/$defs/{definition}"}).validate(message)
    reader = wire.read_checkpoint if definition == "checkpoint" else wire.read_checkpoint_answer
    assert reader(body)["tag"] in (3, 4)


HOSTILE = [b"", b"\xc1", b"\x92\x01", wire.pack(7), wire.pack({"op": "save"}), wire.pack({"op": "jump", "tag": 1, "step": 0}),
           wire.pack({"op": "save", "tag": "1", "step": 0}), wire.pack({"op": "save", "tag": 1.0, "step": 0}),
           wire.pack({"op": "restore", "tag": 1, "step": 0, "state": "text"}),
           wire.pack({"op": "restore", "tag": 1, "step": 0, "ok": 1}), b"\x00" * (wire.MAX_STATE + 1),
           struct.pack(">BI", 0xdd, 0xffffffff), struct.pack(">BI", 0xc6, 0xffffffff)]
BAD_ANSWERS = [wire.pack({"op": "save", "tag": 1, "step": 0}), wire.pack({"op": "save", "tag": 1, "step": 0, "state": 5}),
               wire.pack({"op": "save", "tag": 1, "step": 0, "error": ["x"]}), wire.pack({"op": "restore", "tag": 1, "step": 0})]


@pytest.mark.parametrize("data", HOSTILE + [wire.pack({"op": "save", "tag": 1, "step": -2})])
def test_a_bad_checkpoint_request_gives_a_wire_error(data):
    with pytest.raises(wire.WireError):
        wire.read_checkpoint(data)


@pytest.mark.parametrize("data", HOSTILE + BAD_ANSWERS)
def test_a_bad_checkpoint_answer_gives_a_wire_error(data):
    with pytest.raises(wire.WireError):
        wire.read_checkpoint_answer(data)


@pytest.mark.parametrize("data", HOSTILE + [wire.pack({"format": "planthub.participant-slave/1", "name": "counter",
                                                       "inputs": [], "outputs": [1] * 6, "state": b""}), "text"])
def test_a_bad_saved_state_gives_a_checkpoint_error(data):
    with pytest.raises(CheckpointError):
        read_state(SPEC, data, "here")
    with pytest.raises(CheckpointError):
        in_process().restore(data)


def test_an_fmu_served_over_the_bus_saves_and_restores_its_fmu_state():
    """`planthub serve-fmu`: the participant's state is the FMU's own (FMI's FMU state, serialized)."""
    from .fmus.fmu_support import build

    fmu = build(ROOT / "build" / "fmus") / "belt_drive-fmi2.fmu"
    spec = RemoteSpec(DRIVE.name, DRIVE.inputs, DRIVE.outputs, DRIVE.parameters,
                      command=(sys.executable, "-m", "hub", "serve-fmu", str(fmu)), cwd=str(ROOT), join_timeout=30.0)
    slave = RemoteSlave(spec, RATE)
    with Bus(BusSettings()) as bus:
        lockstep = Lockstep(bus, RUN, [slave], lease=1.0, on_loss="stop", rate=RATE)
        try:
            lockstep.start()
            drive(slave, 0, 30, drive_inputs)
            state = slave.save()
            later = drive(slave, 30, 90, drive_inputs)
            slave.restore(state)
            assert drive(slave, 30, 90, drive_inputs) == later
        finally:
            lockstep.close("test over")
