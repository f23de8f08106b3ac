"""Slot types and slot descriptions: a slot knows its name, type and direction, never its value."""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass


class SlotType(enum.Enum):
    """The value types a slot can carry; `void` carries only activity (an event)."""

    VOID = "void"
    BOOL = "bool"
    INT = "int"
    REAL = "real"
    VEC3 = "vec3"
    QUAT = "quat"
    STRING = "string"

    @property
    def width(self) -> int:
        """Number of CSV columns a value of this type takes."""
        return {SlotType.VEC3: 3, SlotType.QUAT: 4}.get(self, 1)

    def initial(self):
        """The value a slot holds before anything wrote it."""
        return _INITIAL[self]

    def coerce(self, value):
        """Turn a YAML/JSON value into this type's canonical Python value, or raise ValueError."""
        return _COERCE[self](value)


def _to_bool(v):
    if isinstance(v, bool):
        return v
    raise ValueError(f"expected true or false, got {v!r}")


INT_RANGE = (-2**63, 2**63 - 1)   # an int slot is a 64-bit signed integer (FMI Integer64, the wire's int64)


def _to_int(v):
    if isinstance(v, int) and not isinstance(v, bool):
        if INT_RANGE[0] <= v <= INT_RANGE[1]:
            return v
        raise ValueError(f"expected a 64-bit integer, got {v!r}")
    raise ValueError(f"expected an integer, got {v!r}")


def _to_real(v):
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return float(v)
    raise ValueError(f"expected a finite number, got {v!r}")


def _to_vector(n):
    def convert(v):
        if isinstance(v, (list, tuple)) and len(v) == n:
            return tuple(_to_real(x) for x in v)
        raise ValueError(f"expected a list of {n} numbers, got {v!r}")
    return convert


def _to_void(v):
    if v is None:
        return None
    raise ValueError(f"a void slot carries no value, got {v!r}")


def _to_string(v):
    if isinstance(v, str):
        return v
    raise ValueError(f"expected a string, got {v!r}")


_INITIAL = {
    SlotType.VOID: None,
    SlotType.BOOL: False,
    SlotType.INT: 0,
    SlotType.REAL: 0.0,
    SlotType.VEC3: (0.0, 0.0, 0.0),
    SlotType.QUAT: (0.0, 0.0, 0.0, 1.0),
    SlotType.STRING: "",
}
_COERCE = {
    SlotType.VOID: _to_void,
    SlotType.BOOL: _to_bool,
    SlotType.INT: _to_int,
    SlotType.REAL: _to_real,
    SlotType.VEC3: _to_vector(3),
    SlotType.QUAT: _to_vector(4),
    SlotType.STRING: _to_string,
}


class Direction(enum.Enum):
    """A source slot is written by its component and read by flows; a target slot the other way round."""

    SOURCE = "source"
    TARGET = "target"


@dataclass(frozen=True)
class Slot:
    """A typed port of a component, e.g. `trigger.on_enter` (void source)."""

    name: str
    type: SlotType
    direction: Direction
    doc: str = ""

    @classmethod
    def source(cls, name: str, type_: str, doc: str = "") -> Slot:
        return cls(name, SlotType(type_), Direction.SOURCE, doc)

    @classmethod
    def target(cls, name: str, type_: str, doc: str = "") -> Slot:
        return cls(name, SlotType(type_), Direction.TARGET, doc)


@dataclass(frozen=True)
class SlotRef:
    """A slot's full address `object.component.slot` inside a built plant."""

    obj: str
    component: str
    slot: str

    def __str__(self) -> str:
        return f"{self.obj}.{self.component}.{self.slot}"


@dataclass(frozen=True)
class SlotFamily:
    """Slots a module's parameters name or type (an FMU's inputs, a sink's count per destination),
    described once for its reference (`planthub describe`, modules/README.md): `name` stands for
    the names (`<input>`, `DEST`), `type` says where the type comes from ("the input's",
    "param `type`"). It checks nothing; the slots a scenario gets are `Slot`s."""

    name: str
    type: str
    direction: Direction
    doc: str

    @classmethod
    def source(cls, name: str, type_: str, doc: str) -> SlotFamily:
        return cls(name, type_, Direction.SOURCE, doc)

    @classmethod
    def target(cls, name: str, type_: str, doc: str) -> SlotFamily:
        return cls(name, type_, Direction.TARGET, doc)
