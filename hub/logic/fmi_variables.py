"""An FMU's variables as the hub maps them: FMI type → slot type, ranges, start values, array elements, what a scenario may set.

The rules (hub/logic/README.md, "Bringing your own FMU"):

| FMI type                                        | slot   | checked when a value is written          |
|-------------------------------------------------|--------|------------------------------------------|
| Real, Float64, Float32                          | real   | min/max (parameters); Float32's range     |
| Integer, Int8…Int64, UInt8…UInt64, Enumeration  | int    | the type's width ∩ min/max; an Enumeration's items |
| Boolean                                         | bool   |                                          |
| String                                          | string |                                          |
| Binary                                          | string | lower-case hex, two digits a byte; maxSize |
| Clock                                           | —      | not mapped, with the reason              |

An int slot is a signed 64-bit integer, so a UInt64 carries 0 … 2^63 − 1 here. An FMI 3 array
(`<Dimension>`) maps to one slot per element, named `x_0`, `x_1`… (`A_0_1` for row 0, column 1 of
a matrix; elements in FMI's row-major order): slot names are identifiers, so no brackets. A
structural parameter is not mapped: it fixes array sizes, which the hub takes from its start value.
This file reads only what fmpy has parsed; every FMI call stays in hub/logic/fmi.py.
"""
from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass

from hub.core.registry import did_you_mean
from hub.core.slots import INT_RANGE, SlotType

_REAL = ("Real", "Float64", "Float32")
_WIDTHS = {
    "Int8": (-2**7, 2**7 - 1), "UInt8": (0, 2**8 - 1), "Int16": (-2**15, 2**15 - 1), "UInt16": (0, 2**16 - 1),
    "Integer": (-2**31, 2**31 - 1), "Int32": (-2**31, 2**31 - 1), "UInt32": (0, 2**32 - 1),
    "Int64": INT_RANGE, "UInt64": (0, INT_RANGE[1]),
}
_FLOAT32_MAX = 3.4028234663852886e38
_HEX = re.compile(r"^(?:[0-9a-fA-F]{2})*$")


def slot_type(fmi_type: str) -> SlotType | None:
    """The slot type of an FMI 2 or 3 type name; None: not mapped (a Clock)."""
    if fmi_type in _REAL:
        return SlotType.REAL
    if fmi_type in _WIDTHS or fmi_type == "Enumeration":
        return SlotType.INT
    return {"Boolean": SlotType.BOOL, "String": SlotType.STRING, "Binary": SlotType.STRING}.get(fmi_type)


@dataclass(frozen=True)
class FmuVariable:
    """One scalar the hub reads or writes: a scalar variable, or one element of an FMI 3 array."""

    name: str                   # the slot-facing name: the variable's, or `x_0`… for an array element
    type: SlotType
    causality: str              # input, output, parameter, …
    vr: int
    fmi_type: str
    start: object = None        # slot-typed (a Binary: hex), None when the FMU gives none
    description: str = ""
    variability: str = ""
    initial: str | None = None
    low: float | int | None = None    # the range a written value must be in: type width ∩ min/max
    high: float | int | None = None
    narrowed: bool = False            # min/max narrow the type's own range
    items: tuple[tuple[str, int], ...] = ()   # an Enumeration's items (name, value)
    max_size: int | None = None       # a Binary's maxSize, in bytes
    element: int = 0                  # position within its array (0 for a scalar)
    size: int = 1                     # elements of the variable it belongs to (1: a scalar)
    array: str = ""                   # the array's own name, for an element

    def settable(self) -> str | None:
        """None if FMI lets a user set it before initialisation; else why not.

        FMI 2 and 3 alike: a variable that is not a constant and has `initial` exact or approx
        (parameters and inputs with a start value included), set once the FMU is instantiated."""
        if self.causality == "independent":
            return "it is the independent variable (time)"
        if self.causality == "calculatedParameter":
            return "it is a calculated parameter: the FMU computes it from others"
        if self.causality == "output":
            return "it is an output: the FMU computes it"
        if self.variability == "constant":
            return "it is a constant"
        if self.initial == "calculated":
            return f"it is {_article(self.causality)} the FMU calculates (initial=\"calculated\")"
        if self.start is None:
            return "it has no start value, so FMI lets no one set it before initialisation"
        return None

    def check(self, value):
        """`value` (from YAML, a flow or a participant) as this variable takes it, or a ValueError saying why not."""
        if self.fmi_type == "Enumeration" and isinstance(value, str):
            named = dict(self.items)
            if value not in named:
                raise ValueError(f"{value!r} is not one of its items ({self.item_list()})"
                                 f"{did_you_mean(value, named)}")
            return named[value]
        value = self.type.coerce(value)
        if self.fmi_type == "Binary":
            if not _HEX.match(value):
                raise ValueError(f"a Binary is written as hex digits, two a byte (e.g. '0a1b'), got {value!r}")
            if self.max_size is not None and len(value) // 2 > self.max_size:
                raise ValueError(f"{len(value) // 2} bytes are more than its maxSize {self.max_size}")
            return value.lower()
        if self.items and value not in dict(self.items).values():
            raise ValueError(f"{value} is not one of its items ({self.item_list()})")
        if (self.low is not None and value < self.low) or (self.high is not None and value > self.high):
            raise ValueError(f"{value!r} is outside its range {self.range_text()}")
        return value

    def range_text(self) -> str:
        show = (lambda x: f"{x:g}") if self.type is SlotType.REAL else str
        low = "−∞" if self.low is None else show(self.low)
        high = "∞" if self.high is None else show(self.high)
        return f"{low} … {high}"

    def item_list(self) -> str:
        return ", ".join(f"{name}={value}" for name, value in self.items)

    def summary(self) -> str:
        """`name (int, start 1, items slow=1, fast=2)`: what check-fmu shows of it."""
        parts = [self.type.value if self.fmi_type in ("Real", "Float64", "Integer", "Int32", "Boolean", "String")
                 else f"{self.type.value} from {self.fmi_type}"]
        if self.start is not None:
            parts.append(f"start {_shown(self.type, self.start)}")
        if self.items:
            parts.append(f"items {self.item_list()}")
        elif self.narrowed:
            parts.append(self.range_text())
        return f"{self.name} ({', '.join(parts)})"


