"""What a gateway tells when its PLC is missing or silent: a PLC that never sets plc_ready ends the
gateway's wait inside the hub's join wait, and the run's error names plc_ready and the endpoint;
what the launched gateway said is on the hub's console and in the run folder; the OPC UA browse
names are in the plant's namespace, so a client's get_child finds them; a malformed join deadline and
a --ready-timeout longer than the hub's join wait are named; what a lost gateway said is kept and shown
before it is relaunched."""
import argparse
import asyncio
import logging
import os
import signal
import subprocess
import sys
import time

from asyncua import Client

from hub.bus.lockstep import pid_of
from hub.cli.gateway import _ready_timeout
from hub.gateway.image import ProcessImage
from hub.gateway.opcua import OpcUaServer
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import tag_map
from hub.scenario.checker import load_scenario

from .bus_support import hub
from .gateway_support import BOTTLING, free_port, run_beside_client
from .helpers import ROOT
from .test_gateway import belt_scenario


def test_a_plc_that_never_sets_plc_ready_is_named_with_the_endpoint_before_the_hub_gives_up(tmp_path):
    endpoint = f"127.0.0.1:{free_port()}"
    path = belt_scenario(tmp_path, launch=["hub", "gateway", "s7", "belt_plc.yaml", "--object", "plc",
                                           "--endpoint", endpoint])
    path.write_text(path.read_text().replace("    python:", "    join_timeout: 6\n    python:"))
    proc = subprocess.run([sys.executable, "-m", "hub", "run", str(path), "--out", str(tmp_path / "run")],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)
    said = proc.stdout + proc.stderr
    assert proc.returncode == 1 and "Traceback" not in said
    assert "participant 'plc': its process exited with code 1 before it could join" in said
    assert ("no PLC set plc_ready within" in said and
            f"(plc_ready is M0.0 of the s7 server at {endpoint}); the PLC sets it once it runs" in said)
    assert "no PLC set plc_ready" in (tmp_path / "run" / "plc.log").read_text()   # kept in the run folder


WRITER = ("import snap7, time\n"   # an S7 client writing to a PLC input once: the gateway refuses and logs it
          "from snap7.type import Area\n"
          "c = snap7.Client(); deadline = time.monotonic() + 60\n"
          "while True:\n"
          "    try:\n"
          "        c.connect('127.0.0.1', 0, 1, %d); break\n"
          "    except Exception:\n"
          "        assert time.monotonic() < deadline; time.sleep(0.1)\n"
          "try:\n"
          "    c.write_area(Area.PE, 0, 0, bytearray([1]))\n"
          "except Exception:\n"
          "    pass\n"
          "c.disconnect()\n")
REFUSAL = "refused a write to occupied at I0.0 (S7): 0x03 object access not allowed: a PLC input is read-only"


def test_the_launched_gateways_refusals_reach_the_hub_console_and_the_run_folder(tmp_path):
    port = free_port()
    path = belt_scenario(tmp_path, launch=["hub", "gateway", "s7", "belt_plc.yaml", "--object", "plc",
                                           "--endpoint", f"127.0.0.1:{port}", "--sync", "live"])
    proc, _ = run_beside_client(path, tmp_path / "run", WRITER % port)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert REFUSAL in proc.stderr and "participant 'plc' said (all" in proc.stderr
    assert REFUSAL in (tmp_path / "run" / "plc.log").read_text()


def test_what_a_lost_gateway_said_is_kept_and_shown_before_its_relaunch(tmp_path, caplog):
    caplog.set_level(logging.INFO, "hub.bus.lockstep")
    port = free_port()
    path = belt_scenario(tmp_path, launch=["hub", "gateway", "s7", "belt_plc.yaml", "--object", "plc",
                                           "--endpoint", f"127.0.0.1:{port}", "--sync", "live"])
    with hub(path, tmp_path / "run", {"run.bus": {"on_loss": "pause"}}) as master:
        master.run(until_tick=30)
        subprocess.run([sys.executable, "-c", WRITER % port], cwd=ROOT, timeout=60, check=True)
        gateway = next(c.slave for c in master.plant.components if c.obj == "plc")
        os.kill(pid_of(gateway), signal.SIGKILL)   # after it logged the refusal: the output that says why
        master.run()
    kept = tmp_path / "run" / "plc.lost1.log"
    assert REFUSAL in kept.read_text()
    assert "participant 'plc' said (all " in caplog.text and f" in {kept}):" in caplog.text
    last = tmp_path / "run" / "plc.log"   # the relaunched one's own, if it said anything
    assert not last.exists() or REFUSAL not in last.read_text()


def test_a_malformed_join_deadline_is_named_without_a_traceback():
    proc = subprocess.run([sys.executable, "-m", "hub", "gateway", "s7", str(BOTTLING), "--object", "control",
                           "--endpoint", f"127.0.0.1:{free_port()}"], capture_output=True, text=True, cwd=ROOT,
                          timeout=60, env={**os.environ, "PLANTHUB_JOIN_DEADLINE": "soon"})
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert ("the environment's PLANTHUB_JOIN_DEADLINE='soon' is not a time (seconds since the epoch, as the hub "
            "that launches a gateway sets it)") in proc.stderr


def test_a_ready_timeout_longer_than_the_hubs_join_wait_is_warned_of(monkeypatch, caplog):
    args = argparse.Namespace(object="plc", sync="lockstep", ready_timeout=30.0)
    monkeypatch.setenv("PLANTHUB_JOIN_DEADLINE", repr(time.time() + 60.0))
    assert _ready_timeout(args) == 30.0 and "--ready-timeout" not in caplog.text   # within the wait: nothing to say
    monkeypatch.setenv("PLANTHUB_JOIN_DEADLINE", repr(time.time() + 5.0))
    assert _ready_timeout(args) == 30.0   # as asked, and warned of
    warning = caplog.text
    assert "gateway 'plc': --ready-timeout 30 s is longer than the " in warning
    assert " s left of the hub's join wait: the hub gives up first; raise the object's join_timeout" in warning


def test_opc_ua_browse_names_are_in_the_plants_namespace(tmp_path):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc", None)
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"

    async def browse():
        async with Client(endpoint, timeout=5) as client:
            ns = await client.get_namespace_index("urn:planthub:belt_plc")
            node = await client.nodes.objects.get_child([f"{ns}:belt_plc", f"{ns}:belt", f"{ns}:speed"])
            return ns, (await node.read_browse_name()).NamespaceIndex

    with ServerThread(OpcUaServer(ProcessImage(tags), endpoint), "opcua"):
        ns, found = asyncio.run(browse())
    assert found == ns != 0
