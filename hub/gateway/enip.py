"""The EtherNet/IP side of a gateway (cm-ethernetip's CIP stack): every cm-ethernetip call planthub makes is in this file.

Each tag is a controller-scoped Logix tag of its name and type (BOOL, DINT, REAL, SSTRING; the tag
map decides them), read and written by name with the Read/Write Tag services (and their fragmented
forms), alone or in a Multiple Service Packet, unconnected or over a Forward Open connection, as a
ControlLogix answers pylogix. Names are not case-sensitive, as in Logix. Reads are answered from the
process image. A write is checked before it is taken, and refused with CIP's own general status: a
PLC input 0x0F "privilege violation"; a value out of the tag's range, not finite, or a string too
long or not UTF-8 0x09 "invalid attribute value"; a value of another type 0xFF with extended status
0x2107, more than one element 0xFF 0x2105, too few bytes 0x13 "not enough data". A tag no one has
is 0x05 "path destination unknown" for a read as for a write, another service on a tag 0x08 "service
not supported". A Multiple Service Packet in which a service failed is answered with 0x1E "embedded
service error" and every service's own answer. A request whose path or data cannot be read (a name
not ASCII, a segment cut short, a Forward Open cut short) is answered with the encapsulation status
0x0003 "incorrect data", and a frame that cannot be read closes its connection. Every refusal is
logged, and nothing of it reaches the plant. An SSTRING's bytes are the string's UTF-8, both ways.

In lockstep a request naming `cycle` between two scans is held until the next begins (`image.py`), in
a thread of the loop's pool while the loop answers other clients: every tag of it is then read from
that scan.

cm-ethernetip is a pure-Python asyncio server that frames with `struct` (cpppo, the other one, parses
byte by byte and costs a lockstep PLC's scan several times more); pycomm3 and pylogix are clients
only. Its Connection Manager, Message Router and encapsulation are used as they are; the Logix tags
are this file's (`_Tags`).
"""
from __future__ import annotations

import asyncio
import contextvars
import dataclasses
import math
import struct

from ethernetip.cip.encapsulation import SIZE as HEADER_SIZE
from ethernetip.cip.encapsulation import EncapsulationCommand, EncapsulationHeader, EncapsulationStatus
from ethernetip.cip.identity_info import IdentityInfo
from ethernetip.cip.path import CipPath
from ethernetip.cip.service import CipServiceResponse
from ethernetip.cip.status import CipStatus
from ethernetip.connections.connection_manager import ConnectionManagerObject
from ethernetip.logix.logix_dispatcher import LogixDispatcher
from ethernetip.protocol.eip_adapter import EipAdapter
from ethernetip.protocol.messages import EncapsulationMessageManager, SendUnitDataMessage

from hub.core.slots import SlotType
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import hold, refuse_taken
from hub.gateway.tags import OUTPUT, Tag

READ, WRITE, READ_FRAGMENTED, WRITE_FRAGMENTED, MULTIPLE = 0x4C, 0x4D, 0x52, 0x53, 0x0A
PATH_UNKNOWN, NOT_SUPPORTED, INVALID_VALUE, PRIVILEGE_VIOLATION, NOT_ENOUGH_DATA, EMBEDDED_ERROR, GENERAL = \
    0x05, 0x08, 0x09, 0x0F, 0x13, 0x1E, 0xFF
WRONG_TYPE, WRONG_SIZE = 0x2107, 0x2105   # extended status of GENERAL, as a ControlLogix answers
TYPES = {"BOOL": 0xC1, "DINT": 0xC4, "REAL": 0xCA, "SSTRING": 0xDA}
NAMES = {code: name for name, code in TYPES.items()}
DINT = 2 ** 31
FLOAT32 = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]   # REAL's largest finite value
IDENTITY = IdentityInfo(device_type=0x0E, product_name="planthub gateway")   # 0x0E: a programmable logic controller
UNREADABLE = (ValueError, struct.error, IndexError)   # what cm-ethernetip's parsers raise on bytes they cannot read


class EnipServer:
    """The tags of `image` served as Logix controller tags at `endpoint` (HOST:PORT; EtherNet/IP's own port is 44818)."""

    def __init__(self, image: ProcessImage, endpoint: str):
        self.image = image
        host, _, port = endpoint.rpartition(":")
        self.host, self.port = host or "127.0.0.1", int(port)
        self.adapter = None

    async def start(self) -> None:
        refuse_taken(self.host, self.port, f"EtherNet/IP server at {self.host}:{self.port} did not start")
        tags = _Tags(self.image)
        self.adapter = _Adapter(tags, self.image)
        await self.adapter.listen(self.host, self.port)

    def publish(self, changed: dict) -> None:
        """Nothing to do: every read is answered from the image."""

    async def stop(self) -> None:
        if self.adapter is not None:
            await self.adapter.close()
            self.adapter = None