def _shown(kind: SlotType, value) -> str:
    """A value as a scenario writes it."""
    if kind is SlotType.BOOL:
        return "true" if value else "false"
    if kind is SlotType.REAL:
        return f"{value:g}"
    return repr(value) if kind is SlotType.STRING else str(value)


def _article(causality: str) -> str:
    return {"output": "an output", "local": "a local variable", "input": "an input"}.get(causality, f"a {causality}")


def map_variables(model_variables, attributes: dict[str, dict], fmi2: bool):
    """(variables by slot-facing name, unmapped as (name, reason)) from fmpy's parsed variables;
    `attributes` holds each variable's XML attributes by name (fmpy keeps no UInt min/max nor maxSize)."""
    variables, unmapped = {}, []
    for v in model_variables:
        if v.causality == "structuralParameter":
            users = [u.name for u in model_variables if any(d.valueReference == v.valueReference
                                                            for d in u.dimensions)]
            unmapped.append((v.name, f"a structural parameter{' (it sizes ' + ', '.join(users) + ')' if users else ''}"
                                     f": planthub keeps its start value {v.start}"))
            continue
        kind = slot_type(v.type)
        if kind is None:
            unmapped.append((v.name, f"a {v.type}: clocks need scheduled execution or event mode, "
                                     "which planthub does not support"))
            continue
        shape = tuple(v.shape or ())
        count = math.prod(shape) if shape else 1
        try:
            starts = _starts(v, kind, count)
        except ValueError as exc:
            unmapped.append((v.name, f"its start value cannot be read: {exc}"))
            continue
        xml = attributes.get(v.name, {})
        low, high = _range(v, xml, fmi2)
        narrowed = (low, high) != _own_range(v.type, fmi2)
        items = tuple((i.name, int(i.value)) for i in v.declaredType.items) \
            if v.type == "Enumeration" and v.declaredType is not None else ()
        max_size = int(xml["maxSize"]) if "maxSize" in xml else None
        indices = [()] if not shape else list(itertools.product(*(range(n) for n in shape)))
        names = [v.name + "".join(f"_{i}" for i in index) for index in indices]
        taken = [name for name in names if name in variables]
        if taken:   # an array is written whole, so it is mapped whole or not at all
            unmapped.append((v.name, f"its slot {taken[0]!r} has the name of another variable's"))
            continue
        for k, name in enumerate(names):
            variables[name] = FmuVariable(name, kind, v.causality, v.valueReference, v.type, starts[k],
                                          v.description or "", v.variability or "", v.initial, low, high,
                                          narrowed, items, max_size, k, count, v.name if shape else "")
    return variables, unmapped


