"""Property-based: whatever bytes, documents or commands arrive, the answer is the project's error or
a valid result — never another exception, never a hang. Examples are derived deterministically
(derandomize), so CI runs the same cases every time within a bounded budget."""
from __future__ import annotations

import msgpack
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hub.bus import wire
from hub.bus.commands import CommandError, Commands
from hub.core.errors import ScenarioError
from hub.core.slots import SlotType
from hub.run.plant import Plant
from hub.scenario.checker import load_scenario

from .helpers import ROOT

BUDGET = settings(max_examples=300, deadline=None, derandomize=True,
                  suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
SCENES = ["stop_at_barrier", "belt_bottle_sensor", "switch", "source_sink", "switch_logic"]

values = st.recursive(st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.floats() | st.text(max_size=20)
                      | st.binary(max_size=20),
                      lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner, max_size=5),
                      max_leaves=20)


@BUDGET
@given(st.binary(max_size=200))
def test_any_bytes_decode_to_a_message_or_a_wire_error(data):
    for decode in (wire.unpack, wire.read_step):
        try:
            decode(data)
        except wire.WireError:
            pass


@BUDGET
@given(st.sampled_from(list(SlotType)), st.binary(max_size=40))
def test_any_sample_decodes_to_its_value_or_a_wire_error(kind, data):
    try:
        wire.unpack_value(kind, data)
    except wire.WireError:
        pass


@BUDGET
@given(st.sampled_from(list(SlotType)), values)
def test_any_value_in_a_message_is_its_slot_type_or_a_wire_error(kind, value):
    try:
        wire.from_wire(kind, value, "output 'x'")
        wire.reader(kind)(value)
    except wire.WireError:
        pass


@BUDGET
@given(values)
def test_any_hello_interface_is_read_or_refused_with_a_wire_error(entries):
    try:
        wire.read_interface(entries, "inputs")
    except wire.WireError:
        pass


packable = st.recursive(st.none() | st.booleans() | st.integers(-2**63, 2**64 - 1) | st.floats() | st.text(max_size=20)
                        | st.binary(max_size=20),
                        lambda inner: st.lists(inner, max_size=7) | st.dictionaries(st.text(max_size=8), inner, max_size=5),
                        max_leaves=20)


@BUDGET
@given(packable)
def test_any_packed_value_is_read_as_a_step_or_a_wire_error(message):
    try:
        wire.read_step(msgpack.packb(message, use_bin_type=True))
    except wire.WireError:
        pass


@pytest.fixture(scope="module")
def commands():
    with Plant(load_scenario(ROOT / "scenarios" / "stop_at_barrier.yaml")) as plant:
        yield Commands(plant, recorder=None)


@BUDGET
@given(st.dictionaries(st.sampled_from(["op", "slot", "value", "by", "id"]),
                       st.sampled_from(["set", "force", "release", "stop", "belt.drive.speed", "belt.drive.run",
                                        "barrier.trigger.occupied", "nope.x.y", ""]) | values, max_size=5))
def test_any_command_is_parsed_or_refused_with_a_command_error(commands, message):
    try:
        commands.parse(message)
    except CommandError:
        pass


def mutate(text: str, data) -> str:
    """A few random edits of a scenario text: cut, insert, duplicate or swap lines and characters."""
    for _ in range(data.draw(st.integers(1, 4))):
        what = data.draw(st.sampled_from(["cut", "insert", "line", "swap"]))
        at = data.draw(st.integers(0, max(0, len(text) - 1)))
        if what == "cut":
            text = text[:at] + text[at + data.draw(st.integers(1, 12)):]
        elif what == "insert":
            text = text[:at] + data.draw(st.text(alphabet=st.sampled_from(list(":-[]{}&*!|>'\"#,. \n\t0123456789aeInf~")),
                                                 max_size=6)) + text[at:]
        else:
            lines = text.split("\n")
            i, j = (data.draw(st.integers(0, len(lines) - 1)) for _ in range(2))
            if what == "line":
                lines.insert(j, lines[i])
            else:
                lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
    return text


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(st.sampled_from(SCENES), st.data())
def test_a_mutated_scenario_loads_or_gives_a_scenario_error(tmp_path, name, data):
    """Relative paths (an FMU file) then point nowhere: that too must be a ScenarioError."""
    path = tmp_path / f"{name}.yaml"
    path.write_text(mutate((ROOT / "scenarios" / f"{name}.yaml").read_text(), data))
    try:
        load_scenario(path)
    except ScenarioError as exc:
        assert exc.problems and all(p.file in (str(path), "--set") for p in exc.problems)