class _Adapter(EipAdapter):
    """cm-ethernetip's TCP server, which holds a poll of `cycle` between two scans, closes the CIP
    connections a client opened when its TCP connection ends (as a Logix controller does: a PLC that
    restarts may open its connection again), and closes its clients' TCP connections when it stops
    (asyncio's server only stops listening)."""

    def __init__(self, tags: _Tags, image: ProcessImage):
        super().__init__(tags, IDENTITY)
        self._manager = _Frames()
        self.image = image
        cycle = image.tags.by_slot["cycle"].name.lower().encode()
        self.poll = bytes([0x91, len(cycle)]) + cycle   # `cycle`'s ANSI symbolic segment in a request
        self.writers = set()
        self.connections = tags.connections
        # A connected reply carries the connection id the client chose for it (a Logix MSG instruction
        # ignores any other): the Connection Manager's record of the Forward Open has it
        self.connection_id_lookup = lambda ot: getattr(tags.connections.find_by_ot_id(ot), "to_connection_id", 0)

    async def _handle_client(self, reader, writer) -> None:
        self.writers.add(writer)
        opened = _OPENED.set([])
        try:
            await super()._handle_client(_Polls(reader, self.image, self.poll), writer)
        except UNREADABLE as exc:   # no way to find the next frame: the connection is closed (by the base's finally)
            self.image.refuse("(EtherNet/IP)", f"{exc}; its connection is closed", access="a frame")
        finally:
            self.writers.discard(writer)
            for conn in _OPENED.get():   # a Logix controller closes a client's connections with its TCP session
                if self.connections.find_by_ot_id(conn.ot_connection_id) is conn:
                    self.connections.remove_connection(conn)
            _OPENED.reset(opened)

    def _dispatch_message(self, msg, session_handle: int, local_addr: str):
        before = set(map(id, self.connections.active_connections))
        try:
            response = super()._dispatch_message(msg, session_handle, local_addr)
        except UNREADABLE as exc:
            self.image.refuse("(EtherNet/IP)", f"encapsulation status 0x0003 incorrect data: {exc}", access="a request")
            return _incorrect_data(msg)
        _OPENED.get().extend(c for c in self.connections.active_connections if id(c) not in before)
        return response

    async def close(self) -> None:
        for writer in list(self.writers):
            writer.close()
        await super().close()


_OPENED = contextvars.ContextVar("opened")   # the CIP connections a client opened over its TCP connection


class _Frames(EncapsulationMessageManager):
    """cm-ethernetip's framing, with a whole frame too short for its command an error (the base would
    wait for more bytes and leave the connection stalled)."""

    def try_parse(self, data: bytes, remote_addr):
        msg, consumed = super().try_parse(data, remote_addr)
        if msg is None and consumed:
            command = EncapsulationHeader.parse(data).command
            raise ValueError(f"a {command.name} frame of {consumed} bytes is too short for its command")
        return msg, consumed


def _incorrect_data(msg) -> bytes:
    """The answer to a request whose CIP path or data cannot be read."""
    command = EncapsulationCommand.SEND_UNIT_DATA if isinstance(msg, SendUnitDataMessage) else \
        EncapsulationCommand.SEND_RR_DATA
    buf = bytearray(HEADER_SIZE)
    EncapsulationHeader(command=command, session_handle=msg.session_handle, status=EncapsulationStatus.INCORRECT_DATA,
                        sender_context=msg.sender_context).write_to(buf)
    return bytes(buf)


class _Polls:
    """A connection's reader that holds a request naming `cycle` between two scans until the next begins
    (at most the image's hold limit), in a thread of the loop's pool. A request split across two reads
    at that segment is answered at once: loopback and a PLC's small requests come whole."""

    def __init__(self, reader: asyncio.StreamReader, image: ProcessImage, poll: bytes):
        self.reader, self.image, self.poll = reader, image, poll

    async def read(self, n: int) -> bytes:
        chunk = await self.reader.read(n)
        if self.poll in chunk.lower() and self.image.between_scans():
            await hold(self.image)
        return chunk


