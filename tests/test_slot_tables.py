"""The slot table in each module's docstring lists exactly the slots the module declares.

Every module of the registry opens its module docstring (the one `planthub describe NAME`
prints) with a table `| slot | type | dir | meaning |`, right after the summary line. The test
compares its rows with `Module.slots(Module.with_defaults(params))` — component.slot, type and
direction; the meaning is prose — for the minimal parameters (the required ones, drawn from
the parameter schema and checked against it), and again for parameters that fill in the
parameter-dependent rows. The rows are read by these rules:

- `comp.slot | type | dir | …` is one slot. A type written as a parameter in backticks
  (constant's ``param `type` ``) is that parameter's value.
- A slot name in angle brackets or capitals (`logic.<input>`, `count.DEST`) stands for the
  slots parameters name: every slot of that component and direction that no other row lists
  must match one such row (and its type, where the row gives one), and the row must match at
  least one slot under the filling parameters.
- `comp.… | | | …` (or `comp.first …`, type and dir left empty) stands for a whole component
  whose slots another table lists: `see NAME` names a module (its table, of one component) and
  `the same slots` the component of the row above (a switch's two belts, a separator's two gates).

Referrals are for a component an element holds twice or takes from another module. A module
whose component is reused unchanged (a conveyor's belt drive in a curve, a gate in a stopper)
keeps its own full table: that table is what `planthub describe` shows, and this test holding
every table to the code is what keeps the copies from drifting. The files of the shared
components (modules/belt.py, gate.py, trigger.py) are no modules; a table in such a file is held
to the one component class the file declares slots for. A table nothing checks fails.
"""
from __future__ import annotations

import importlib
import inspect
import re
import sys
from dataclasses import dataclass

import jsonschema
import pytest

from hub.core.component import Component
from hub.core.registry import default_registry
from hub.core.resources import BUILT_FMUS
from hub.core.slots import SlotType

from .helpers import ROOT
from .ssp_archives import timer_belt

REGISTRY = default_registry()
HEADER = ["slot", "type", "dir", "meaning"]
TYPES = {t.value for t in SlotType}
PLACEHOLDER = re.compile(r"^(<[^>]+>|[A-Z][A-Z0-9_]*)$")
REFERRAL = re.compile(r"^(\w+)\.(\w+\s*)?(…|\.\.\.)$")

# Required parameters the schema alone cannot give a meaningful value: a real FMU, a slot type.
REQUIRED = {
    "constant": {"type": "vec3", "value": [0, 0, 1]},
    "fmu": {"file": str(BUILT_FMUS / "belt_drive-fmi2.fmu")},
    "ssp": {"file": str(timer_belt())},
}
# Parameters that fill in the rows that depend on parameters.
FILLING = {
    "sink": {"destinations": ["A", "B"]},
    "participant": {"inputs": {"x": "real", "go": "void"}, "outputs": {"done": "void", "n": "int"}},
}


@dataclass(frozen=True)
class Row:
    component: str
    slot: str
    type: str
    dir: str
    meaning: str

    @property
    def placeholder(self) -> bool:
        return bool(PLACEHOLDER.match(self.slot))


def slot_table(doc: str, where: str) -> list[list[str]] | None:
    """The cells of the rows of the docstring's slot table (None: it has none)."""
    lines = doc.splitlines()
    starts = [i for i, line in enumerate(lines) if cells(line) == HEADER]
    if not starts:
        return None
    first_table = next(i for i, line in enumerate(lines) if line.lstrip().startswith("|"))
    assert starts[0] == first_table == 2, \
        f"{where}: the docstring must open with its slot table, after the summary line"
    rows = []
    for line in lines[starts[0] + 2:]:
        if not line.lstrip().startswith("|"):
            break
        row = cells(line)
        assert len(row) == 4, f"{where}: a slot table row needs 4 cells: {line!r}"
        rows.append(row)
    return rows


def cells(line: str) -> list[str]:
    line = line.strip()
    if not (line.startswith("|") and line.endswith("|")):
        return []
    return [c.strip() for c in line[1:-1].split("|")]


def table_of(py_module, where: str) -> list[Row]:
    """A module file's slot table, referral rows replaced by the rows they stand for."""
    raw = slot_table(py_module.__doc__ or "", where)
    assert raw is not None, f"{where}: the module docstring has no `| slot | type | dir | meaning |` table"
    rows: list[Row] = []
    for slot, type_, dir_, meaning in raw:
        referral = REFERRAL.match(slot)
        if referral and not type_ and not dir_:
            rows += referred(referral.group(1), (referral.group(2) or "").strip(), meaning, rows, where)
            continue
        assert "." in slot, f"{where}: {slot!r} is not component.slot"
        component, name = slot.split(".", 1)
        assert meaning, f"{where}: {slot} has no meaning"
        rows.append(Row(component, name, type_, dir_, meaning))
    return rows


def referred(component: str, first: str, meaning: str, above: list[Row], where: str) -> list[Row]:
    see = re.search(r"\bsee (?:modules/)?(\w+)", meaning)
    if see:
        name = see.group(1)
        assert name in REGISTRY, f"{where}: {component}.… refers to {name!r}, which is no module"
        source = module_table(name)
    elif "the same slots" in meaning:
        assert above, f"{where}: {component}.… says 'the same slots' with no row above it"
        source = [r for r in above if r.component == above[-1].component]
    else:
        raise AssertionError(f"{where}: {component}.… names no table (`see MODULE` or `the same slots`)")
    assert len({r.component for r in source}) == 1, \
        f"{where}: {component}.… refers to a table of several components"
    assert not first or first in [r.slot for r in source], \
        f"{where}: {component}.{first} … is not in the table it refers to"
    return [Row(component, r.slot, r.type, r.dir, r.meaning) for r in source]


