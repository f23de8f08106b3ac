"""planthub gateway s7: the tag map's S7 addresses and the TIA Portal tag table, every kind of bad
write refused with S7's own item return code and logged, nothing of it reaching the plant (a real
python-snap7 server, python-snap7's client in another process), a PLC writing its whole Q image over
the padding bytes taken, a second gateway on a taken port refused, and the bottling plant routed by an
S7 PLC client scanning every step, bit for bit the run of the routing participant."""
import csv
import json
import subprocess
import sys
import textwrap

import pytest

from hub.core.errors import PlanthubError
from hub.gateway.image import ProcessImage
from hub.gateway.s7 import S7Server
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import BOTTLING, bottling_via_gateway, free_port
from .helpers import ROOT, run_scenario
from .test_gateway import belt_scenario, overrides

DURATION = 36.0   # s: the first bottle has been read, routed and delivered (sink_A)


def test_the_bottling_plants_s7_tags_and_its_tia_portal_table(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "hub", "gateway", "s7", str(BOTTLING), "--object", "control",
                           "--export-tags", str(tmp_path / "tags.csv"), "--export-tia", str(tmp_path / "tia.csv")],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr
    with open(tmp_path / "tags.csv", newline="") as f:
        tags = {r["tag"]: r for r in csv.DictReader(f)}
    assert [tags[t]["s7_address"] for t in ("plc_ready", "cycle", "cycle_done", "r1_read", "r2_read",
                                            "r1_destination", "r2_destination", "sw1_work", "sw5_base")] == \
           ["M0.0", "MW2", "MW4", "IW0", "IW2", "DB1.DBB0", "DB1.DBB18", "Q0.0", "Q1.1"]
    assert (tags["r1_destination"]["s7_type"], tags["sw1_work"]["logix_type"]) == ("String[16]", "BOOL")
    with open(tmp_path / "tia.csv", newline="") as f:
        tia = {r["Name"]: r for r in csv.DictReader(f)}
    assert (tia["r1_read"]["Data Type"], tia["r1_read"]["Logical Address"], tia["r1_read"]["Hmi Writeable"]) == \
           ("Word", "%IW0", "False")
    assert (tia["sw1_work"]["Data Type"], tia["sw1_work"]["Logical Address"]) == ("Bool", "%Q0.0")
    assert "r1_destination" not in tia   # a tag table holds no data block


CLIENT = """
import snap7
from snap7.datatypes import S7Area, S7WordLen
from snap7.type import Area, WordLen
c = snap7.Client()
c.connect("127.0.0.1", 0, 1, PORT)
def attempt(write):
    try:
        write()
        return "ok"
    except Exception as exc:
        return str(exc)
def two_items():   # python-snap7's write_multi_vars sends one request per item: the request by hand
    one, two = (c.protocol.build_write_request(S7Area.PA, 0, at, S7WordLen.BYTE, data)
                for at, data in ((2, b"\\x36\\x00"), (0, b"\\x01\\x00")))
    params, data = bytes([0x05, 2]) + one[12:24] + two[12:24], one[24:] + two[24:]
    connection = c._get_connection()
    connection.send_data(one[:6] + len(params).to_bytes(2, "big") + len(data).to_bytes(2, "big") + params + data)
    return connection.receive_data()[10:12].hex()   # the answer's error class and code
label = lambda length, text: bytearray([16, length]) + text.ljust(16, b"\\0")
results = {
    "an input": attempt(lambda: c.write_area(Area.PE, 0, 0, bytearray([0]))),
    "half a word": attempt(lambda: c.write_area(Area.PA, 0, 2, bytearray([0]))),
    "beyond the raw range": attempt(lambda: c.write_area(Area.PA, 0, 2, bytearray([0x75, 0x30]))),
    "beyond the area": attempt(lambda: c.write_area(Area.PA, 0, 40, bytearray([1]))),
    "the scan number": attempt(lambda: c.write_area(Area.MK, 0, 2, bytearray([0, 9]))),
    "the padding alone": attempt(lambda: c.write_area(Area.PA, 0, 1, bytearray([0xFF]))),
    "a bit of a word": attempt(lambda: c.write_area(Area.PA, 0, 16, bytearray([1]), WordLen.Bit)),
    "a string too long": attempt(lambda: c.db_write(1, 18, label(17, b"x" * 16))),
    "a string not UTF-8": attempt(lambda: c.db_write(1, 18, label(2, b"\\xff\\xfe"))),
    "two items": two_items(),
    "a download": attempt(lambda: c.download(bytearray(16), 1)),
    "the whole Q image": attempt(lambda: c.write_area(Area.PA, 0, 0, bytearray([0, 0xFF, 0x1B, 0x00]))),
    "a good speed": attempt(lambda: c.write_area(Area.PA, 0, 2, bytearray([0x36, 0x00]))),
    "a good bit": attempt(lambda: c.write_area(Area.PA, 0, 0, bytearray([1]), WordLen.Bit)),
}
print(repr((results, bytes(c.read_area(Area.PE, 0, 0, 8)).hex(), bytes(c.db_read(1, 0, 6)).hex(),
            bytes(c.read_area(Area.PA, 0, 0, 4)).hex())))
c.disconnect()
"""


