"""planthub gateway: the tag map generated from a scenario and its overrides (each bad override
named at its file and line), the table for a PLC's tag editor, every kind of bad write refused with
the protocol's own error code and nothing of it reaching the plant (a real asyncua or pymodbus
server, a real client of the same library), OPC UA's user and password, a PLC that stops answering
ending the run with the reason, and live mode driving a belt paced to the wall clock."""
import asyncio
import csv
import json
import math
import subprocess
import sys
import textwrap

import pytest
from asyncua import Client, ua
from pymodbus.client import AsyncModbusTcpClient

from hub.core.errors import PlanthubError
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import export_tags, free_port
from .helpers import ROOT, planthub

BELT = """\
planthub: 1
name: belt_plc
description: A belt whose speed a PLC sets, a light barrier the PLC sees.
run: {duration: DURATION, physics_rate: 150, communication_step: 0.02}
objects:
  belt: {module: conveyor, position: [0, 0, 0], length: 2.5, speed: 0.0, k: 16}
  bottle: {module: bottle, position: [0.04, 0, 0]}
  barrier: {module: light_barrier, position: [1.0, 0, 0.05]}
  plc:
    module: participant
    inputs: {seen: void, occupied: bool, who: string, velocity: real}
    outputs: {speed: real, run: bool}
    PLC_LAUNCH
flows:
  - {from: barrier.trigger.on_enter, to: plc.logic.seen}
  - {from: barrier.trigger.occupied, to: plc.logic.occupied}
  - {from: barrier.trigger.object, to: plc.logic.who}
  - {from: belt.drive.velocity, to: plc.logic.velocity}
  - {from: plc.logic.speed, to: belt.drive.speed}
  - {from: plc.logic.run, to: belt.drive.run}
record: [belt.drive.velocity, bottle.body.position]
"""


def belt_scenario(tmp_path, duration=2.0, launch=None, name="belt_plc.yaml"):
    text = BELT.replace("DURATION", str(duration))
    text = text.replace("PLC_LAUNCH", f"python: {json.dumps(launch)}" if launch else "join_timeout: 5")
    path = tmp_path / name
    path.write_text(text)
    return path


def overrides(tmp_path, body: str):
    path = tmp_path / "tags.yaml"
    path.write_text(textwrap.dedent(body))
    return path


# ---- the tag map ----------------------------------------------------------------------------

def test_the_bottling_plants_tag_table_has_every_reader_and_switch_with_its_addresses(tmp_path):
    export_tags(ROOT / "scenarios" / "bottling_plant.yaml", "control", tmp_path / "tags.csv")
    with open(tmp_path / "tags.csv", newline="") as f:
        rows = {r["tag"]: r for r in csv.DictReader(f)}
    assert list(rows)[:3] == ["cycle", "cycle_done", "plc_ready"]
    r1, dest, sw = rows["r1_read"], rows["r1_destination"], rows["sw1_work"]
    assert (r1["direction"], r1["plant"], r1["opcua_type"], r1["modbus_table"]) == \
           ("input", "r1.trigger.on_enter", "UInt32", "input_register")
    assert r1["opcua_node"] == "nsu=urn:planthub:bottling_plant;s=r1.r1_read"
    assert (dest["modbus_table"], dest["modbus_count"], dest["opcua_type"]) == ("input_register", "8", "String")
    assert (sw["direction"], sw["plant"], sw["modbus_table"], sw["opcua_type"]) == \
           ("output", "sw1.logic.MoveToWorkingPos_put", "coil", "Boolean")
    for table in ("input_register", "coil"):   # no two tags share an address
        spans = [set(range(int(r["modbus_address"]), int(r["modbus_address"]) + int(r["modbus_count"])))
                 for r in rows.values() if r["modbus_table"] == table]
        assert sum(map(len, spans)) == len(set().union(*spans))