class _Tags(LogixDispatcher):
    """The Logix tags of the process image, behind cm-ethernetip's Message Router and Connection Manager."""

    def __init__(self, image: ProcessImage):
        super().__init__(identity=IDENTITY)
        self.image = image
        self.by_name = {t.name.lower(): t for t in image.tags.tags}
        self.connections = ConnectionManagerObject()   # one this gateway keeps, for the connected replies' ids
        self.connections.dispatch_request = self.dispatch
        self.register_class(self.connections.cip_class)

    def dispatch(self, service: int, path: CipPath, data: bytes) -> CipServiceResponse:
        response = super().dispatch(service, path, data)
        if service == MULTIPLE and response.status.is_success and _any_failed(response.data):
            # as a ControlLogix answers a Multiple Service Packet: "embedded service error", each answer its own
            return dataclasses.replace(response, status=CipStatus.error(EMBEDDED_ERROR))
        return response

    def on_unhandled(self, service: int, path: CipPath, data: bytes, default_status: int = PATH_UNKNOWN):
        if path.symbolic_name is None:
            return super().on_unhandled(service, path, data, default_status)
        tag = self.by_name.get(path.symbolic_name.lower())
        writing = service in (WRITE, WRITE_FRAGMENTED)
        if tag is None:
            return self._refuse(service, f"{path.symbolic_name} (EtherNet/IP)", "no such tag", PATH_UNKNOWN,
                                access="a write to" if writing else "a read of")
        where = f"{tag.name} (EtherNet/IP)"
        if path.element_id:
            return self._refuse(service, where, f"element {path.element_id} of a tag of one", GENERAL, WRONG_SIZE,
                                access="a write to" if writing else "a read of")
        if service in (READ, READ_FRAGMENTED):
            return self._read(service, tag, data)
        if writing:
            return self._write(service, tag, where, data)
        return self._refuse(service, where, f"service 0x{service:02X} on a tag", NOT_SUPPORTED, access="a request to")

    def _read(self, service: int, tag: Tag, data: bytes) -> CipServiceResponse:
        fragmented = service == READ_FRAGMENTED
        where = f"{tag.name} (EtherNet/IP)"
        if len(data) < (6 if fragmented else 2):
            return self._refuse(service, where, "no element count", NOT_ENOUGH_DATA, access="a read of")
        count, offset = struct.unpack_from("<HI", data) if fragmented else (struct.unpack_from("<H", data)[0], 0)
        if count != 1 or offset:
            return self._refuse(service, where, f"{count} elements from byte {offset} of a tag of one", GENERAL,
                                WRONG_SIZE, access="a read of")
        return CipServiceResponse.success(service, struct.pack("<H", TYPES[tag.logix_type]) +
                                          _encode(tag, self.image.read(tag.slot)))

    def _write(self, service: int, tag: Tag, where: str, data: bytes) -> CipServiceResponse:
        head = 8 if service == WRITE_FRAGMENTED else 4
        if len(data) < head:
            return self._refuse(service, where, "no type and count", NOT_ENOUGH_DATA)
        kind, count = struct.unpack_from("<HH", data)
        if kind != TYPES[tag.logix_type]:
            got = NAMES.get(kind, f"type 0x{kind:04X}")
            return self._refuse(service, where, f"a {got} written to a {tag.logix_type}", GENERAL, WRONG_TYPE)
        if count != 1 or (head == 8 and struct.unpack_from("<I", data, 4)[0]):
            return self._refuse(service, where, f"{count} elements written to a tag of one", GENERAL, WRONG_SIZE)
        if tag.direction != OUTPUT:
            return self._refuse(service, where, "a PLC input is read-only", PRIVILEGE_VIOLATION)
        try:
            value = tag.check_written(_decode(tag, data[head:]))
        except struct.error:
            return self._refuse(service, where, f"too few bytes for a {tag.logix_type}", NOT_ENOUGH_DATA)
        except (ValueError, UnicodeDecodeError) as exc:
            return self._refuse(service, where, str(exc), INVALID_VALUE)
        self.image.write(tag.slot, value)
        return CipServiceResponse.success(service)

    def _refuse(self, service: int, where: str, why: str, status: int, extended: int | None = None,
                access: str = "a write to") -> CipServiceResponse:
        meaning = {PATH_UNKNOWN: "path destination unknown", NOT_SUPPORTED: "service not supported",
                   INVALID_VALUE: "invalid attribute value", PRIVILEGE_VIOLATION: "privilege violation",
                   NOT_ENOUGH_DATA: "not enough data",
                   GENERAL: f"general error, extended status 0x{extended or 0:04X}"}[status]
        self.image.refuse(where, f"0x{status:02X} {meaning}: {why}", access=access)
        codes = (status,) if extended is None else (status, extended)
        return CipServiceResponse.error(service, CipStatus.error(*codes))


def _any_failed(answers: bytes) -> bool:
    """Whether an answer of a Multiple Service Packet (a count, the offsets, the answers) holds a failed one."""
    (count,) = struct.unpack_from("<H", answers)
    return any(answers[offset + 2] for offset in struct.unpack_from(f"<{count}H", answers, 2))


def _encode(tag: Tag, value) -> bytes:
    if tag.logix_type == "BOOL":
        return b"\x01" if value else b"\x00"
    if tag.logix_type == "DINT":   # an event counter wraps, a number saturates
        return struct.pack("<i", (int(value) + DINT) % (2 * DINT) - DINT if tag.type is SlotType.VOID else
                           max(min(int(value), DINT - 1), -DINT))
    if tag.logix_type == "REAL":   # a value beyond REAL's range is its infinity, as a float32 cast gives
        return struct.pack("<f", value if abs(value) <= FLOAT32 or math.isnan(value) else math.copysign(math.inf, value))
    raw = value.encode()[:2 * tag.length].decode(errors="ignore").encode()   # whole characters only
    return bytes([len(raw)]) + raw


def _decode(tag: Tag, data: bytes):
    if tag.logix_type == "BOOL":
        return struct.unpack_from("<B", data)[0] != 0
    if tag.logix_type == "DINT":
        return struct.unpack_from("<i", data)[0]
    if tag.logix_type == "REAL":
        return float(struct.unpack_from("<f", data)[0])
    (size,) = struct.unpack_from("<B", data)
    if len(data) < 1 + size:
        raise struct.error("short")
    if size > 2 * tag.length:
        raise ValueError(f"{size} bytes is longer than {2 * tag.length}")
    return data[1:1 + size].decode()