def _starts(v, kind: SlotType, count: int) -> list:
    if v.start is None:
        return [None] * count
    if kind is SlotType.STRING:
        if count > 1:   # an FMI 3 String or Binary array has one <Start> per element; fmpy keeps the first
            raise ValueError(f"a {v.type} array's start values are not all read")
        if v.type == "Binary" and not _HEX.match(v.start):
            raise ValueError(f"{v.start!r} is not hex")
        return [v.start.lower() if v.type == "Binary" else v.start]
    words = v.start.split()
    if len(words) != count:
        raise ValueError(f"{len(words)} values for {count} elements")
    if kind is SlotType.BOOL:
        return [w in ("true", "1") for w in words]
    if kind is SlotType.INT:
        return [int(w) for w in words]
    return [float(w) for w in words]


def _number(text, kind):
    if text is None:
        return None
    if kind == "real":
        return float(text)
    try:
        return int(text)
    except ValueError:
        return int(float(text))


def _own_range(fmi_type: str, fmi2: bool):
    """The values a type holds at all (None: unbounded)."""
    if fmi_type == "Float32":
        return -_FLOAT32_MAX, _FLOAT32_MAX
    if fmi_type == "Enumeration":   # written with fmi2SetInteger, or fmi3SetInt64
        return _WIDTHS["Integer" if fmi2 else "Int64"]
    return _WIDTHS.get(fmi_type, (None, None))


def _range(v, xml: dict, fmi2: bool):
    """The range a written value must be in: the type's own, narrowed by min/max."""
    if v.type not in _REAL and v.type not in _WIDTHS and v.type != "Enumeration":
        return None, None
    kind = "real" if v.type in _REAL else "int"
    low, high = _own_range(v.type, fmi2)
    declared = v.declaredType
    for source in (declared, v):
        if source is None:
            continue
        for attr, pick in (("min", max), ("max", min)):
            bound = _number(getattr(source, attr, None), kind)
            if bound is not None:
                if attr == "min":
                    low = bound if low is None else pick(low, bound)
                else:
                    high = bound if high is None else pick(high, bound)
    for attr in ("min", "max"):   # fmpy leaves UInt min/max unread: take them from the XML
        bound = _number(xml.get(attr), kind)
        if bound is not None:
            if attr == "min":
                low = bound if low is None else max(low, bound)
            else:
                high = bound if high is None else min(high, bound)
    return low, high


def parameter_values(variables: dict[str, FmuVariable], given: dict) -> dict:
    """The scenario's `parameters:` (checked before) as the values to write, by slot-facing name;
    an array given by its own name as a list (nested or flat) becomes its elements."""
    out = {}
    for name, value in given.items():
        if name in variables:
            out[name] = variables[name].check(value)
        else:
            for element, item in zip(array_elements(variables, name), _flat(value)):
                out[element.name] = element.check(item)
    return out


def array_elements(variables: dict[str, FmuVariable], array: str) -> list[FmuVariable]:
    return [v for v in variables.values() if v.array == array]


def _flat(value):
    if isinstance(value, (list, tuple)):
        return [x for item in value for x in _flat(item)]
    return [value]


def parameter_problems(path_name: str, variables: dict[str, FmuVariable], unmapped, given: dict):
    """(name, message) for every bad entry of `parameters:`: unknown (with did-you-mean), not settable,
    of the wrong type, out of range."""
    settable = {n: v for n, v in variables.items() if v.settable() is None}
    arrays = {v.array for v in settable.values() if v.array}
    reasons = dict(unmapped)
    problems = []
    for name, value in given.items():
        if name in arrays:
            elements = array_elements(variables, name)
            flat = _flat(value)
            if len(flat) != len(elements):
                problems.append((name, f"{name} has {len(elements)} elements, got {len(flat)} values"))
                continue
            for element, item in zip(elements, flat):
                try:
                    element.check(item)
                except ValueError as exc:
                    problems.append((name, f"{element.name} is {element.fmi_type}: {exc}"))
            continue
        variable = variables.get(name)
        if variable is None:
            if name in reasons:
                problems.append((name, f"{name} is not mapped: {reasons[name]}"))
            else:
                problems.append((name, f"{path_name} has no variable {name!r} that can be set"
                                       f"{did_you_mean(name, list(settable) + sorted(arrays))}"))
            continue
        why = variable.settable()
        if why is not None:
            problems.append((name, f"{name} cannot be set: {why}"))
            continue
        try:
            variable.check(value)
        except ValueError as exc:
            problems.append((name, f"{name} is {variable.fmi_type}: {exc}"))
    return problems
