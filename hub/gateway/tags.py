"""The tag map: how a gateway participant's slots appear to a PLC — names, data types, OPC UA node ids,
Modbus tables and addresses, scaling — generated from the scenario and overridable in YAML.

Direction is the PLC's: the participant's inputs (what the plant's sensors and readers feed it) are
the PLC's *inputs*, its outputs (the commands it sends to actuators) are the PLC's *outputs*.

| slot type | PLC input (plant → PLC)                | PLC output (PLC → plant)                  |
|-----------|----------------------------------------|-------------------------------------------|
| void      | event counter: UInt32 / input register | command bit, fires on its rising edge: Boolean / coil |
| bool      | Boolean / discrete input               | Boolean / coil                            |
| int       | Int32 / 2 input registers              | Int32 / 2 holding registers               |
| real      | Double / 2 input registers (Float32), or 1 register scaled | Double / 2 holding registers, or 1 scaled |
| string    | String / `length` input registers (2 bytes each, UTF-8, zero-padded) | String / `length` holding registers |

S7 (`planthub gateway s7`): PLC inputs in the process inputs I, outputs in the process outputs Q,
the handshake in the markers M, strings in data block 1; in each area the bits first (8 to a byte),
then the numbers at even bytes: a counter or a scaled real a Word/Int (2 bytes), an int a DInt, a
real a Real (4 bytes, big-endian as S7 keeps them), a string an S7 STRING[2·length]. EtherNet/IP
(`planthub gateway enip`): each tag a Logix controller tag of its name, BOOL, DINT (event counters
wrap at 2³¹), REAL (engineering units; `scale` is only its range) or SSTRING.

A real with `scale: [low, high]` is one register of raw counts: `raw` (default 0…27648, the usual
analogue I/O range) maps linearly onto low…high, clamped for inputs, refused beyond for outputs.
vec3 and quat slots are not mapped (a PLC has no such type): a gateway refuses them by name.
The handshake of lockstep mode is three more tags of the folder `gateway`: `cycle` (PLC input:
the scan number the plant waits on; it counts modulo 65536 in every protocol, hub/gateway/participant.py), `cycle_done` (PLC output: the PLC writes the scan number back
when its scan is done) and `plc_ready` (PLC output: the PLC sets it once, the gateway then joins).
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field, replace
from pathlib import Path

import jsonschema

from hub.core.errors import PlanthubError, Problem, format_path
from hub.core.registry import did_you_mean
from hub.core.slots import SlotType
from hub.scenario.yamlsource import line_of, load_yaml

INPUT, OUTPUT = "input", "output"       # the PLC's direction
RAW = (0, 27648)                        # raw counts of analogue I/O (S7's nominal range)
INT32 = (-2 ** 31, 2 ** 31 - 1)
STRING_REGISTERS = 8                    # 16 bytes of UTF-8
#: Modbus tables, by direction and kind of value
BITS = {INPUT: "discrete_input", OUTPUT: "coil"}
WORDS = {INPUT: "input_register", OUTPUT: "holding_register"}
_OPCUA = {(SlotType.VOID, INPUT): "UInt32", (SlotType.VOID, OUTPUT): "Boolean", SlotType.BOOL: "Boolean",
          SlotType.INT: "Int32", SlotType.REAL: "Double", SlotType.STRING: "String"}
HANDSHAKE = "gateway"
S7_AREAS = {INPUT: "I", OUTPUT: "Q"}    # process image of inputs, of outputs
S7_MARKERS, S7_DB, S7_DB_NUMBER = "M", "DB", 1


@dataclass(frozen=True)
class Tag:
    """One slot as a PLC sees it."""

    slot: str                   # the participant's input or output
    type: SlotType
    direction: str              # INPUT or OUTPUT (the PLC's)
    name: str                   # the tag's name (OPC UA browse name)
    folder: str                 # the object at the flow's other end (OPC UA folder)
    plant: str = ""             # the plant slots it is connected to
    description: str = ""
    units: str = ""
    scale: tuple | None = None  # (low, high) of a scaled real
    raw: tuple = RAW
    range: tuple | None = None  # allowed (low, high) of a written value
    length: int = STRING_REGISTERS
    address: int = 0            # Modbus: first address in its table
    handshake: bool = False
    s7_area: str = ""           # S7: I, Q, M or DB (data block S7_DB_NUMBER)
    s7_byte: int = 0            # S7: its first byte in that area
    s7_bit: int = -1            # S7: its bit in that byte (a Bool), else -1

    @property
    def opcua_type(self) -> str:
        return _OPCUA.get((self.type, self.direction)) or _OPCUA[self.type]

    @property
    def node_id(self) -> str:
        return f"{self.folder}.{self.name}"

    @property
    def table(self) -> str:
        bits = self.type is SlotType.BOOL or (self.type is SlotType.VOID and self.direction == OUTPUT)
        return (BITS if bits else WORDS)[self.direction]

    @property
    def count(self) -> int:
        """Modbus: bits or registers it takes."""
        if self.table in BITS.values():
            return 1
        if self.type is SlotType.STRING:
            return self.length
        if self.type is SlotType.VOID or self.scale is not None or self.handshake:
            return 1
        return 2

    @property
    def encoding(self) -> str:
        """How its Modbus words carry the value."""
        if self.table in BITS.values():
            return "bit"
        if self.type is SlotType.STRING:
            return f"UTF-8, {2 * self.length} bytes"
        if self.type is SlotType.VOID or self.handshake:
            return "UInt16 (counts modulo 65536)"
        if self.scale is not None:
            return f"raw {self.raw[0]}..{self.raw[1]} = {self.scale[0]:g}..{self.scale[1]:g}"
        return "Float32, high word first" if self.type is SlotType.REAL else "Int32, high word first"

    @property
    def s7_type(self) -> str:
        """Its S7 data type (TIA Portal's names)."""
        if self.table in BITS.values():
            return "Bool"
        if self.type is SlotType.STRING:
            return f"String[{2 * self.length}]"
        if self.type is SlotType.VOID or self.handshake:
            return "Word"
        if self.scale is not None:
            return "Int"
        return "Real" if self.type is SlotType.REAL else "DInt"

    @property
    def s7_size(self) -> int:
        """Bytes it takes in its S7 area (a Bool: 1, its byte shared)."""
        if self.type is SlotType.STRING:
            return 2 + 2 * self.length
        return {"Bool": 1, "Word": 2, "Int": 2}.get(self.s7_type, 4)

    @property
    def s7_address(self) -> str:
        """Its absolute S7 address: I0.0, QW4, MD8, DB1.DBB0 (a string's first byte)."""
        if self.s7_area == S7_DB:
            return f"DB{S7_DB_NUMBER}.DBB{self.s7_byte}"
        if self.s7_bit >= 0:
            return f"{self.s7_area}{self.s7_byte}.{self.s7_bit}"
        return f"{self.s7_area}{'W' if self.s7_size == 2 else 'D'}{self.s7_byte}"

    @property
    def logix_type(self) -> str:
        """Its Logix (EtherNet/IP) data type."""
        if self.table in BITS.values():
            return "BOOL"
        if self.type is SlotType.STRING:
            return "SSTRING"
        return "REAL" if self.type is SlotType.REAL and not self.handshake else "DINT"

    def to_raw(self, value: float) -> int:
        """A scaled real as raw counts, clamped to the raw range (a PLC input)."""
        (low, high), (r0, r1) = self.scale, self.raw
        return min(max(round(r0 + (value - low) * (r1 - r0) / (high - low)), r0), r1)

    def from_raw(self, raw: int) -> float:
        """Raw counts a PLC wrote as the scaled real; a ValueError beyond the raw range."""
        (low, high), (r0, r1) = self.scale, self.raw
        if not r0 <= raw <= r1:
            raise ValueError(f"raw {raw} is outside {r0}..{r1}")
        return low + (raw - r0) * (high - low) / (r1 - r0)

    def check_written(self, value):
        """A value the PLC wrote, as the plant takes it; a ValueError says why it is refused."""
        if self.type is SlotType.REAL:
            if value - value != 0.0:
                raise ValueError(f"{value!r} is not finite")
            low, high = self.range or self.scale or (None, None)
            if low is not None and not low <= value <= high:
                raise ValueError(f"{value!r} is outside {low:g}..{high:g}")
        elif self.type is SlotType.INT:
            low, high = self.range or INT32
            if not low <= value <= high:
                raise ValueError(f"{value!r} is outside {low}..{high}")
        elif self.type is SlotType.STRING and len(value.encode()) > 2 * self.length and self.length:
            raise ValueError(f"{len(value.encode())} bytes is longer than {2 * self.length}")
        return value


@dataclass(frozen=True)
class TagMap:
    run: str
    tags: tuple[Tag, ...]
    by_slot: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        self.by_slot.update({t.slot: t for t in self.tags})

    @property
    def inputs(self):
        return [t for t in self.tags if t.direction == INPUT]

    @property
    def outputs(self):
        return [t for t in self.tags if t.direction == OUTPUT]

    def csv(self) -> str:
        """The table a PLC programmer imports into a tag editor."""
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(["tag", "direction", "slot", "plant", "opcua_node", "opcua_type", "modbus_table",
                         "modbus_address", "modbus_count", "modbus_encoding", "range", "units", "description",
                         "s7_address", "s7_type", "logix_type"])
        for t in self.tags:
            limits = t.range or t.scale
            writer.writerow([t.name, t.direction, t.slot, t.plant, f"nsu={namespace(self.run)};s={t.node_id}",
                             t.opcua_type, t.table, t.address, t.count, t.encoding,
                             f"{limits[0]:g}..{limits[1]:g}" if limits else "", t.units, t.description,
                             t.s7_address, t.s7_type, t.logix_type])
        return out.getvalue()

    def tia_csv(self) -> str:
        """The S7 tags as a PLC tag table in TIA Portal's columns (I, Q and M only: a tag table holds no
        data block; the strings of DB1 are in `csv()`, with their offsets)."""
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(["Name", "Path", "Data Type", "Logical Address", "Comment", "Hmi Visible",
                         "Hmi Accessible", "Hmi Writeable", "Typeobject ID", "Version ID"])
        for t in self.tags:
            if t.s7_area != S7_DB:
                writer.writerow([t.name, f"planthub {self.run}", t.s7_type, f"%{t.s7_address}", t.description,
                                 "True", "True", str(t.direction == OUTPUT), "", ""])
        return out.getvalue()


def namespace(run: str) -> str:
    return f"urn:planthub:{run}"


_OVERRIDE = {
    "type": "object",
    "properties": {
        "name": {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"},
        "folder": {"type": "string", "pattern": "^[A-Za-z_][A-Za-z0-9_]*$"},
        "description": {"type": "string"},
        "units": {"type": "string"},
        "address": {"type": "integer", "minimum": 0, "maximum": 65535},
        "scale": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        "raw": {"type": "array", "items": {"type": "integer", "minimum": -32768, "maximum": 65535},
                "minItems": 2, "maxItems": 2},
        "range": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        "length": {"type": "integer", "minimum": 1, "maximum": 120},
    },
    "additionalProperties": False,
}
SCHEMA = {"type": "object", "properties": {"tags": {"type": "object", "additionalProperties": _OVERRIDE}},
          "required": ["tags"], "additionalProperties": False}


def tag_map(scenario, name: str, overrides_file: Path | None = None) -> TagMap:
    """The tag map of participant object `name` of a checked scenario, with the overrides of a YAML file."""
    obj = next((o for o in scenario.objects if o.name == name), None)
    if obj is None or obj.module_name != "participant":
        names = [o.name for o in scenario.objects if o.module_name == "participant"]
        what = "no object" if obj is None else f"a {obj.module_name}, not a participant:"
        raise PlanthubError(f"{scenario.path}: {what} {name!r}{did_you_mean(name, names) if obj is None else ''} "
                            f"(its participant objects: {', '.join(names) or 'none'})")
    ends = {}
    for flow in scenario.flows:
        if flow.target.obj == name:
            ends.setdefault(flow.target.slot, []).append(flow.source)
        if flow.source.obj == name:
            ends.setdefault(flow.source.slot, []).append(flow.target)
    problems, tags = [], []
    for slots, direction in ((obj.params["inputs"], INPUT), (obj.params["outputs"], OUTPUT)):
        for slot, kind in slots.items():
            kind = SlotType(kind)
            if kind in (SlotType.VEC3, SlotType.QUAT):
                problems.append(f"objects.{name}.{direction}s.{slot}: a {kind.value} has no PLC data type; "
                                f"feed the gateway its components as reals")
                continue
            plant = ends.get(slot, [])
            tags.append(Tag(slot, kind, direction, slot, plant[0].obj if plant else HANDSHAKE,
                            " ".join(map(str, plant)), _describe(kind, direction, plant)))
    if problems:
        raise PlanthubError(f"{scenario.path}: " + "; ".join(problems))
    if overrides_file is not None:
        tags = _override(tags, overrides_file)
    handshake = [Tag("cycle", SlotType.INT, INPUT, "cycle", HANDSHAKE, "", "lockstep: the scan the plant waits on",
                     handshake=True),
                 Tag("cycle_done", SlotType.INT, OUTPUT, "cycle_done", HANDSHAKE, "",
                     "lockstep: the PLC writes `cycle` back here when its scan is done", handshake=True),
                 Tag("plc_ready", SlotType.BOOL, OUTPUT, "plc_ready", HANDSHAKE, "",
                     "lockstep: the PLC sets it once it is running; the gateway then joins the plant", handshake=True)]
    tags = _s7_layout(_addresses(handshake + tags, overrides_file))
    return TagMap(scenario.name, tuple(tags))


def _s7_layout(tags: list[Tag]) -> list[Tag]:
    """S7 addresses: in each area the bits from byte 0, then the numbers and strings at even bytes, in order."""
    area = lambda t: S7_DB if t.type is SlotType.STRING else S7_MARKERS if t.handshake else S7_AREAS[t.direction]
    placed = {}
    for name in dict.fromkeys(map(area, tags)):
        mine = [t for t in tags if area(t) == name]
        bits = [t for t in mine if t.s7_type == "Bool"]
        for k, t in enumerate(bits):
            placed[t.slot] = replace(t, s7_area=name, s7_byte=k // 8, s7_bit=k % 8)
        at = (len(bits) + 7) // 8
        for t in mine:
            if t.s7_type != "Bool":
                at += at % 2
                placed[t.slot] = replace(t, s7_area=name, s7_byte=at)
                at += t.s7_size
    return [placed[t.slot] for t in tags]


def _describe(kind: SlotType, direction: str, plant) -> str:
    where = ", ".join(map(str, plant)) or "no flow"
    if kind is SlotType.VOID:
        return (f"counts the events of {where}" if direction == INPUT
                else f"a rising edge fires {where}")
    return f"{'from' if direction == INPUT else 'to'} {where}"


def _override(tags: list[Tag], path: Path) -> list[Tag]:
    data, lines, problems = load_yaml(path)
    if data is not None:
        for error in jsonschema.Draft202012Validator(SCHEMA).iter_errors(data):
            place = tuple(error.absolute_path)
            problems.append(Problem(str(path), line_of(lines, place), format_path(place), error.message))
    by_slot = {t.slot: t for t in tags}
    if not problems:
        for slot, change in data["tags"].items():
            place = ("tags", slot)
            if slot not in by_slot:
                problems.append(Problem(str(path), line_of(lines, place), format_path(place),
                                        f"no slot {slot!r} on the gateway{did_you_mean(slot, by_slot)}"))
                continue
            tag = by_slot[slot]
            for key in ("scale", "raw", "range"):
                if key in change and change[key][0] >= change[key][1]:
                    problems.append(Problem(str(path), line_of(lines, place + (key,)), format_path(place + (key,)),
                                            f"{change[key]}: the low end must be below the high end"))
            wrong = [k for k in ("scale", "range") if k in change and tag.type is not SlotType.REAL] + \
                    (["length"] if "length" in change and tag.type is not SlotType.STRING else [])
            for key in wrong:
                problems.append(Problem(str(path), line_of(lines, place + (key,)), format_path(place + (key,)),
                                        f"only a {'string' if key == 'length' else 'real'} slot takes `{key}`; "
                                        f"{slot!r} is {tag.type.value}"))
            fields = {k: tuple(v) if isinstance(v, list) else v for k, v in change.items() if k != "address"}
            by_slot[slot] = replace(tag, **fields)
    if problems:
        raise PlanthubError("\n".join(map(str, problems)))
    return list(by_slot.values())


def _addresses(tags: list[Tag], path: Path | None) -> list[Tag]:
    """Modbus addresses: each tag in its table in order, after any fixed by the overrides; overlaps refused."""
    fixed, lines = {}, {}
    if path is not None:
        data, lines, _ = load_yaml(path)
        fixed = {slot: change["address"] for slot, change in data["tags"].items() if "address" in change}

    def wrong(slot, key, message):
        place = ("tags", slot, key)
        return PlanthubError(str(Problem(str(path), line_of(lines, place) or line_of(lines, place[:2]),
                                         format_path(place), message)))

    renamed = {slot for slot, change in (data["tags"].items() if path is not None else ()) if "name" in change}
    names = {}
    for tag in sorted(tags, key=lambda t: t.slot in renamed):   # a renamed one is the one named
        if tag.name in names:
            raise wrong(tag.slot, "name", f"{tag.name!r} is already the name of {names[tag.name]!r}")
        names[tag.name] = tag.slot
    owners, out = {}, []
    for tag in sorted(tags, key=lambda t: t.slot not in fixed):   # fixed ones first, then in order
        taken = owners.setdefault(tag.table, {})
        start = fixed.get(tag.slot)
        if start is None:
            start = 0
            while any(a in taken for a in range(start, start + tag.count)):
                start += 1
        span = range(start, start + tag.count)
        clash = sorted({taken[a] for a in span if a in taken})
        if clash:
            raise wrong(tag.slot, "address", f"{tag.table} {start}..{span[-1]} overlaps {', '.join(clash)}")
        if span[-1] > 65535:
            raise wrong(tag.slot, "address", f"{tag.table} {start}..{span[-1]} runs past 65535")
        taken.update({a: tag.slot for a in span})
        out.append(replace(tag, address=start))
    order = {t.slot: k for k, t in enumerate(tags)}
    return sorted(out, key=lambda t: order[t.slot])
