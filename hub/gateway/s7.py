"""The S7 side of a gateway (python-snap7's pure-Python server): every snap7 call planthub makes is in this file.

Four areas, laid out by the tag map (hub/gateway/tags.py): the process inputs I (the plant's values,
read-only to the PLC), the process outputs Q (the PLC's commands), the markers M (the lockstep
handshake) and data block 1 (strings, S7 STRING). Numbers big-endian, as S7 keeps them. Reads are
answered from the areas, which the plant's values are written into at each publish (the scan's
`cycle` last). A write is checked before it is taken, and refused with S7's own item return codes:
a PLC input (I, `cycle`, an input string) 0x03 "accessing the object not allowed"; bytes no tag
holds or beyond the area 0x05 "invalid address"; a part of a tag alone, a value out of its range, a
raw value beyond its raw range or a string that is not UTF-8 0x07 "data type inconsistent". Each
refusal is logged and nothing reaches the plant; bits of a written byte that no tag holds, and the
padding bytes that keep numbers at even bytes, are ignored (a write of nothing but them is refused).
A write of several items in one request and a block download are refused whole, with the PDU error
0x8104 "function not supported" (snap7 would apply the first item only, and a download unchecked).
In lockstep a read over `cycle` in its area (one item; the tag map puts it in the markers) between two
scans is held until the next begins (`image.py`).

python-snap7 3.3.0's server has no hook for writes (its `set_rw_area_callback` is a stub), so
`_Server` overrides its write handler, and keeps the bit of a bit-sized write that it would drop.
"""
from __future__ import annotations

import logging
import struct

from snap7.datatypes import S7Area, S7WordLen
from snap7.error import S7Error
from snap7.server import Server
from snap7.type import SrvArea

from hub.core.errors import PlanthubError
from hub.core.slots import SlotType
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import refuse_taken
from hub.gateway.tags import OUTPUT, S7_AREAS, S7_DB, S7_DB_NUMBER, S7_MARKERS, Tag

_AREAS = {S7_AREAS["input"]: (SrvArea.PE, S7Area.PE, 0), S7_AREAS["output"]: (SrvArea.PA, S7Area.PA, 0),
          S7_MARKERS: (SrvArea.MK, S7Area.MK, 0), S7_DB: (SrvArea.DB, S7Area.DB, S7_DB_NUMBER)}
NOT_ALLOWED, INVALID_ADDRESS, INCONSISTENT = 0x03, 0x05, 0x07
NOT_SUPPORTED = 0x8104   # the PDU's error class and code: "function not supported", as snap7's own refusals
logging.getLogger("snap7").setLevel(logging.ERROR)   # it logs every connection and every read


