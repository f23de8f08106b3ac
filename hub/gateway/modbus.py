"""The Modbus TCP side of a gateway (pymodbus): every pymodbus call planthub makes is in this file.

Four tables, each addressed from 0 as the tag map says: discrete inputs (bool PLC inputs), coils
(bool outputs and command bits; bits of no tag in between read as 0), input registers (counters, numbers, strings to the PLC), holding
registers (numbers and strings from it, and `cycle_done`). Reads are answered from the process image;
a write is checked before it is taken, and refused with Modbus's own exception codes: an address no
tag holds ILLEGAL_ADDRESS (02), a part of a multi-register value alone, a value out of the tag's
range, a scaled value beyond its raw range or a string that is not UTF-8 ILLEGAL_VALUE (03); each
refusal is logged and nothing reaches the plant. Discrete inputs and input registers cannot be
written at all (Modbus has no function for it: ILLEGAL_FUNCTION, 01, from pymodbus). In lockstep a
read of the input registers over `cycle` between two scans is held until the next begins (`image.py`).
"""
from __future__ import annotations

import asyncio
import logging
import struct

from pymodbus.constants import ExcCodes
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from hub.core.slots import SlotType
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import hold
from hub.gateway.tags import BITS, Tag

_TABLES = ("coil", "discrete_input", "holding_register", "input_register")   # SimDevice's order
_CODES = {1: "coil", 5: "coil", 15: "coil", 2: "discrete_input", 4: "input_register",
          3: "holding_register", 6: "holding_register", 16: "holding_register", 23: "holding_register"}
logging.getLogger("pymodbus").setLevel(logging.ERROR)   # it warns of its own coming API at every start


class ModbusServer:
    """The tags of `image` served at `endpoint` (HOST:PORT), to any unit id."""

    def __init__(self, image: ProcessImage, endpoint: str):
        self.image = image
        host, _, port = endpoint.rpartition(":")
        self.address = (host or "127.0.0.1", int(port))
        self.by_table = {table: [t for t in image.tags.tags if t.table == table] for table in _TABLES}
        self.cycle = image.tags.by_slot["cycle"]
        self.server = None
        self.task = None

    async def start(self) -> None:
        blocks = []
        for table in _TABLES:
            tags = self.by_table[table]
            if table in BITS.values():   # bits are addressed singly, 16 to a register
                top = max((t.address for t in tags), default=0)
                blocks.append([SimData(0, count=top // 16 + 1, datatype=DataType.BITS)])
            else:
                blocks.append([SimData(t.address, count=t.count, datatype=DataType.REGISTERS) for t in tags]
                              or [SimData(0, count=1, datatype=DataType.INVALID)])
        device = SimDevice(id=0, simdata=tuple(blocks), use_bit_addressing=True, action=self._access)
        self.server = ModbusTcpServer(device, address=self.address)
        self.task = asyncio.create_task(self.server.serve_forever())
        for _ in range(200):     # until it listens (or its task failed)
            if self.task.done():
                self.task.result()
            if getattr(self.server, "transport", None) is not None:
                break
            await asyncio.sleep(0.01)

    def publish(self, changed: dict) -> None:
        """Nothing to do: every read is answered from the image."""

    async def stop(self) -> None:
        if self.server is not None:
            await self.server.shutdown()
            self.server = None

    async def _access(self, code, start, address, count, registers, values):
        table = _CODES.get(code)
        bits = table in BITS.values()
        if values is not None:   # (for bits, `count` is the registers they take: the bits are the values)
            tags = [t for t in self.by_table.get(table, ())
                    if t.address < address + len(values) and address < t.address + t.count]
            return self._write(table, address, values, tags)
        if self.cycle in self._overlapping(table, address, count) and self.image.between_scans():
            await hold(self.image)   # lockstep: held while the plant steps to its next scan (image.py)
        for tag in self.by_table.get(table, ()) if bits else self._overlapping(table, address, count):
            words = _encode(tag, self.image.read(tag.slot))   # fresh from the image
            if bits:
                r, b = divmod(tag.address, 16)
                registers[r - start] = (registers[r - start] & ~(1 << b)) | (int(words[0]) << b)
            else:
                registers[tag.address - start:tag.address - start + tag.count] = words
        return None

    def _overlapping(self, table, address, count):
        return [t for t in self.by_table.get(table, ()) if t.address < address + count and address < t.address + t.count]

    def _write(self, table, address, values, tags):
        covered = {a for t in tags for a in range(t.address, t.address + t.count)}
        if any(a not in covered for a in range(address, address + len(values))):
            self.image.refuse(f"{table} {address} (Modbus)", "ILLEGAL_ADDRESS: no tag there")
            return ExcCodes.ILLEGAL_ADDRESS
        taken = []
        for tag in tags:
            if tag.address < address or tag.address + tag.count > address + len(values):
                self.image.refuse(f"{tag.name} at {table} {tag.address} (Modbus)",
                                  f"ILLEGAL_VALUE: {tag.count} words, written only in part")
                return ExcCodes.ILLEGAL_VALUE
            words = values[tag.address - address:tag.address - address + tag.count]
            try:
                taken.append((tag, tag.check_written(_decode(tag, words))))
            except ValueError as exc:
                self.image.refuse(f"{tag.name} at {table} {tag.address} (Modbus)", f"ILLEGAL_VALUE: {exc}")
                return ExcCodes.ILLEGAL_VALUE
        for tag, value in taken:
            self.image.write(tag.slot, value)
        return None


def _encode(tag: Tag, value) -> list:
    if tag.table in BITS.values():
        return [bool(value)]
    if tag.type is SlotType.STRING:
        data = value.encode()[:2 * tag.length].ljust(2 * tag.length, b"\0")
        return list(struct.unpack(f">{tag.length}H", data))
    if tag.type is SlotType.VOID or tag.handshake:
        return [int(value) % 65536]
    if tag.scale is not None:
        return [tag.to_raw(value) % 65536]
    if tag.type is SlotType.REAL:
        return list(struct.unpack(">HH", struct.pack(">f", value)))
    return list(struct.unpack(">HH", struct.pack(">i", max(min(int(value), 2 ** 31 - 1), -2 ** 31))))


def _decode(tag: Tag, words: list):
    if tag.table in BITS.values():
        return bool(words[0])
    if tag.type is SlotType.STRING:
        try:
            return struct.pack(f">{tag.length}H", *words).rstrip(b"\0").decode()
        except UnicodeDecodeError:
            raise ValueError("the string is not UTF-8") from None
    if tag.handshake:
        return words[0]
    if tag.scale is not None:
        return tag.from_raw(words[0] - 65536 if tag.raw[0] < 0 and words[0] > 32767 else words[0])
    if tag.type is SlotType.REAL:
        return float(struct.unpack(">f", struct.pack(">HH", *words))[0])
    return struct.unpack(">i", struct.pack(">HH", *words))[0]
