"""The wire format: slot value codecs, control messages checked against schemas/wire.schema.json."""
import json
import math
import struct

import jsonschema
import pytest

from hub.bus import wire
from hub.bus.commands import command_message
from hub.core.slots import SlotRef, SlotType

from .helpers import ROOT

SCHEMA = json.loads((ROOT / "schemas" / "wire.schema.json").read_text())


def check(definition: str, message) -> None:
    schema = {**SCHEMA, "$ref": f"#/$defs/{definition}"}
    jsonschema.Draft202012Validator(schema).validate(message)


@pytest.mark.parametrize("kind, value, size", [
    (SlotType.BOOL, True, 1), (SlotType.INT, -(2**40), 8), (SlotType.REAL, 0.1, 8),
    (SlotType.VEC3, (1.0, -0.0, 1e-300), 24), (SlotType.QUAT, (0.0, 0.0, 0.0, 1.0), 32),
    (SlotType.STRING, "Flasche-17 ✓", None), (SlotType.VOID, None, 0)])
def test_data_plane_values_are_raw_little_endian_and_round_trip_exactly(kind, value, size):
    data = wire.value_packer(kind)(value)
    if size is not None:
        assert len(data) == size
    assert wire.unpack_value(kind, data) == value
    assert wire.value_encoding(kind) == f"zenoh/bytes;planthub/{kind.value}"


def test_a_real_is_the_ieee_double_little_endian():
    assert wire.value_packer(SlotType.REAL)(0.5) == struct.pack("<d", 0.5) == bytes.fromhex("000000000000e03f")
    assert math.copysign(1, wire.unpack_value(SlotType.REAL, wire.value_packer(SlotType.REAL)(-0.0))) == -1


def test_keys():
    assert wire.data_key("line1", SlotRef("belt", "drive", "speed")) == "plant/line1/belt/drive/speed"
    assert wire.logic_key("line1", "drive", "step") == "plant/line1/@cosim/logic/drive/step"
    assert wire.hub_token("line1") == "plant/line1/@cosim/hub"
    with pytest.raises(wire.WireError, match=r"run name 'a/b' cannot be a Zenoh key chunk"):
        wire.check_run_name("a/b")


def test_step_and_output_messages_follow_the_schema_and_keep_every_bit():
    step = wire.step_message(3, 9, 3, 0.06, 0.02, [True, 0.1, [1.0, 2.0, 3.0]])
    n, tick, ticks, t, h, inputs = wire.read_step(step)
    assert (n, tick, ticks, t, h) == (3, 9, 3, 0.06, 0.02) and inputs == [True, 0.1, [1.0, 2.0, 3.0]]
    check("step", wire.unpack(step))
    check("output", wire.unpack(wire.output_message(-1, [0.0, False])))
    check("output", wire.unpack(wire.error_message(4, "ZeroDivisionError")))
    x = 0.1 + 0.2   # 0.30000000000000004: msgpack keeps the float64 as it is
    assert wire.unpack(wire.output_message(0, [x]))[1][0] == x


def test_values_from_the_wire_are_checked_and_named():
    assert wire.from_wire(SlotType.REAL, 1, "x") == 1.0 and isinstance(wire.from_wire(SlotType.REAL, 1, "x"), float)
    assert wire.from_wire(SlotType.VEC3, [1, 2, 3], "p") == (1.0, 2.0, 3.0)
    with pytest.raises(wire.WireError, match=r"output 'speed' of step 2: expected a real, got 'fast'"):
        wire.from_wire(SlotType.REAL, "fast", "output 'speed' of step 2")
    with pytest.raises(wire.WireError, match=r"input 'run': expected a bool, got 1"):
        wire.from_wire(SlotType.BOOL, 1, "input 'run'")
    with pytest.raises(wire.WireError, match=r"step message: expected \[n, tick, ticks, t, h, inputs\]"):
        wire.read_step(wire.pack({"n": 1}))
    with pytest.raises(wire.WireError, match=r"not a msgpack message"):
        wire.unpack(b"\xc1")


def test_commands_follow_the_schema():
    check("command", wire.unpack(command_message("set", "belt.drive.speed", 0.2, "hmi", "42")))
    check("command", wire.unpack(command_message("force", "stopper.gate.position", (0.0, 0.0, 1.0))))
    check("command", wire.unpack(command_message("stop")))


def test_readers_take_the_right_type_fast_and_name_the_wrong_one():
    assert wire.reader(SlotType.REAL)(0.25) == 0.25 and wire.reader(SlotType.REAL)(2) == 2.0
    assert wire.reader(SlotType.VEC3)([0, 1.5, 2]) == (0.0, 1.5, 2.0)
    with pytest.raises(wire.WireError, match=r"value: expected a bool, got 1"):
        wire.reader(SlotType.BOOL)(1)
