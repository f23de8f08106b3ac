"""planthub gateway enip: the tags as Logix controller tags read and written by name by pylogix in
another process (a real server), every kind of bad request refused with CIP's own status and
logged, nothing of it reaching the plant, strings in UTF-8 both ways; a taken port refused naming
it; and the bottling plant routed by a Logix PLC client scanning every 0.1 s (at every step:
tests/test_gateway_plant.py)."""
import re
import socket
import subprocess
import sys
import textwrap
import time

import pytest

from hub.core.errors import PlanthubError
from hub.gateway.enip import EnipServer
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import BOTTLING, bottling_via_gateway, free_port
from .helpers import ROOT
from .test_bottling_plant import deliveries
from .test_gateway import belt_scenario, overrides

DURATION = 36.0   # s: the first bottle has been read, routed and delivered (sink_A)

CLIENT = """
from pylogix import PLC
with PLC("127.0.0.1") as c:
    c.Port = PORT
    read = [(r.TagName, r.Value, r.Status) for r in c.Read(["occupied", "seen", "velocity", "cycle"])]
    who = c.Read("who").Value
    odd = {"in capitals": (lambda r: (r.Value, r.Status))(c.Read("CYCLE")),
           "two elements": c.Read("seen", count=2).Status, "an element": c.Read("seen[1]").Status}
    statuses = {what: c.Write(name, value).Status for what, name, value in [
        ("an input", "occupied", False), ("out of range", "speed", 9.0), ("not finite", "speed", float("nan")),
        ("unknown", "sped", 1.0), ("the scan number", "cycle", 3), ("a good speed", "speed", 1.5),
        ("a good bit", "run", True), ("a string too long", "label", "x" * 17),
        ("a string not UTF-8", "label", "\\xff\\xfe"),   # pylogix sends an SSTRING's characters as bytes
        ("a good string", "label", "B\\u00e9".encode().decode("latin-1"))]}   # "Bé" in UTF-8
    print(repr((read, who, odd, statuses)))
"""
RAW = """
import asyncio, struct
from ethernetip.logix.tag_client import TagClient

async def main():   # unconnected requests of the wrong shape, which pylogix does not send
    async with TagClient("127.0.0.1", PORT) as c:
        said = {}
        for what, data in [("a DINT to a REAL", (0xC4, 1, struct.pack("<i", 1))),
                           ("too few bytes", (0xCA, 1, b"\\x00\\x00")),
                           ("two elements", (0xCA, 2, struct.pack("<ff", 1, 1)))]:
            try:
                await c.write_raw("speed", *data)
                said[what] = "taken"
            except RuntimeError as exc:
                said[what] = str(exc)
        print(repr(said))

asyncio.run(main())
"""