class S7Server:
    """The tags of `image` served at `endpoint` (HOST:PORT; S7's own port is 102)."""

    def __init__(self, image: ProcessImage, endpoint: str):
        self.image = image
        host, _, port = endpoint.rpartition(":")
        self.host, self.port = host or "127.0.0.1", int(port)
        self.tags = image.tags.tags
        self.cycle = image.tags.by_slot["cycle"]
        self.server = None
        self.memory = {}       # S7Area, DB number → the area's bytes (the server's own bytearray)
        # area → the bytes between its tags that keep the numbers at even bytes: like the bits of no
        # tag, a PLC writing its whole image over them is not refused, and what it writes there ignored
        self.padding = {}
        for name in _AREAS:
            mine = [t for t in self.tags if t.s7_area == name]
            held = {b for t in mine for b in range(t.s7_byte, t.s7_byte + t.s7_size)}
            self.padding[name] = set(range(max((t.s7_byte + t.s7_size for t in mine), default=0))) - held

    async def start(self) -> None:
        server = _Server(self, log=False)
        for name, (srv_area, area, number) in _AREAS.items():
            size = max((t.s7_byte + t.s7_size for t in self.tags if t.s7_area == name), default=0)
            self.memory[area, number] = bytearray(max(size, 2))
            server.register_area(srv_area, number, self.memory[area, number])
        for tag in self.tags:
            self._store(tag, self.image.read(tag.slot))
        server.host = self.host
        refuse_taken(self.host, self.port, f"the S7 server could not listen at {self.host}:{self.port}")
        try:
            server.start(tcp_port=self.port)
        except S7Error as exc:
            raise PlanthubError(f"the S7 server could not listen at {self.host}:{self.port}: {exc}") from None
        self.server = server

    def publish(self, changed: dict) -> None:
        """In the plant's thread: snap7 serves from threads of its own, each read under the area's lock."""
        for slot in sorted(changed, key=lambda s: s == "cycle"):   # the scan's number last: then all is there
            self._put(self.image.tags.by_slot[slot], changed[slot])

    async def stop(self) -> None:
        if self.server is not None:
            self.server.stop()
            self.server = None

    def _put(self, tag: Tag, value) -> None:
        _, area, number = _AREAS[tag.s7_area]
        with self.server.area_locks[area, number]:
            self._store(tag, value)

    def _store(self, tag: Tag, value) -> None:
        """The tag's bytes in its area (the caller holds the area's lock, or the server is not yet started)."""
        _, area, number = _AREAS[tag.s7_area]
        memory = self.memory[area, number]
        if tag.s7_bit >= 0:
            mask = 1 << tag.s7_bit
            memory[tag.s7_byte] = (memory[tag.s7_byte] | mask) if value else (memory[tag.s7_byte] & ~mask)
        else:
            memory[tag.s7_byte:tag.s7_byte + tag.s7_size] = _encode(tag, value)

    def write(self, area, number: int, start: int, data: bytes, bit: int | None) -> int | None:
        """A PLC's write checked and, if whole, handed to the image: None, or the item return code refusing it."""
        name = next((n for n, (_, a, k) in _AREAS.items() if (a, k) == (area, number)), None)
        where = f"{area.name if name is None else name}{number if name == S7_DB else ''} bytes {start}..{start + len(data) - 1} (S7)"
        if name is None or start + len(data) > len(self.memory[area, number]):
            return self._refuse(where, INVALID_ADDRESS, "no such area or beyond its end")
        end = start + len(data)
        tags = [t for t in self.tags if t.s7_area == name and t.s7_byte < end and start < t.s7_byte + t.s7_size
                and (bit is None or t.s7_bit == bit)]
        covered = {b for t in tags for b in range(t.s7_byte, t.s7_byte + t.s7_size)}
        if not tags or bit is None and any(b not in covered and b not in self.padding[name] for b in range(start, end)):
            return self._refuse(where, INVALID_ADDRESS, "no tag there")
        taken = []
        for tag in tags:
            at = f"{tag.name} at {tag.s7_address} (S7)"
            if tag.direction != OUTPUT:
                return self._refuse(at, NOT_ALLOWED, "a PLC input is read-only")
            if tag.s7_byte < start or tag.s7_byte + tag.s7_size > end:
                return self._refuse(at, INCONSISTENT, f"{tag.s7_type} takes {tag.s7_size} bytes, written only in part")
            raw = data[tag.s7_byte - start:tag.s7_byte - start + tag.s7_size]
            try:
                value = (bool(raw[0] & 1) if bit is not None else bool(raw[0] >> tag.s7_bit & 1)) \
                    if tag.s7_bit >= 0 else _decode(tag, raw)
                taken.append((tag, tag.check_written(value)))
            except ValueError as exc:
                return self._refuse(at, INCONSISTENT, str(exc))
        for tag, value in taken:
            self.image.write(tag.slot, value)
            self._store(tag, value)   # under the area's lock: bits of no tag cleared
        return None

    def _refuse(self, where: str, code: int, why: str) -> int:
        names = {NOT_ALLOWED: "0x03 object access not allowed", INVALID_ADDRESS: "0x05 invalid address",
                 INCONSISTENT: "0x07 data type inconsistent", NOT_SUPPORTED: "0x8104 function not supported"}
        self.image.refuse(where, f"{names[code]}: {why}")
        return code


