"""Property-based: whatever bytes, documents or commands arrive, the answer is the project's error or
a valid result — never another exception, never a hang. Examples are derived deterministically
(derandomize), so CI runs the same cases every time within a bounded budget."""
from __future__ import annotations

import functools
import json
import string

import msgpack
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis_jsonschema import from_schema

from hub.bus import wire
from hub.bus.commands import CommandError, Commands
from hub.core.errors import ScenarioError
from hub.core.registry import default_registry
from hub.core.resources import SCHEMAS
from hub.core.slots import SlotType
from hub.run.plant import Plant
from hub.scenario.checker import Scenario, load_scenario

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


# --- whole documents from the JSON Schemas ---------------------------------------------------------
# hypothesis-jsonschema makes the values of every schema but an object's: its object strategy
# (0.23.1) drives a private Hypothesis API (`many.more()`) that Hypothesis 6.170 no longer has. So
# objects are composed here, from their properties, required keys and additional properties, now
# and then with a key the schema does not know; everything inside them — numbers within their
# bounds, names by their patterns, enums, lists — comes from hypothesis-jsonschema.

any_value = st.recursive(st.none() | st.booleans() | st.integers(-2**40, 2**40) | st.floats() | st.text(max_size=12),
                         lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner,
                                                                                      max_size=4),
                         max_leaves=12)
unknown_keys = st.text(alphabet=string.ascii_lowercase + "_", min_size=1, max_size=8)


@functools.cache
def _leaf(schema: str) -> st.SearchStrategy:
    return from_schema(json.loads(schema), allow_x00=False)


def inlined(schema, defs: dict):
    """`schema` with each local reference (`{"$ref": "#/$defs/slot"}`) replaced by what it names."""
    if isinstance(schema, dict):
        if "$ref" in schema:
            return inlined(defs[schema["$ref"].rsplit("/", 1)[1]], defs)
        return {k: inlined(v, defs) for k, v in schema.items() if k != "$defs"}
    return [inlined(v, defs) for v in schema] if isinstance(schema, list) else schema


def _holds_objects(schema: dict) -> bool:
    kind = schema.get("type")
    kinds = kind if isinstance(kind, list) else [kind]
    return "object" in kinds or "array" in kinds and _holds_objects(schema.get("items", {})) or (
        kind is None and "enum" not in schema and "const" not in schema)


def schema_values(schema: dict) -> st.SearchStrategy:
    """Values of a JSON Schema without references (`inlined`)."""
    kind = schema.get("type")
    if isinstance(kind, list):
        return st.one_of([schema_values({**schema, "type": k}) for k in kind])
    if kind == "object":
        return _objects(schema)
    if kind == "array" and _holds_objects(schema.get("items", {})):
        low = schema.get("minItems", 0)
        return st.lists(schema_values(schema.get("items", {})), min_size=low,
                        max_size=max(low, min(schema.get("maxItems", 3), 3)))
    if _holds_objects(schema):
        return any_value
    return _leaf(json.dumps(schema, sort_keys=True))


def _objects(schema: dict) -> st.SearchStrategy:
    properties = schema.get("properties", {})
    required = {k: schema_values(properties.get(k, {})) for k in schema.get("required", [])}
    optional = {k: schema_values(v) for k, v in properties.items() if k not in required}
    known = st.fixed_dictionaries(required, optional=optional)
    extra = schema.get("additionalProperties", True)
    if extra is False:   # one time in five, a key the checker must name as unknown
        stranger = st.dictionaries(unknown_keys, any_value, min_size=1, max_size=1)
        return st.tuples(known, st.integers(0, 4), stranger).map(lambda t: {**t[2], **t[0]} if t[1] == 0 else t[0])
    # Names are strings whatever their schema says: `{"pattern": …}` alone would be any value.
    names = schema_values({"type": "string", **schema["propertyNames"]}) if "propertyNames" in schema \
        else unknown_keys
    more = st.dictionaries(names, schema_values(extra) if isinstance(extra, dict) else any_value,
                           min_size=schema.get("minProperties", 0), max_size=3)
    return st.tuples(known, more).map(lambda t: {**t[1], **t[0]})


REGISTRY = default_registry()
MODULES = REGISTRY.names()
SCENARIO_SCHEMA = json.loads((SCHEMAS / "scenario.schema.json").read_text())
object_names = st.from_regex(r"\A[a-z][a-z0-9_]{0,6}\Z")


def module_object(name: str) -> st.SearchStrategy:
    """One object of the module `name`, its parameters drawn from the module's own schema."""
    return schema_values(REGISTRY.get(name).PARAMETERS).map(lambda params: {**params, "module": name})


module_objects = st.dictionaries(object_names, st.sampled_from(MODULES).flatmap(module_object), min_size=1, max_size=3)
documents = st.tuples(schema_values(inlined(SCENARIO_SCHEMA, SCENARIO_SCHEMA["$defs"])), module_objects).map(
    lambda t: {**t[0], "objects": t[1]})


def loads_or_names_its_problems(path, document) -> None:
    """The checker's answer to `document`, written to `path` as YAML: a Scenario, or a
    ScenarioError each of whose problems names this file and a place in it."""
    path.write_text(yaml.safe_dump(document, allow_unicode=True, sort_keys=False), encoding="utf-8")
    try:
        assert isinstance(load_scenario(path), Scenario)
    except ScenarioError as exc:
        assert exc.problems
        for problem in exc.problems:
            assert problem.file == str(path) and (problem.line or problem.path), problem


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.filter_too_much, HealthCheck.data_too_large])
@given(st.sampled_from(MODULES).flatmap(module_object))
def test_an_object_from_its_modules_schema_loads_or_gives_a_scenario_error(tmp_path, params):
    """Each module's parameters as its schema allows them (and now and then a key it does not know),
    in a scenario of one object: the meaning checks behind the schema see them all."""
    loads_or_names_its_problems(tmp_path / "scene.yaml", {"planthub": 1, "run": {"duration": 0.5},
                                                          "objects": {"x": params}})


@settings(max_examples=100, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.filter_too_much, HealthCheck.data_too_large])
@given(documents)
def test_a_document_from_the_scenario_schema_loads_or_gives_a_scenario_error(tmp_path, document):
    """Run settings, bus, flows, records and expectations from the scenario schema, objects from the
    modules' schemas."""
    loads_or_names_its_problems(tmp_path / "scene.yaml", document)