def test_bad_s7_writes_get_their_return_codes_and_nothing_reaches_the_plant(tmp_path, caplog):
    scenario = belt_scenario(tmp_path)   # with a string the PLC writes
    scenario.write_text(scenario.read_text().replace("outputs: {speed: real, run: bool}",
                                                     "outputs: {speed: real, run: bool, label: string}"))
    tags = tag_map(load_scenario(scenario), "plc", overrides(tmp_path, "tags:\n  speed: {scale: [0, 2]}\n"))
    assert [tags.by_slot[s].s7_address for s in ("occupied", "seen", "velocity", "run", "speed", "who", "label")] == \
           ["I0.0", "IW2", "ID4", "Q0.0", "QW2", "DB1.DBB0", "DB1.DBB18"]
    image, port = ProcessImage(tags), free_port()
    with ServerThread(S7Server(image, f"127.0.0.1:{port}"), "s7") as server:
        image.put({"who": "B001", "occupied": True, "seen": 3})
        server.publish(image.take_changed())
        proc = subprocess.run([sys.executable, "-c", textwrap.dedent(CLIENT).replace("PORT", str(port))],
                              capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr[-2000:]
    results, inputs, strings, outputs = eval(proc.stdout)
    assert results == {"an input": "Write operation failed: Accessing the object not allowed (0x03)",
                       "half a word": "Write operation failed: Data type inconsistent (0x07)",
                       "beyond the raw range": "Write operation failed: Data type inconsistent (0x07)",
                       "beyond the area": "Write operation failed: Invalid address (0x05)",
                       "the scan number": "Write operation failed: Accessing the object not allowed (0x03)",
                       "the padding alone": "Write operation failed: Invalid address (0x05)",
                       "a bit of a word": "Write operation failed: Invalid address (0x05)",
                       "a string too long": "Write operation failed: Data type inconsistent (0x07)",
                       "a string not UTF-8": "Write operation failed: Data type inconsistent (0x07)",
                       "two items": "8104", "a download": "S7 protocol error (class=0x81, code=0x04): This service "
                                                          "is not implemented on the module or a frame error was reported",
                       "the whole Q image": "ok", "a good speed": "ok", "a good bit": "ok"}
    assert image.outputs() == {"speed": 1.0, "run": True, "label": ""} and image.refused == 11
    assert inputs == "0100000300000000" and strings == "100442303031"   # I0.0, IW2 = 3; STRING[16] "B001"
    assert outputs == "01003600"   # the padding byte Q1 as the gateway keeps it: what was written there ignored
    logged = caplog.text
    assert "refused a write to speed at QW2 (S7): 0x07 data type inconsistent: raw 30000 is outside 0..27648" in logged
    assert "refused a write to speed at QW2 (S7): 0x07 data type inconsistent: Int takes 2 bytes, written only in part" \
           in logged
    assert "refused a write to occupied at I0.0 (S7): 0x03 object access not allowed: a PLC input is read-only" in logged
    assert "refused a write to Q bytes 40..40 (S7): 0x05 invalid address: no such area or beyond its end" in logged
    assert "refused a write to Q bytes 1..1 (S7): 0x05 invalid address: no tag there" in logged
    assert "refused a write to Q bytes 2..2 (S7): 0x05 invalid address: no tag there" in logged   # bit Q2.0 of QW2
    assert "refused a write to label at DB1.DBB18 (S7): 0x07 data type inconsistent: a string of 17 bytes in a " \
           "String[16]" in logged
    assert "refused a write to label at DB1.DBB18 (S7): 0x07 data type inconsistent: the string is not UTF-8" in logged
    assert "refused a write to 2 items in one request (S7): 0x8104 function not supported: a write of several " \
           "items; write each item on its own" in logged
    assert "refused a write to a block download (S7): 0x8104 function not supported: blocks are not downloaded " \
           "to a gateway" in logged


def test_a_second_s7_gateway_on_a_taken_port_is_refused_naming_the_endpoint(tmp_path):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc")
    port = free_port()
    with ServerThread(S7Server(ProcessImage(tags), f"127.0.0.1:{port}"), "s7 server"):
        with pytest.raises(PlanthubError) as second:
            with ServerThread(S7Server(ProcessImage(tags), f"127.0.0.1:{port}"), "s7 server"):
                pass
    assert str(second.value).startswith(f"the S7 server could not listen at 127.0.0.1:{port}: Address already in use")


@pytest.mark.slow
def test_an_s7_plc_routes_the_bottling_plant_bit_for_bit_as_the_participant(tmp_path):
    reference = tmp_path / "participant"
    run_scenario(BOTTLING, reference, {"run.duration": DURATION, "objects.control.runs": "hub"})
    (tmp_path / "s7").mkdir()
    out, said, summary = bottling_via_gateway(tmp_path / "s7", "s7", DURATION)
    scans, decisions = int(said.split()[1]), int(said.split()[3])
    assert scans == round(DURATION / 0.02) and decisions >= 1   # every step a scan, each answered
    assert (out / "recording.csv").read_bytes() == (reference / "recording.csv").read_bytes()
    assert (out / "events.csv").read_bytes() == (reference / "events.csv").read_bytes()
    assert summary["ended"]["kind"] != "failed"
    assert json.loads((reference / "summary.json").read_text())["ended"]["kind"] == summary["ended"]["kind"]