class _Server(Server):
    """python-snap7's server with every write judged by the gateway, under the area's lock."""

    def __init__(self, gateway: S7Server, **kwargs):
        super().__init__(**kwargs)
        self.gateway = gateway

    def _parse_address_specification(self, addr_spec: bytes):
        spec = super()._parse_address_specification(addr_spec)
        if spec and spec["word_len"] == S7WordLen.BIT:
            spec["bit"] = int.from_bytes(addr_spec[9:12], "big") % 8
        return spec

    def _handle_read_area(self, request, client_address):
        if request["parameters"].get("item_count", 1) == 1:
            at = self._parse_read_address(request)
            cycle = self.gateway.cycle
            if at and (at[0], at[1]) == _AREAS[cycle.s7_area][1:] and at[2] < cycle.s7_byte + cycle.s7_size \
                    and cycle.s7_byte < at[2] + at[3]:
                self.gateway.image.hold()   # lockstep: held while the plant steps to its next scan (hub/gateway/image.py)
        return super()._handle_read_area(request, client_address)

    def _handle_write_area(self, request, client_address):
        items = request["parameters"].get("item_count", 1)
        if items != 1:   # snap7 parses the first item only: the others would be answered and dropped
            self.gateway._refuse(f"{items} items in one request (S7)", NOT_SUPPORTED,
                                 "a write of several items; write each item on its own")
            return self._build_error_response(request, NOT_SUPPORTED)
        parsed = self._parse_write_address(request)
        if not parsed:
            return self._build_error_response(request, 0x8001)
        area, number, start, _count, data = parsed
        bit = request["parameters"]["address_spec"].get("bit")
        lock = self.area_locks.get((area, number))
        if lock is None:
            code = self.gateway.write(area, number, start, bytes(data), bit)
        else:
            with lock:
                code = self.gateway.write(area, number, start, bytes(data), bit)
        # the answer python-snap7 gives, with the item's return code
        header = struct.pack(">BBHHHHBB", 0x32, 0x03, 0, request["sequence"], 2, 1, 0, 0)
        return header + struct.pack(">BB", 0x05, 1) + bytes([0xFF if code is None else code])

    def _handle_request_download(self, request, client_address):
        # a downloaded DB would replace data block 1 unchecked, past every tag's check
        self.gateway._refuse("a block download (S7)", NOT_SUPPORTED, "blocks are not downloaded to a gateway")
        return self._build_error_response(request, NOT_SUPPORTED)


def _encode(tag: Tag, value) -> bytes:
    if tag.type is SlotType.STRING:
        text = value.encode()[:2 * tag.length]
        return bytes([2 * tag.length, len(text)]) + text.ljust(2 * tag.length, b"\0")
    if tag.s7_type == "Word":
        return struct.pack(">H", int(value) % 65536)
    if tag.s7_type == "Int":
        return struct.pack(">h", tag.to_raw(value))
    if tag.s7_type == "Real":
        return struct.pack(">f", value)
    return struct.pack(">i", max(min(int(value), 2 ** 31 - 1), -2 ** 31))


def _decode(tag: Tag, raw: bytes):
    if tag.type is SlotType.STRING:
        length = raw[1]
        if length > 2 * tag.length:
            raise ValueError(f"a string of {length} bytes in a String[{2 * tag.length}]")
        try:
            return raw[2:2 + length].decode()
        except UnicodeDecodeError:
            raise ValueError("the string is not UTF-8") from None
    if tag.s7_type == "Word":
        return struct.unpack(">H", raw)[0]
    if tag.s7_type == "Int":
        return tag.from_raw(struct.unpack(">h", raw)[0])
    if tag.s7_type == "Real":
        return float(struct.unpack(">f", raw)[0])
    return struct.unpack(">i", raw)[0]