def test_bad_logix_writes_get_their_cip_status_and_nothing_reaches_the_plant(tmp_path, caplog):
    scenario = belt_scenario(tmp_path)   # with a string the PLC writes
    scenario.write_text(scenario.read_text().replace("outputs: {speed: real, run: bool}",
                                                     "outputs: {speed: real, run: bool, label: string}"))
    tags = tag_map(load_scenario(scenario), "plc", overrides(tmp_path, "tags:\n  speed: {scale: [0, 2]}\n"))
    assert [tags.by_slot[s].logix_type for s in ("occupied", "seen", "velocity", "who", "speed", "run")] == \
           ["BOOL", "DINT", "REAL", "SSTRING", "REAL", "BOOL"]
    image, port = ProcessImage(tags), free_port()
    with ServerThread(EnipServer(image, f"127.0.0.1:{port}"), "enip"):
        image.put({"who": "B\u00e91", "occupied": True, "seen": 3})
        proc, raw = (subprocess.run([sys.executable, "-c", textwrap.dedent(code).replace("PORT", str(port))],
                                    capture_output=True, text=True, cwd=ROOT, timeout=60) for code in (CLIENT, RAW))
    assert proc.returncode == 0 and raw.returncode == 0, proc.stderr[-2000:] + raw.stderr[-2000:]
    read, who, odd, statuses = eval(proc.stdout)
    assert odd == {"in capitals": (0, "Success"),   # Logix names are not case-sensitive
                   "two elements": "Unknown error 255", "an element": "Unknown error 255"}   # pylogix has no name for 0xFF
    assert eval(raw.stdout) == {what: f"CIP error: service=0x4D, status=0x{status:02X}" for what, status in
                                [("a DINT to a REAL", 0xFF), ("too few bytes", 0x13), ("two elements", 0xFF)]}
    assert read == [("occupied", True, "Success"), ("seen", 3, "Success"), ("velocity", 0.0, "Success"),
                    ("cycle", 0, "Success")] and who == "B\u00e91"   # in UTF-8, as pylogix reads it
    assert statuses == {"an input": "Privilege violation", "out of range": "Invalid Attribute",
                        "not finite": "Invalid Attribute", "unknown": "Path destination unknown",
                        "the scan number": "Privilege violation", "a good speed": "Success", "a good bit": "Success",
                        "a string too long": "Invalid Attribute", "a string not UTF-8": "Invalid Attribute",
                        "a good string": "Success"}
    assert image.outputs() == {"speed": 1.5, "run": True, "label": "B\u00e9"} and image.refused == 12
    logged = caplog.text
    assert "refused a write to speed (EtherNet/IP): 0x09 invalid attribute value: 9.0 is outside 0..2" in logged
    assert "refused a write to occupied (EtherNet/IP): 0x0F privilege violation: a PLC input is read-only" in logged
    # pylogix reads a tag to learn its type before writing it: a tag no one has is refused at that read
    assert "refused a read of sped (EtherNet/IP): 0x05 path destination unknown: no such tag" in logged
    assert "refused a read of seen (EtherNet/IP): 0xFF general error, extended status 0x2105: element 1 of a tag of one" in logged
    assert "refused a read of seen (EtherNet/IP): 0xFF general error, extended status 0x2105: 2 elements from byte 0" in logged
    assert "refused a write to speed (EtherNet/IP): 0xFF general error, extended status 0x2107: a DINT written to a REAL" in logged
    assert "refused a write to speed (EtherNet/IP): 0x13 not enough data: too few bytes for a REAL" in logged
    assert "refused a write to speed (EtherNet/IP): 0xFF general error, extended status 0x2105: 2 elements written to a tag of one" in logged
    assert "refused a write to label (EtherNet/IP): 0x09 invalid attribute value: 17 bytes is longer than 16" in logged
    assert "refused a write to label (EtherNet/IP): 0x09 invalid attribute value: 'utf-8' codec can't decode" in logged