def module_table(name: str) -> list[Row]:
    cls = REGISTRY.get(name)
    return table_of(sys.modules[cls.__module__], f"modules/{name} ({cls.__module__})")


def minimal_parameters(name: str) -> dict:
    """The required parameters only, from the schema (an enum's first value, a number, a vector)."""
    schema = REGISTRY.get(name).PARAMETERS
    params = {}
    for key in schema.get("required", []):
        if key in REQUIRED.get(name, {}):
            params[key] = REQUIRED[name][key]
            continue
        prop = schema["properties"][key]
        if "enum" in prop:
            params[key] = prop["enum"][0]
        elif prop.get("type") == "array" and prop.get("items", {}).get("type") == "number":
            params[key] = [0.5] * prop.get("minItems", 1)
        elif prop.get("type") in ("number", "integer"):
            params[key] = max(1, prop.get("minimum", 1))
        else:
            raise AssertionError(f"test_slot_tables.py: give {name}'s required {key!r} a value in REQUIRED")
    jsonschema.validate(params, schema)
    return params


def expected(name: str, params: dict) -> dict[tuple[str, str], tuple[str, str]]:
    cls = REGISTRY.get(name)
    return {(comp, s.name): (s.type.value, s.direction.value)
            for comp, slots in cls.slots(cls.with_defaults(params)).items() for s in slots}


def problems(rows: list[Row], slots: dict, params: dict) -> tuple[list[str], set[Row]]:
    """What differs between the table and the slots; and the placeholder rows that matched."""
    out, used = [], set()
    fixed = {(r.component, r.slot): r for r in rows if not r.placeholder}
    for key, (type_, dir_) in slots.items():
        row = fixed.get(key)
        if row is None:
            family = [r for r in rows if r.placeholder and r.component == key[0] and r.dir == dir_
                      and (r.type not in TYPES or r.type == type_)]
            if family:
                used.add(family[0])
            else:
                out.append(f"{'.'.join(key)} ({type_} {dir_}) is not in the table")
            continue
        table_type = row.type
        parameter = re.search(r"`(\w+)`", row.type)
        if row.type not in TYPES and parameter:
            table_type = params.get(parameter.group(1), f"parameter {parameter.group(1)!r} (not given)")
        if (table_type, row.dir) != (type_, dir_):
            out.append(f"{'.'.join(key)}: the table says {row.type} {row.dir}, the module {type_} {dir_}")
    out += [f"{r.component}.{r.slot} is in the table, not among the slots" for k, r in fixed.items() if k not in slots]
    return out, used


@pytest.mark.parametrize("name", REGISTRY.names())
def test_the_table_lists_exactly_the_modules_slots(name):
    rows = module_table(name)
    params = minimal_parameters(name)
    found, _ = problems(rows, expected(name, params), params)
    assert not found, f"{REGISTRY.get(name).__module__}: " + "; ".join(found)


def with_parameter_named_rows() -> list[str]:
    return [name for name in REGISTRY.names() if any(r.placeholder for r in module_table(name))]


@pytest.mark.parametrize("name", with_parameter_named_rows())
def test_every_row_standing_for_parameter_named_slots_names_some(name):
    rows = module_table(name)
    params = {**minimal_parameters(name), **FILLING.get(name, {})}
    found, used = problems(rows, expected(name, params), params)
    assert not found, f"{REGISTRY.get(name).__module__}: " + "; ".join(found)
    unused = [f"{r.component}.{r.slot}" for r in rows if r.placeholder and r not in used]
    assert not unused, (f"{REGISTRY.get(name).__module__}: {', '.join(unused)} named no slot: give {name} "
                        "parameters that fill them in FILLING")


def tables_outside_modules() -> list[str]:
    """The files under modules/ whose docstring has a slot table but that hold no registry module."""
    of_modules = {REGISTRY.get(name).__module__ for name in REGISTRY.names()}
    files = sorted(".".join(p.relative_to(ROOT).with_suffix("").parts) for p in (ROOT / "modules").rglob("*.py"))
    return [dotted for dotted in files if dotted not in of_modules
            and slot_table(importlib.import_module(dotted).__doc__ or "", dotted) is not None]


@pytest.mark.parametrize("dotted", tables_outside_modules())
def test_a_table_outside_a_module_lists_the_slots_of_the_component_there(dotted):
    py_module = importlib.import_module(dotted)
    own = [c for _, c in inspect.getmembers(py_module, inspect.isclass)
           if issubclass(c, Component) and c.__module__ == dotted and "SLOTS" in vars(c)]
    assert len(own) == 1, (f"{dotted}: a slot table in a file that is no module must document the one component "
                           f"it declares slots for; it declares {[c.__name__ for c in own]}")
    rows = table_of(py_module, dotted)
    components = {r.component for r in rows}
    assert len(components) == 1, f"{dotted}: the table lists the components {sorted(components)}, not one"
    component = components.pop()
    slots = {(component, s.name): (s.type.value, s.direction.value) for s in own[0].SLOTS}
    found, _ = problems(rows, slots, {})
    assert not found, f"{dotted} ({own[0].__name__}): " + "; ".join(found)


def test_the_rules_catch_a_wrong_table():
    # The same check on a table with a slot missing, a wrong type and a slot the module lacks.
    rows = [Row("drive", "speed", "real", "target", "m/s"), Row("drive", "run", "int", "target", "on"),
            Row("drive", "running", "bool", "source", "on"), Row("drive", "reverse", "bool", "target", "back")]
    found, _ = problems(rows, expected("conveyor", minimal_parameters("conveyor")), {})
    assert found == ["drive.run: the table says int target, the module bool target",
                     "drive.velocity (real source) is not in the table",
                     "drive.reverse is in the table, not among the slots"]