def test_overrides_set_names_addresses_scaling_and_units(tmp_path):
    scenario = load_scenario(belt_scenario(tmp_path))
    tags = tag_map(scenario, "plc", overrides(tmp_path, """\
        tags:
          speed: {name: belt_speed, scale: [0, 2], units: m/s, address: 40}
          who: {length: 4}
        """))
    speed = tags.by_slot["speed"]
    assert (speed.name, speed.address, speed.count, speed.units, speed.scale) == ("belt_speed", 40, 1, "m/s", (0, 2))
    assert speed.encoding == "raw 0..27648 = 0..2" and tags.by_slot["who"].count == 4
    assert "belt_speed,output,speed,belt.drive.speed" in tags.csv()


@pytest.mark.parametrize("body, message", [
    ("tags:\n  sped: {units: m/s}\n", "tags.yaml:2: tags.sped: no slot 'sped' on the gateway (did you mean 'speed'?)"),
    ("tags:\n  run: {scale: [0, 1]}\n", "tags.yaml:2: tags.run.scale: only a real slot takes `scale`; 'run' is bool"),
    ("tags:\n  speed: {scale: [2, 0]}\n", "tags.yaml:2: tags.speed.scale: [2, 0]: the low end must be below the high end"),
    ("tags:\n  speed: {colour: red}\n", "tags.yaml:2: tags.speed: Additional properties are not allowed ('colour' was unexpected)"),
    ("tags:\n  velocity: {address: 1}\n  who: {address: 2}\n", "tags.yaml:2: tags.velocity.address: input_register 1..2 overlaps who"),
    ("tags:\n  speed: {name: run}\n", "tags.yaml:2: tags.speed.name: 'run' is already the name of 'run'"),
])
def test_a_bad_override_is_named_at_its_line(tmp_path, body, message):
    scenario = load_scenario(belt_scenario(tmp_path))
    with pytest.raises(PlanthubError) as caught:
        tag_map(scenario, "plc", overrides(tmp_path, body))
    assert message in str(caught.value)


def test_an_object_that_is_no_participant_or_a_vector_slot_is_refused(tmp_path):
    scenario = load_scenario(belt_scenario(tmp_path))
    with pytest.raises(PlanthubError, match=r"a conveyor, not a participant: 'belt' \(its participant objects: plc\)"):
        tag_map(scenario, "belt", None)
    with pytest.raises(PlanthubError, match=r"no object 'plcc' \(did you mean 'plc'\?\)"):
        tag_map(scenario, "plcc", None)
    path = belt_scenario(tmp_path)
    path.write_text(path.read_text().replace("outputs: {speed: real, run: bool}",
                                             "outputs: {speed: real, run: bool, where: vec3}"))
    with pytest.raises(PlanthubError, match=r"objects.plc.outputs.where: a vec3 has no PLC data type"):
        tag_map(load_scenario(path), "plc", None)


def test_the_command_line_refuses_a_scan_off_the_step_and_a_plc_timeout_beyond_the_lease(tmp_path, capsys):
    path = belt_scenario(tmp_path)
    code, _, err = planthub(capsys, "gateway", "opcua", path, "--object", "plc", "--scan", "0.03")
    assert code == 2 and "--scan 0.03: a whole number of the run's communication step (0.02 s)" in err
    code, _, err = planthub(capsys, "gateway", "modbus", path, "--object", "plc", "--plc-timeout", "2")
    assert code == 2 and "--plc-timeout 2: above 0 and below the lease (--lease 1 s)" in err


# ---- bad writes -----------------------------------------------------------------------------

@pytest.fixture
def served(tmp_path, request):
    """A real server of `request.param` for the belt's tags (speed scaled 0..2 m/s); (image, endpoint)."""
    protocol = request.param
    scenario = load_scenario(belt_scenario(tmp_path))
    tags = tag_map(scenario, "plc", overrides(tmp_path, "tags:\n  speed: {scale: [0, 2]}\n"))
    image = ProcessImage(tags)
    port = free_port()
    if protocol == "opcua":
        from hub.gateway.opcua import OpcUaServer
        endpoint = f"opc.tcp://127.0.0.1:{port}/planthub"
        server = OpcUaServer(image, endpoint)
    else:
        from hub.gateway.modbus import ModbusServer
        endpoint = f"127.0.0.1:{port}"
        server = ModbusServer(image, endpoint)
    with ServerThread(server, protocol) as thread:
        thread.publish({"who": "B001", "occupied": True})
        image.put({"who": "B001", "occupied": True})
        yield image, endpoint