UNREADABLE = r"""
import socket, struct

def frame(command, payload, session=0, status=0):
    return struct.pack("<HHIIQI", command, len(payload), session, status, 7, 0) + payload

def unconnected(mr):   # SendRRData's interface, timeout and two items: a null address and the request
    return struct.pack("<IHHHHHH", 0, 0, 2, 0, 0, 0xB2, len(mr)) + mr

def connected(connection, mr):   # SendUnitData's: a connected address and the sequence count, then the request
    return struct.pack("<IHHHHIHHH", 0, 0, 2, 0xA1, 4, connection, 0xB1, len(mr) + 2, 1) + mr

def answer(s):
    head = s.recv(24, socket.MSG_WAITALL)
    if len(head) < 24:
        return "closed"
    length, status = struct.unpack_from("<H", head, 2)[0], struct.unpack_from("<I", head, 8)[0]
    body = s.recv(length, socket.MSG_WAITALL)
    return status, body[16:].hex()   # the Message Router's answer, after the items' headers

READ = bytes([0x4C, 4, 0x91, 5]) + b"cycle\x00" + bytes([1, 0])
PACKET = bytes([0x0A, 2, 0x20, 0x02, 0x24, 0x01])   # a Multiple Service Packet to the Message Router
said = {}
with socket.create_connection(("127.0.0.1", PORT), timeout=10) as s:
    s.sendall(frame(0x65, struct.pack("<HH", 1, 0)))   # RegisterSession
    handle = struct.unpack_from("<I", s.recv(28, socket.MSG_WAITALL), 4)[0]
    for what, command, payload in [
            ("a name not ASCII", 0x6F, unconnected(bytes([0x4C, 2, 0x91, 2, 0xE9, 0x78, 1, 0]))),
            ("a segment cut short", 0x6F, unconnected(bytes([0x4C, 1, 0x21, 0, 1, 0]))),   # a 16-bit class id of no bytes
            ("a Forward Open cut short", 0x6F, unconnected(bytes([0x54, 2, 0x20, 0x06, 0x24, 0x01, 0, 0, 0, 0]))),
            ("a Forward Close cut short", 0x6F, unconnected(bytes([0x4E, 2, 0x20, 0x06, 0x24, 0x01, 0, 0]))),
            ("a name of no characters", 0x6F, unconnected(bytes([0x4C, 1, 0x91, 0, 1, 0]))),
            ("another service on a tag", 0x6F, unconnected(bytes([0x0E, 4, 0x91, 5]) + b"cycle\x00")),
            ("a packet of a good read and a bad one", 0x6F, unconnected(
                PACKET + bytes([2, 0, 6, 0, 18, 0]) + READ + bytes([0x4C, 3, 0x91, 4]) + b"sped" + bytes([1, 0]))),
            ("a packet of two good reads", 0x6F, unconnected(PACKET + bytes([2, 0, 6, 0, 18, 0]) + READ * 2)),
            ("a packet whose second offset is past its end", 0x6F, unconnected(PACKET + bytes([2, 0, 6, 0, 200, 0]) + READ)),
            ("a packet whose answers pass 4002 bytes", 0x6F, unconnected(   # 400 reads of cycle
                PACKET + struct.pack("<H400H", 400, *range(802, 802 + 400 * len(READ), len(READ))) + READ * 400)),
            ("a connected read on no connection", 0x70, connected(0x12345678, READ)),
            ("a frame whose items cannot be read", 0x6F, b"\x00\x00"),
            ("a command no one has", 0x9999, b""),
            ("then a good read", 0x6F, unconnected(READ))]:
        s.sendall(frame(command, payload, handle))
        said[what] = answer(s)
    s.sendall(frame(0x6F, unconnected(READ), handle, status=0x42) + frame(0x6F, unconnected(READ), handle))
    said["a request with a status, then a good read"] = answer(s)   # the first is not answered
print(repr(said))
"""


