"""planthub gateway enip: the tags as Logix controller tags read and written by name by pylogix in
another process (a real cpppo server), every kind of bad write refused with CIP's own status and
logged, nothing of it reaching the plant, strings in UTF-8 both ways; a taken port refused naming it; and the bottling plant routed by a Logix PLC client scanning
every 0.1 s (cpppo answers in ms of CPU per request: a scan at every step is what it cannot keep up with)."""
import logging
import socket
import subprocess
import sys
import textwrap

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
    statuses = {what: c.Write(name, value).Status for what, name, value in [
        ("an input", "occupied", False), ("out of range", "speed", 9.0), ("not finite", "speed", float("nan")),
        ("unknown", "sped", 1.0), ("the scan number", "cycle", 3), ("a good speed", "speed", 1.5),
        ("a good bit", "run", True), ("a string too long", "label", "x" * 17),
        ("a string not UTF-8", "label", "\\xff\\xfe"),   # pylogix sends an SSTRING's characters as bytes
        ("a good string", "label", "B\\u00e9".encode().decode("latin-1"))]}   # "Bé" in UTF-8
    print(repr((read, who, statuses)))
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
        proc = subprocess.run([sys.executable, "-c", textwrap.dedent(CLIENT).replace("PORT", str(port))],
                              capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr[-2000:]
    read, who, statuses = eval(proc.stdout)
    assert read == [("occupied", True, "Success"), ("seen", 3, "Success"), ("velocity", 0.0, "Success"),
                    ("cycle", 0, "Success")] and who == "B\u00e91"   # in UTF-8, as pylogix reads it
    assert statuses == {"an input": "Privilege violation", "out of range": "Invalid Attribute",
                        "not finite": "Invalid Attribute", "unknown": "Path destination unknown",
                        "the scan number": "Privilege violation", "a good speed": "Success", "a good bit": "Success",
                        "a string too long": "Invalid Attribute", "a string not UTF-8": "Invalid Attribute",
                        "a good string": "Success"}
    assert image.outputs() == {"speed": 1.5, "run": True, "label": "B\u00e9"} and image.refused == 7
    logged = caplog.text
    assert "refused a write to speed (EtherNet/IP): 0x09 invalid attribute value: 9.0 is outside 0..2" in logged
    assert "refused a write to occupied (EtherNet/IP): 0x0F privilege violation: a PLC input is read-only" in logged
    assert "refused a write to sped (EtherNet/IP): 0x05 path destination unknown: no such tag" in logged
    assert "refused a write to label (EtherNet/IP): 0x09 invalid attribute value: 17 bytes is longer than 16" in logged
    assert "refused a write to label (EtherNet/IP): 0x09 invalid attribute value: 'utf-8' codec can't decode" in logged
    assert logging.getLogger("enip.lgx").propagate   # as it was before the server: restored by its stop


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
