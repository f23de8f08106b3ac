"""A PLC's poll of `cycle` in lockstep, over each protocol: made while the plant steps toward its next
scan (the PLC answered the last), it is held by the gateway and answered with the next scan's
number as soon as that scan begins, while the server goes on answering other clients; in live mode
it is answered at once. The hold has a limit and ends with the run. A real server in this process,
real clients of the protocol in other processes."""
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import namespace, tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import BOTTLING, free_port
from .helpers import ROOT

LIMIT = 60.0  # s for anything the test waits on
HOLD = 2 * LIMIT   # s: a hold that is not ended by its scan outlasts every wait of the test

READ = {   # a client reading a tag (`cycle`, unless told) once and printing it (the placeholders filled in below)
    "modbus": """
        from pymodbus.client import ModbusTcpClient
        c = ModbusTcpClient("127.0.0.1", port=PORT, timeout=60, retries=0)
        assert c.connect()
        print(c.read_input_registers(ADDRESS, count=1).registers[0])""",
    "s7": """
        import struct, snap7
        from snap7.type import Area
        c = snap7.Client()
        c.connect("127.0.0.1", 0, 1, PORT)
        print(struct.unpack(">H", c.read_area(Area.AREA, 0, BYTE, 2))[0])""",
    "enip": """
        from pylogix import PLC
        with PLC("127.0.0.1") as c:
            c.Port, c.SocketTimeout = PORT, 60
            print(c.Read("TAG").Value)""",
    "opcua": """
        import asyncio
        from asyncua import Client, ua
        async def main():
            async with Client("ENDPOINT", timeout=60) as c:
                ns = await c.get_namespace_index("NAMESPACE")
                print(await c.get_node(ua.NodeId("NODE", ns)).read_value())
        asyncio.run(main())""",
}


def server_of(protocol: str, image: ProcessImage, port: int):
    if protocol == "modbus":
        from hub.gateway.modbus import ModbusServer
        return ModbusServer(image, f"127.0.0.1:{port}")
    if protocol == "s7":
        from hub.gateway.s7 import S7Server
        return S7Server(image, f"127.0.0.1:{port}")
    if protocol == "enip":
        from hub.gateway.enip import EnipServer
        return EnipServer(image, f"127.0.0.1:{port}")
    from hub.gateway.opcua import OpcUaServer
    return OpcUaServer(image, f"opc.tcp://127.0.0.1:{port}/planthub")


def scan(server, image: ProcessImage, cycle: int) -> None:
    """What the gateway does at a scan (hub/gateway/participant.py): the number put, published, begun."""
    image.put({"cycle": cycle})
    server.publish(image.take_changed())
    image.begin_scan(cycle)


def reader(protocol: str, tags, port: int, slot: str = "cycle") -> subprocess.Popen:
    tag = tags.by_slot[slot]
    code = textwrap.dedent(READ[protocol]).replace("PORT", str(port)).replace("ADDRESS", str(tag.address)) \
        .replace("BYTE", str(tag.s7_byte)).replace("ENDPOINT", f"opc.tcp://127.0.0.1:{port}/planthub") \
        .replace("NAMESPACE", namespace(tags.run)).replace("NODE", tag.node_id).replace("TAG", tag.name) \
        .replace("AREA", {"I": "PE", "Q": "PA", "M": "MK"}.get(tag.s7_area, ""))
    return subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def answer(client: subprocess.Popen) -> int:
    try:
        out, err = client.communicate(timeout=LIMIT)   # less than HOLD: a read answered by its hold's end fails here
    finally:
        if client.poll() is None:
            client.kill()
            client.communicate()
    assert client.returncode == 0, err[-2000:]
    return int(out.strip())


@pytest.fixture(scope="module")
def tags():
    return tag_map(load_scenario(BOTTLING), "control")


@pytest.mark.parametrize("protocol", ["modbus", "s7", "enip", "opcua"])
def test_a_poll_between_two_scans_is_answered_with_the_next_scan_once_it_begins(protocol, tags):
    image, port = ProcessImage(tags, hold=HOLD), free_port()
    image.holds = True   # lockstep
    with ServerThread(server_of(protocol, image, port), protocol) as server:
        scan(server, image, 1)
        image.write("cycle_done", 1)   # the PLC answered scan 1: the plant steps toward scan 2
        client = reader(protocol, tags, port)
        deadline = time.monotonic() + LIMIT
        while image.held == 0 and client.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert image.held == 1, f"the read of cycle was not held (the client ended with {client.poll()})"
        image.put({"r1_read": 7})
        server.publish(image.take_changed())
        assert answer(reader(protocol, tags, port, "r1_read")) == 7   # another client, answered meanwhile
        assert client.poll() is None and image.held == 1   # the first one still held
        scan(server, image, 2)
        assert answer(client) == 2   # asked before scan 2 began, answered with it


@pytest.mark.parametrize("protocol", ["modbus", "opcua"])
def test_in_live_mode_a_poll_is_answered_at_once(protocol, tags):
    image, port = ProcessImage(tags, hold=HOLD), free_port()   # image.holds stays False: live
    with ServerThread(server_of(protocol, image, port), protocol) as server:
        scan(server, image, 1)
        image.write("cycle_done", 1)
        assert answer(reader(protocol, tags, port)) == 1 and image.held == 0


def test_a_hold_ends_at_its_limit_and_at_the_end_of_the_run(tags):
    image = ProcessImage(tags, hold=0.05)
    image.holds = True
    image.hold()   # no scan yet: held for its limit, then answered
    assert image.held == 1
    image.hold_limit = HOLD
    waiting = threading.Thread(target=image.hold)
    waiting.start()
    deadline = time.monotonic() + LIMIT
    while image.held < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    image.release()   # the run ended
    waiting.join(LIMIT)   # less than HOLD: only release() ends it in time
    assert image.held == 2 and not waiting.is_alive()
