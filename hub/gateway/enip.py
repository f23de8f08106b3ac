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
not supported", a name of no characters 0x04 "path segment error". A Multiple Service Packet in
which a service failed is answered with 0x1E "embedded service error" and every service's own
answer; one whose answers would pass 4002 bytes with 0x11 "reply data too large". A connected
request on a connection no one opened is 0x01 with extended status 0x0107. A request whose path or
data cannot be read (a name not ASCII, a segment cut short, a Forward Open cut short) is answered
with the encapsulation status 0x0003 "incorrect data"; a frame whose items cannot be read too, a
command EtherNet/IP does not have with 0x0001 "invalid command", and a request whose status is not
0 not at all: the connection goes on. Every refusal is logged (a request's or a frame's with the
client's address), and nothing of it reaches the plant. An SSTRING's bytes are the string's UTF-8,
both ways.

In lockstep a request naming `cycle` between two scans is held until the next begins (`image.py`), in
a thread of the loop's pool while the loop answers other clients: every tag of it is then read from
that scan.

cm-ethernetip is a pure-Python asyncio server that frames with `struct`: it answers pylogix's read of
six tags in 0.3 ms, where cpppo, the other one, took 12-17 ms (its parser reads byte by byte), and the
bottling plant routed at every step by a Logix PLC took 2.8 times the routing participant's wall
time. pycomm3 and pylogix are clients only. Its Connection Manager, Message Router and encapsulation
are used as they are; the Logix tags are this file's (`_Tags`).
"""
from __future__ import annotations

import asyncio
import contextvars
import dataclasses
import math
import struct

from ethernetip.cip.encapsulation import SIZE as HEADER_SIZE
from ethernetip.cip.encapsulation import EncapsulationCommand, EncapsulationStatus
from ethernetip.cip.identity_info import IdentityInfo
from ethernetip.cip.path import CipPath
from ethernetip.cip.service import CipServiceResponse
from ethernetip.cip.status import CipStatus
from ethernetip.connections.connection_manager import ConnectionManagerObject
from ethernetip.logix.logix_dispatcher import LogixDispatcher
from ethernetip.protocol.eip_adapter import EipAdapter
from ethernetip.protocol.messages import EncapsulationMessageManager, SendRRDataMessage, SendUnitDataMessage

from hub.core.slots import SlotType
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import hold, refuse_taken
from hub.gateway.tags import OUTPUT, Tag

READ, WRITE, READ_FRAGMENTED, WRITE_FRAGMENTED, MULTIPLE = 0x4C, 0x4D, 0x52, 0x53, 0x0A
CONNECTION_FAILURE, PATH_SEGMENT, PATH_UNKNOWN, NOT_SUPPORTED, INVALID_VALUE, PRIVILEGE_VIOLATION, TOO_LARGE, \
    NOT_ENOUGH_DATA, EMBEDDED_ERROR, GENERAL = 0x01, 0x04, 0x05, 0x08, 0x09, 0x0F, 0x11, 0x13, 0x1E, 0xFF
WRONG_TYPE, WRONG_SIZE = 0x2107, 0x2105   # extended status of GENERAL, as a ControlLogix answers
NO_CONNECTION = 0x0107   # extended status of CONNECTION_FAILURE: "target connection not found"
MEANINGS = {CONNECTION_FAILURE: "connection failure", PATH_SEGMENT: "path segment error",
            PATH_UNKNOWN: "path destination unknown", NOT_SUPPORTED: "service not supported",
            INVALID_VALUE: "invalid attribute value", PRIVILEGE_VIOLATION: "privilege violation",
            TOO_LARGE: "reply data too large", NOT_ENOUGH_DATA: "not enough data", 0x14: "attribute not supported",
            0x16: "object does not exist", EMBEDDED_ERROR: "embedded service error", GENERAL: "general error"}
REPLY_LIMIT = 4002   # bytes of a Multiple Service Packet's answers at most: a Large Forward Open's largest connection
TYPES = {"BOOL": 0xC1, "DINT": 0xC4, "REAL": 0xCA, "SSTRING": 0xDA}
NAMES = {code: name for name, code in TYPES.items()}
DINT = 2 ** 31
FLOAT32 = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]   # REAL's largest finite value
IDENTITY = IdentityInfo(device_type=0x0E, product_name="planthub gateway")   # 0x0E: a programmable logic controller
UNREADABLE = (ValueError, struct.error, IndexError)   # what cm-ethernetip's parsers raise on bytes they cannot read
_HEADER = struct.Struct("<HHIIQI")   # an encapsulation header: command, length, session, status, context, options


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
        self._manager = _Frames()   # the base's parser of frames (its own attribute)
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
        finally:
            self.writers.discard(writer)
            for conn in _OPENED.get():   # a Logix controller closes a client's connections with its TCP session
                if self.connections.find_by_ot_id(conn.ot_connection_id) is conn:
                    self.connections.remove_connection(conn)
            _OPENED.reset(opened)

    def _dispatch_message(self, msg, session_handle: int, local_addr: str):
        where = "(EtherNet/IP from {}:{})".format(*msg.remote_addr)
        if isinstance(msg, _Unread):
            self.image.refuse(where, msg.why, access="a frame")
            return msg.answer()
        if isinstance(msg, SendUnitDataMessage) and session_handle and self._sessions.is_valid(msg.session_handle) \
                and len(msg.cip_data) > 2 and self.connections.find_by_ot_id(msg.connection_id) is None:
            self.image.refuse(where, f"0x01 connection failure, extended status 0x0107: no connection "
                                     f"0x{msg.connection_id:08X} was opened", access="a connected request")
            return _no_connection(msg, session_handle)
        before = set(map(id, self.connections.active_connections))
        try:
            response = super()._dispatch_message(msg, session_handle, local_addr)
        except UNREADABLE as exc:   # cm-ethernetip's parsers of a request's path and data (our own errors are not these)
            self.image.refuse(where, f"encapsulation status 0x0003 incorrect data: {exc}", access="a request")
            return _header(_COMMAND[type(msg)], msg.session_handle, msg.sender_context, EncapsulationStatus.INCORRECT_DATA)
        status = _HEADER.unpack_from(response, 0)[3] if response else 0
        if status:   # cm-ethernetip's own refusal of a request: no session, no request it can read
            meaning = EncapsulationStatus(status).name.lower().replace("_", " ")
            self.image.refuse(where, f"encapsulation status 0x{status:04X} {meaning}", access="a request")
        _OPENED.get().extend(c for c in self.connections.active_connections if id(c) not in before)
        return response

    async def close(self) -> None:
        for writer in list(self.writers):
            writer.close()
        await super().close()


_OPENED = contextvars.ContextVar("opened")   # the CIP connections a client opened over its TCP connection


class _Frames(EncapsulationMessageManager):
    """cm-ethernetip's framing, where a whole frame it cannot read is an `_Unread` (skipped by the length
    in its header, so the connection goes on): the base raised on a command or status it does not know,
    which closed the connection unanswered, and waited for more bytes on a frame too short for its
    command, which stalled it."""

    def try_parse(self, data: bytes, remote_addr):
        if len(data) < HEADER_SIZE:
            return None, 0
        command, length, session, status, context, _ = _HEADER.unpack_from(data)
        total = HEADER_SIZE + length
        if len(data) < total:
            return None, 0
        unread = lambda answer, why: (_Unread(command, session, context, answer, why, remote_addr), total)
        if command not in _COMMANDS:
            return unread(EncapsulationStatus.INVALID_COMMAND, f"command 0x{command:04X} is no EtherNet/IP command "
                                                               "(answered with encapsulation status 0x0001 invalid command)")
        if status:   # a request's status is 0: one that is not is ignored
            return unread(None, f"a {EncapsulationCommand(command).name} request's status is 0x{status:08X}, not 0 "
                                "(not answered)")
        try:
            msg, consumed = super().try_parse(data, remote_addr)
        except UNREADABLE as exc:
            msg, why = None, str(exc)
        else:
            why = "its items cannot be read"
        if msg is None:
            return unread(EncapsulationStatus.INCORRECT_DATA, f"a {EncapsulationCommand(command).name} frame of "
                                                              f"{total} bytes cannot be read: {why} (answered with "
                                                              "encapsulation status 0x0003 incorrect data)")
        return msg, consumed


_COMMANDS = frozenset(int(c) for c in EncapsulationCommand)
_COMMAND = {SendRRDataMessage: EncapsulationCommand.SEND_RR_DATA,   # the messages that carry CIP requests
            SendUnitDataMessage: EncapsulationCommand.SEND_UNIT_DATA}


@dataclasses.dataclass(frozen=True)
class _Unread:
    """A frame `_Frames` could not read: what to answer (None: nothing) and why."""
    command: int
    session_handle: int
    sender_context: int
    status: EncapsulationStatus | None
    why: str
    remote_addr: tuple

    def answer(self) -> bytes | None:
        return None if self.status is None else _header(self.command, self.session_handle, self.sender_context,
                                                        self.status)


def _header(command: int, session_handle: int, sender_context: int, status: EncapsulationStatus) -> bytes:
    """An answer that is a header alone: a request refused with an encapsulation status."""
    return _HEADER.pack(int(command), 0, session_handle, int(status), sender_context, 0)


def _no_connection(msg: SendUnitDataMessage, session_handle: int) -> bytes:
    """The answer to a connected request on a connection no one opened: CIP's "target connection not found"."""
    answer = bytearray(16)
    size = CipServiceResponse.error(msg.cip_data[2], CipStatus.error(CONNECTION_FAILURE, NO_CONNECTION)).encode(answer)
    return SendUnitDataMessage(session_handle=session_handle, sender_context=msg.sender_context,
                               connection_id=msg.connection_id, cip_data=msg.cip_data[:2] + bytes(answer[:size])).to_bytes()


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
        """Every request, and every one a Multiple Service Packet or an Unconnected Send holds. A refusal
        that none of ours logged (cm-ethernetip's own) is logged here."""
        logged = self.image.refused
        response = super().dispatch(service, path, data)
        if service == MULTIPLE and response.status.is_success:
            if len(response.data) > REPLY_LIMIT:
                return self._refuse(service, "(EtherNet/IP)", f"{len(response.data)} bytes of answers, more than "
                                    f"{REPLY_LIMIT}", TOO_LARGE, access="a Multiple Service Packet")
            count, failed = _failed(response.data)
            if failed:   # as a ControlLogix answers: "embedded service error", each service's answer its own
                unread = failed - (self.image.refused - logged)   # those cm-ethernetip could not read, unlogged
                if unread > 0:
                    self.image.refuse("(EtherNet/IP)", f"0x04 path segment error: {unread} of its {count} services "
                                      "cannot be read", access="a Multiple Service Packet")
                return dataclasses.replace(response, status=CipStatus.error(EMBEDDED_ERROR))
        elif not response.status.is_success and self.image.refused == logged:
            status = response.status.general_status
            to = "a path of no class and no tag" if path.class_id is None else \
                f"class 0x{path.class_id:02X}, instance {path.instance_id}"
            self.image.refuse("(EtherNet/IP)", f"0x{status:02X} {MEANINGS.get(status, 'CIP error')}: service "
                              f"0x{service:02X} to {to}", access="a request")
        return response

    def on_unhandled(self, service: int, path: CipPath, data: bytes, default_status: int = PATH_UNKNOWN):
        if path.symbolic_name is None:
            return super().on_unhandled(service, path, data, default_status)
        try:
            return self._tag_service(service, path, data)
        except UNREADABLE as exc:   # ours, not the request's: not to be taken for a request that cannot be read
            raise RuntimeError(f"EtherNet/IP service 0x{service:02X} on {path.symbolic_name!r} failed") from exc

    def _tag_service(self, service: int, path: CipPath, data: bytes) -> CipServiceResponse:
        if not path.symbolic_name:
            return self._refuse(service, "(EtherNet/IP)", "a symbolic segment of no characters", PATH_SEGMENT,
                                access="a request")
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
        meaning = MEANINGS[status] + ("" if extended is None else f", extended status 0x{extended:04X}")
        self.image.refuse(where, f"0x{status:02X} {meaning}: {why}", access=access)
        codes = (status,) if extended is None else (status, extended)
        return CipServiceResponse.error(service, CipStatus.error(*codes))


def _failed(answers: bytes) -> tuple[int, int]:
    """How many answers a Multiple Service Packet's answer (a count, the offsets, the answers) holds, and
    how many of them are refusals."""
    (count,) = struct.unpack_from("<H", answers)
    return count, sum(answers[offset + 2] != 0 for offset in struct.unpack_from(f"<{count}H", answers, 2))


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