def test_raw_requests_get_a_controllers_answers_and_those_it_cannot_read_are_refused_and_logged(tmp_path, caplog):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc")
    image, port = ProcessImage(tags), free_port()
    with ServerThread(EnipServer(image, f"127.0.0.1:{port}"), "enip"):
        proc = subprocess.run([sys.executable, "-c", UNREADABLE.replace("PORT", str(port))],
                              capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr[-2000:]
    read = "cc000000c40000000000"   # cycle: a DINT, 0
    assert eval(proc.stdout) == {   # one connection, which goes on through all of them
        "a name not ASCII": (3, ""), "a segment cut short": (3, ""), "a Forward Open cut short": (3, ""),   # incorrect data
        "a Forward Close cut short": (0, "ce001300"),   # CIP's 0x13 not enough data
        "a name of no characters": (0, "cc000400"),   # CIP's 0x04 path segment error
        "another service on a tag": (0, "8e000800"),   # CIP's 0x08 service not supported
        "a packet of a good read and a bad one": (0, "8a001e00" "0200" "0600" "1000" + read + "cc000500"),
        "a packet of two good reads": (0, "8a000000" "0200" "0600" "1000" + read * 2),
        "a packet whose second offset is past its end": (0, "8a001e00" "0200" "0600" "1000" + read + "80000400"),
        "a packet whose answers pass 4002 bytes": (0, "8a001100"),   # reply data too large
        "a connected read on no connection": (0, "b1000800" "0100" "cc0001010701"),   # its count, then 0x01/0x0107
        "a frame whose items cannot be read": (3, ""), "a command no one has": (1, ""),   # invalid command
        "then a good read": (0, read), "a request with a status, then a good read": (0, read)}
    assert image.refused == 13 and image.outputs() == {"speed": 0.0, "run": False}
    logged = re.sub(r"EtherNet/IP from 127\.0\.0\.1:\d+", "EtherNet/IP from the PLC", caplog.text)
    for line in [
            "a request (EtherNet/IP from the PLC): encapsulation status 0x0003 incorrect data: 'ascii' codec can't decode "
            "byte 0xe9",
            "a request (EtherNet/IP from the PLC): encapsulation status 0x0003 incorrect data: unpack_from requires a buffer",
            "a request (EtherNet/IP from the PLC): encapsulation status 0x0003 incorrect data: Forward Open requires at "
            "least 36 bytes",
            "a request (EtherNet/IP): 0x13 not enough data: service 0x4E to class 0x06, instance 1",
            "a request (EtherNet/IP): 0x04 path segment error: a symbolic segment of no characters",
            "a request to cycle (EtherNet/IP): 0x08 service not supported: service 0x0E on a tag",
            "a read of sped (EtherNet/IP): 0x05 path destination unknown: no such tag",
            "a Multiple Service Packet (EtherNet/IP): 0x04 path segment error: 1 of its 2 services cannot be read",
            "a Multiple Service Packet (EtherNet/IP): 0x11 reply data too large: 4802 bytes of answers, more than 4002",
            "a connected request (EtherNet/IP from the PLC): 0x01 connection failure, extended status 0x0107: no "
            "connection 0x12345678 was opened",
            "a frame (EtherNet/IP from the PLC): a SEND_RR_DATA frame of 26 bytes cannot be read: its items cannot be "
            "read (answered with encapsulation status 0x0003 incorrect data)",
            "a frame (EtherNet/IP from the PLC): command 0x9999 is no EtherNet/IP command (answered with encapsulation "
            "status 0x0001 invalid command)",
            "a frame (EtherNet/IP from the PLC): a SEND_RR_DATA request's status is 0x00000042, not 0 (not answered)"]:
        assert f"gateway: refused {line}" in logged, line


GONE = """
import os, sys
from pylogix import PLC
c = PLC("127.0.0.1")
c.Port = PORT
print(c.Read("cycle").Status, flush=True)   # over the CIP connection pylogix opens with a Forward Open
sys.stdin.readline()
os._exit(0)   # no Forward Close, no unregistering: as a PLC that crashes
"""


def test_a_clients_cip_connection_ends_with_its_tcp_connection(tmp_path):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc")
    port = free_port()
    server = EnipServer(ProcessImage(tags), f"127.0.0.1:{port}")
    with ServerThread(server, "enip"):
        for _ in range(2):
            with subprocess.Popen([sys.executable, "-c", textwrap.dedent(GONE).replace("PORT", str(port))], cwd=ROOT,
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True) as proc:
                try:
                    assert proc.stdout.readline() == "Success\n"
                    assert len(server.adapter.connections.active_connections) == 1   # its Forward Open's
                    proc.communicate("\n", timeout=60)
                finally:
                    proc.kill()
            deadline = time.monotonic() + 10.0
            while server.adapter.connections.active_connections and time.monotonic() < deadline:
                time.sleep(0.01)
            assert server.adapter.connections.active_connections == []


def test_an_enip_gateway_on_a_taken_port_does_not_start_naming_the_endpoint(tmp_path):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(PlanthubError) as refused:
            with ServerThread(EnipServer(ProcessImage(tags), f"127.0.0.1:{port}"), "enip server"):
                pass
    assert str(refused.value) == (f"EtherNet/IP server at 127.0.0.1:{port} did not start: Address already in use "
                                  "(another gateway or server holds the port?)")


@pytest.mark.slow
def test_a_logix_plc_scanning_every_100_ms_routes_the_bottling_plant(tmp_path):
    out, said, summary = bottling_via_gateway(tmp_path, "enip", DURATION, "--scan", "0.1")
    scans, decisions = int(said.split()[1]), int(said.split()[3])
    assert scans == round(DURATION / 0.1) and decisions >= 1
    taken, misrouted = deliveries(load_scenario(BOTTLING), out)
    assert not misrouted and taken, (taken, misrouted)
    assert summary["ended"]["kind"] != "failed"
