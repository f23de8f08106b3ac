"""A PLC's poll of `cycle` in lockstep, over each protocol: made while the plant steps toward its next
scan (the PLC answered the last), it is held by the gateway and answered with the next scan's
values as soon as that scan begins, while the server goes on answering other clients; in live mode
it is answered at once. The hold has a limit and ends with the run. The gateway participant is
stepped as a run steps it (Participant.advance → Gateway.step), a real server in this process,
real clients of the protocol in other processes."""
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from hub.core.slots import SlotType
from hub.gateway.enip import TYPES as LOGIX
from hub.gateway.image import ProcessImage
from hub.gateway.participant import LIVE, LOCKSTEP, Gateway
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import namespace, tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import BOTTLING, free_port
from .helpers import ROOT

LIMIT = 60.0  # s for anything the test waits on
HOLD = 2 * LIMIT   # s: a hold that is not ended by its scan outlasts every wait of the test
STEP = 0.02   # s of plant time a step
PAUSE = 0.2   # s the plant's thread stays in a scan's beginning: a read it lets go on is answered meanwhile

READ = {   # a client printing the values of the tags P names, read in one request (P is set before it)
    "modbus": """
        from pymodbus.client import ModbusTcpClient
        c = ModbusTcpClient("127.0.0.1", port=P["port"], timeout=60, retries=0)
        assert c.connect()
        first = min(P["addresses"])
        words = c.read_input_registers(first, count=max(P["addresses"]) - first + 1).registers
        print(*[words[a - first] for a in P["addresses"]])""",
    "s7": """
        import struct, snap7
        from snap7.type import Area
        (area, byte), = P["s7"]   # one item: S7 holds no other
        c = snap7.Client()
        c.connect("127.0.0.1", 0, 1, P["port"])
        print(struct.unpack(">H", c.read_area(getattr(Area, area), 0, byte, 2))[0])""",
    "enip": """
        from pylogix import PLC
        with PLC("127.0.0.1") as c:
            c.Port, c.SocketTimeout = P["port"], 60
            known = [(name, 1, kind) for name, kind in zip(P["names"], P["types"])]   # no single reads to learn them
            print(*[r.Value for r in (c.Read(known) if len(known) > 1 else [c.Read(*known[0])])])""",
    "opcua": """
        import asyncio
        from asyncua import Client, ua
        async def main():
            async with Client(P["endpoint"], timeout=60) as c:
                ns = await c.get_namespace_index(P["namespace"])
                print(*await c.read_values([c.get_node(ua.NodeId(node, ns)) for node in P["nodes"]]))
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


class Plant:
    """The gateway participant stepped as a run steps it (Participant.advance, which calls Gateway.step),
    in a thread of its own: at a scan the step waits until the PLC answers. A listener of the image
    (after the server's) keeps the plant's thread PAUSE s in each scan's beginning, as if preempted
    there: a step that began a scan before its values were put and published would have a held read
    answered with the scan before's."""

    def __init__(self, gateway: Gateway):
        self.gateway, self.image = gateway, gateway.image
        self.image.listen(lambda: time.sleep(PAUSE))
        self.inputs, _ = gateway.interface()
        gateway.begin({}, 0.0)
        self.thread = ThreadPoolExecutor(1)
        self.t = 0.0

    def step(self, **inputs):
        """A step with these inputs (an event: True), the others at rest; its future."""
        values = [inputs.get(name, False if kind is SlotType.VOID else kind.initial()) for name, kind in self.inputs]
        future = self.thread.submit(self.gateway.advance, self.t, STEP, values)
        self.t += STEP
        return future

    def answer(self, cycle: int) -> None:
        """The PLC answers scan `cycle` once it began (cycle_done written, as the server would)."""
        until(lambda: self.image.at_scan == cycle, f"scan {cycle} did not begin")
        self.image.write("cycle_done", cycle)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.image.write("cycle_done", self.gateway.cycle)   # a step left waiting (a failed test) ends
        self.thread.shutdown()


def until(condition, failed: str) -> None:
    deadline = time.monotonic() + LIMIT
    while not condition():
        assert time.monotonic() < deadline, failed
        time.sleep(0.01)


def reader(protocol: str, tags, port: int, *slots: str) -> subprocess.Popen:
    """A client process reading these tags (`cycle` if none) in one request."""
    chosen = [tags.by_slot[slot] for slot in slots or ("cycle",)]
    params = {"port": port, "addresses": [t.address for t in chosen], "names": [t.name for t in chosen],
              "types": [LOGIX[t.logix_type] for t in chosen],
              "s7": [({"I": "PE", "Q": "PA", "M": "MK"}[t.s7_area], t.s7_byte) for t in chosen],
              "endpoint": f"opc.tcp://127.0.0.1:{port}/planthub", "namespace": namespace(tags.run),
              "nodes": [t.node_id for t in chosen]}
    code = f"P = {params!r}\n" + textwrap.dedent(READ[protocol])
    return subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def answer(client: subprocess.Popen) -> list[int]:
    try:
        out, err = client.communicate(timeout=LIMIT)   # less than HOLD: a read answered by its hold's end fails here
    finally:
        if client.poll() is None:
            client.kill()
            client.communicate()
    assert client.returncode == 0, err[-2000:]
    return [int(v) for v in out.split()]


def until_held(image: ProcessImage, client: subprocess.Popen, count: int = 1) -> None:
    until(lambda: image.held_reads >= count or client.poll() is not None, "the read of cycle was not held")
    assert image.held_reads == count, f"the read of cycle was not held (the client ended with {client.poll()})"


@pytest.fixture(scope="module")
def tags():
    return tag_map(load_scenario(BOTTLING), "control")


@pytest.mark.parametrize("protocol", ["modbus", "s7", "enip", "opcua"])
def test_a_poll_between_two_scans_is_answered_with_the_next_scan_once_it_begins(protocol, tags):
    image, port = ProcessImage(tags, lockstep=True, hold=HOLD), free_port()
    with ServerThread(server_of(protocol, image, port), protocol) as server, \
            Plant(Gateway(tags, server, plc_timeout=LIMIT)) as plant:
        first = plant.step(r1_read=True)   # scan 1: a bottle at reader 1
        plant.answer(1)
        first.result(LIMIT)   # the plant steps toward scan 2
        client = reader(protocol, tags, port)
        until_held(image, client)
        assert answer(reader(protocol, tags, port, "r1_read")) == [1]   # another client, answered meanwhile
        assert client.poll() is None and image.held_reads == 1   # the first one still held
        second = plant.step()   # scan 2
        assert answer(client) == [2]   # asked before scan 2 began, answered with it
        plant.answer(2)
        second.result(LIMIT)


@pytest.mark.parametrize("protocol", ["modbus", "enip", "opcua"])   # S7 holds a read of one item only
def test_a_held_poll_of_cycle_and_an_input_is_answered_with_the_next_scans_value_of_both(protocol, tags):
    image, port = ProcessImage(tags, lockstep=True, hold=HOLD), free_port()
    with ServerThread(server_of(protocol, image, port), protocol) as server, \
            Plant(Gateway(tags, server, plc_timeout=LIMIT)) as plant:
        first = plant.step()   # scan 1: no bottle yet
        plant.answer(1)
        first.result(LIMIT)
        client = reader(protocol, tags, port, "cycle", "r1_read")   # one request for both
        until_held(image, client)
        second = plant.step(r1_read=True)   # scan 2: a bottle at reader 1
        assert answer(client) == [2, 1]
        plant.answer(2)
        second.result(LIMIT)


@pytest.mark.parametrize("protocol", ["modbus", "opcua"])
def test_in_live_mode_a_poll_is_answered_at_once(protocol, tags):
    image, port = ProcessImage(tags, hold=HOLD), free_port()   # not lockstep: live
    with ServerThread(server_of(protocol, image, port), protocol) as server, \
            Plant(Gateway(tags, server, mode=LIVE)) as plant:
        plant.step(r1_read=True).result(LIMIT)   # no scan: the plant does not wait for the PLC
        assert answer(reader(protocol, tags, port, "cycle", "r1_read")) == [0, 1] and image.held_reads == 0


def test_an_opcua_wake_run_after_its_scan_was_answered_leaves_a_held_poll_for_the_next(tags):
    image, port = ProcessImage(tags, lockstep=True, hold=HOLD), free_port()
    with ServerThread(server_of("opcua", image, port), "opcua") as server, \
            Plant(Gateway(tags, server, plc_timeout=LIMIT)) as plant:
        first = plant.step()
        plant.answer(1)
        first.result(LIMIT)   # the plant steps toward scan 2
        client = reader("opcua", tags, port)
        until_held(image, client)

        async def late_wake():   # scan 1's wake, run by the loop only now (and then at once the count of the held)
            server.protocol._go_on()
            return len(server.protocol.waiting)

        assert server.call(late_wake()) == 1 and client.poll() is None
        second = plant.step()
        assert answer(client) == [2]
        plant.answer(2)
        second.result(LIMIT)


@pytest.mark.parametrize("protocol", ["modbus", "s7", "enip", "opcua"])
def test_a_poll_held_when_the_run_ends_is_answered_then(protocol, tags):
    image, port = ProcessImage(tags, lockstep=True, hold=HOLD), free_port()
    with ServerThread(server_of(protocol, image, port), protocol) as server, \
            Plant(Gateway(tags, server, plc_timeout=LIMIT)) as plant:
        first = plant.step()
        plant.answer(1)
        first.result(LIMIT)
        client = reader(protocol, tags, port)
        until_held(image, client)
        image.release()   # the run ended (hub/cli/gateway.py)
        assert answer(client) == [1]   # within LIMIT, less than HOLD: only the release ends it in time


def test_a_hold_ends_at_its_limit(tags):
    image = ProcessImage(tags, lockstep=True, hold=0.05)
    image.hold()   # no scan yet: held for its limit, then answered
    assert image.held_reads == 1


@pytest.mark.parametrize("mode, lockstep, image", [(LIVE, True, "holds"), (LOCKSTEP, False, "never holds")])
def test_a_gateway_on_an_image_of_the_other_mode_is_refused_saying_which_image_it_needs(tags, mode, lockstep, image):
    server = ServerThread(server_of("modbus", ProcessImage(tags, lockstep=lockstep), free_port()), "modbus")   # not started
    try:
        with pytest.raises(ValueError) as refused:
            Gateway(tags, server, mode=mode)
    finally:
        server.loop.close()
    assert str(refused.value) == (f"a {mode} gateway on a process image that {image} reads of cycle: "
                                  f"ProcessImage(tags, lockstep={not lockstep})")