@pytest.mark.parametrize("served", ["opcua"], indirect=True)
def test_bad_opc_ua_writes_get_their_status_codes_and_nothing_reaches_the_plant(served, caplog):
    image, endpoint = served

    async def client_side():
        async with Client(endpoint, timeout=5) as client:
            ns = await client.get_namespace_index("urn:planthub:belt_plc")
            node = lambda name: client.get_node(ua.NodeId(name, ns))
            results = {}
            for what, name, variant in [
                    ("read-only", "barrier.occupied", ua.Variant(False, ua.VariantType.Boolean)),
                    ("wrong type", "belt.run", ua.Variant(1, ua.VariantType.Int32)),
                    ("out of range", "belt.speed", ua.Variant(9.0, ua.VariantType.Double)),
                    ("not finite", "belt.speed", ua.Variant(math.nan, ua.VariantType.Double)),
                    ("unknown", "belt.sped", ua.Variant(1.0, ua.VariantType.Double))]:
                try:
                    await node(name).write_value(variant)
                    results[what] = "Good"
                except ua.UaStatusCodeError as exc:
                    results[what] = exc.code
            await node("belt.speed").write_value(ua.Variant(1.5, ua.VariantType.Double))   # a good one
            description = (await node("belt.speed").read_description()).Text
            return results, description

    results, description = asyncio.run(client_side())
    assert results == {"read-only": ua.StatusCodes.BadUserAccessDenied, "wrong type": ua.StatusCodes.BadTypeMismatch,
                       "out of range": ua.StatusCodes.BadOutOfRange, "not finite": ua.StatusCodes.BadOutOfRange,
                       "unknown": ua.StatusCodes.BadNodeIdUnknown}
    assert image.outputs() == {"speed": 1.5, "run": False}   # only the good write
    assert image.read("occupied") is True and image.refused == 5
    logged = caplog.text
    assert "refused a write to belt.speed (OPC UA): BadOutOfRange: 9.0 is outside 0..2" in logged
    assert "refused a write to belt.run (OPC UA): BadTypeMismatch: Int32, the tag is Boolean" in logged
    assert "refused a write to barrier.occupied (OPC UA): BadUserAccessDenied" in logged
    assert description == "to belt.drive.speed"


@pytest.mark.parametrize("served", ["modbus"], indirect=True)
def test_bad_modbus_writes_get_their_exception_codes_and_nothing_reaches_the_plant(served, caplog):
    image, endpoint = served
    tags = image.tags.by_slot
    host, port = endpoint.split(":")

    async def client_side():
        client = AsyncModbusTcpClient(host, port=int(port), timeout=5, retries=0)
        assert await client.connect()
        try:
            codes = {
                "no tag there (coil)": await client.write_coil(50, True),
                "no tag there (register)": await client.write_register(500, 1),
                "beyond the raw range": await client.write_register(tags["speed"].address, 30000),
                "a read-only table": await client.write_register(tags["velocity"].address, 1),
            }
            codes = {what: r.exception_code if r.isError() else 0 for what, r in codes.items()}
            good = await client.write_register(tags["speed"].address, 13824)            # 1.0 m/s
            words = (await client.read_input_registers(tags["who"].address, count=tags["who"].count)).registers
            occupied = (await client.read_discrete_inputs(tags["occupied"].address, count=1)).bits[0]
            return codes, good.isError(), words, occupied
        finally:
            client.close()

    codes, bad_good, words, occupied = asyncio.run(client_side())
    # the velocity is an input register: a holding register of that number holds another tag or none
    assert codes["no tag there (coil)"] == codes["no tag there (register)"] == 2    # ILLEGAL_ADDRESS
    assert codes["beyond the raw range"] == 3                                       # ILLEGAL_VALUE
    assert codes["a read-only table"] in (2, 3) or tags["velocity"].address == tags["speed"].address
    assert not bad_good and image.outputs()["speed"] == 1.0
    assert words[:2] == [0x4230, 0x3031] and occupied is True   # "B001", the sensor seen
    assert "refused a write to speed at holding_register 1 (Modbus): ILLEGAL_VALUE: raw 30000 is outside 0..27648" \
           in caplog.text


@pytest.mark.parametrize("served", ["modbus"], indirect=True)
def test_a_modbus_value_of_two_registers_written_in_part_or_a_string_not_utf8_is_refused(served, tmp_path):
    image, endpoint = served
    host, port = endpoint.split(":")
    # A holding-register string and an Int32 on a second gateway of the same server kind: the belt's
    # outputs have neither, so they are added to it here.
    path = tmp_path / "belt_plc.yaml"
    path.write_text(path.read_text().replace("outputs: {speed: real, run: bool}",
                                             "outputs: {speed: real, run: bool, label: string, batch: int}"))
    from hub.gateway.modbus import ModbusServer
    tags = tag_map(load_scenario(path), "plc", None)
    image2, port2 = ProcessImage(tags), free_port()
    with ServerThread(ModbusServer(image2, f"127.0.0.1:{port2}"), "modbus"):
        async def client_side():
            client = AsyncModbusTcpClient(host, port=port2, timeout=5, retries=0)
            assert await client.connect()
            try:
                half = await client.write_register(tags.by_slot["batch"].address, 7)
                label = tags.by_slot["label"]
                bad_text = await client.write_registers(label.address, [0xFFFE] + [0] * (label.count - 1))
                whole = await client.write_registers(tags.by_slot["batch"].address, [0, 42])
                return half.exception_code, bad_text.exception_code, whole.isError()
            finally:
                client.close()
        half, bad_text, whole_failed = asyncio.run(client_side())
    assert (half, bad_text, whole_failed) == (3, 3, False)
    assert image2.outputs()["batch"] == 42 and image2.outputs()["label"] == ""


# ---- security, a PLC that stops answering, live mode ----------------------------------------

def test_an_opc_ua_gateway_with_a_user_refuses_anyone_else(tmp_path):
    from hub.gateway.opcua import OpcUaServer
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc", None)
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"

    async def connect(user=None, password=None):
        client = Client(endpoint, timeout=5)
        if user:
            client.set_user(user)
            client.set_password(password)
        try:
            await client.connect()
        except Exception as exc:
            return type(exc).__name__
        await client.disconnect()
        return "connected"

    with ServerThread(OpcUaServer(ProcessImage(tags), endpoint, ("operator", "s3cret")), "opcua"):
        assert asyncio.run(connect("operator", "s3cret")) == "connected"
        assert asyncio.run(connect("operator", "wrong")) != "connected"
        assert asyncio.run(connect()) != "connected"


def test_a_plc_that_stops_answering_ends_the_run_naming_the_scan(tmp_path):
    port = free_port()
    endpoint = f"127.0.0.1:{port}"
    path = belt_scenario(tmp_path, launch=["hub", "gateway", "modbus", "belt_plc.yaml", "--object", "plc",
                                           "--endpoint", endpoint])
    silent = ("import asyncio, sys, time\n"
              "from pymodbus.client import AsyncModbusTcpClient\n"
              "async def main():\n"
              "    c = AsyncModbusTcpClient('127.0.0.1', port=%d, timeout=2, retries=0)\n"
              "    deadline = time.monotonic() + 60\n"
              "    while not await c.connect() and time.monotonic() < deadline:\n"
              "        await asyncio.sleep(0.1)\n"
              "    await c.write_coil(0, True)\n"      # plc_ready, and never a scan answered
              "    c.close()\n"
              "asyncio.run(main())\n") % port
    client = subprocess.Popen([sys.executable, "-c", silent], cwd=ROOT)
    try:
        proc = subprocess.run([sys.executable, "-m", "hub", "run", str(path), "--out", str(tmp_path / "run")],
                              capture_output=True, text=True, cwd=ROOT, timeout=120)
    finally:
        client.wait(timeout=60)
    said = proc.stdout + proc.stderr
    assert proc.returncode == 1 and "Traceback" not in said   # a named stop, not a crash
    assert "the PLC did not answer scan 1 (t = 0 s) within 0.5 s" in said
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["ended"]["kind"] == "failed" and "the PLC did not answer scan 1" in summary["ended"]["reason"]


def test_live_mode_a_plc_sets_the_belt_running_against_the_wall_clock(tmp_path):
    port = free_port()
    endpoint = f"opc.tcp://127.0.0.1:{port}/planthub"
    path = belt_scenario(tmp_path, duration=3.0, launch=["hub", "gateway", "opcua", "belt_plc.yaml", "--object", "plc",
                                                         "--endpoint", endpoint, "--sync", "live"])
    writer = ("import asyncio, time\n"
              "from asyncua import Client, ua\n"
              "async def main():\n"
              "    deadline = time.monotonic() + 60\n"
              "    while True:\n"
              "        try:\n"
              "            c = Client('%s', timeout=5); await c.connect(); break\n"
              "        except Exception:\n"
              "            assert time.monotonic() < deadline; await asyncio.sleep(0.1)\n"
              "    ns = await c.get_namespace_index('urn:planthub:belt_plc')\n"
              "    await c.get_node(ua.NodeId('belt.speed', ns)).write_value(ua.Variant(0.5, ua.VariantType.Double))\n"
              "    await c.get_node(ua.NodeId('belt.run', ns)).write_value(ua.Variant(True, ua.VariantType.Boolean))\n"
              "    await c.disconnect()\n"
              "asyncio.run(main())\n") % endpoint
    client = subprocess.Popen([sys.executable, "-c", writer], cwd=ROOT)
    try:
        proc = subprocess.run([sys.executable, "-m", "hub", "run", str(path), "--realtime", "--out", str(tmp_path / "run")],
                              capture_output=True, text=True, cwd=ROOT, timeout=120)
    finally:
        client.wait(timeout=60)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert client.returncode == 0
    with open(tmp_path / "run" / "recording.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[0]["belt.drive.velocity"]) == 0.0
    assert float(rows[-1]["belt.drive.velocity"]) == pytest.approx(0.5)   # the PLC's set-point, taken live


def test_an_opc_ua_client_subscribes_to_a_sensor_with_its_own_sampling_interval(tmp_path):
    from hub.gateway.opcua import OpcUaServer
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc", None)
    image = ProcessImage(tags)
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"

    class Seen:
        def __init__(self):
            self.values = asyncio.Queue()

        def datachange_notification(self, node, value, data):
            self.values.put_nowait(value)

    with ServerThread(OpcUaServer(image, endpoint), "opcua") as thread:
        async def client_side():
            async with Client(endpoint, timeout=5) as client:
                ns = await client.get_namespace_index("urn:planthub:belt_plc")
                seen = Seen()
                subscription = await client.create_subscription(20, seen)
                await subscription.subscribe_data_change(client.get_node(ua.NodeId("barrier.who", ns)),
                                                         sampling_interval=10)
                first = await asyncio.wait_for(seen.values.get(), 5)      # the value it has now
                image.put({"who": "M007"})
                await asyncio.to_thread(thread.publish, image.take_changed())
                second = await asyncio.wait_for(seen.values.get(), 5)
                return first, second, subscription.parameters.RequestedPublishingInterval

        first, second, interval = asyncio.run(client_side())
    assert (first, second, interval) == ("", "M007", 20)
