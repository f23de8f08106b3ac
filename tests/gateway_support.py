"""Support for the gateway's tests: free loopback ports, the tag table of a scenario's participant
object, and a PLC client process (tests/plc/) that is always stopped."""
from __future__ import annotations

import contextlib
import json
import socket
import subprocess
import sys

from .helpers import ROOT

BOTTLING = ROOT / "scenarios" / "bottling_plant.yaml"
LANES = ("--lanes", "A,B,C,D,E")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def export_tags(scenario, obj: str, csv_path, *extra) -> None:
    proc = subprocess.run([sys.executable, "-m", "hub", "gateway", "opcua", str(scenario), "--object", obj,
                           "--export-tags", str(csv_path), *extra], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr


@contextlib.contextmanager
def plc(module: str, *args, limit: float = 240.0):
    """A PLC client process (`python -m tests.plc.MODULE ARGS`); yields it, stops it at the end."""
    proc = subprocess.Popen([sys.executable, "-m", f"tests.plc.{module}", *map(str, args), "--limit", str(limit)],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.terminate()
        try:
            proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


def run_beside_client(scenario, out, code: str):
    """`planthub run SCENARIO --realtime --out OUT` with a client process (`python -c CODE`) beside
    it; the client has a minute after the run to end, and is killed if it has not. (run, client)."""
    client = subprocess.Popen([sys.executable, "-c", code], cwd=ROOT)
    try:
        run = subprocess.run([sys.executable, "-m", "hub", "run", str(scenario), "--realtime", "--out", str(out)],
                             capture_output=True, text=True, cwd=ROOT, timeout=120)
    finally:
        try:
            client.wait(timeout=60)
        except subprocess.TimeoutExpired:
            client.kill()
            client.wait()
    return run, client


def bottling_via_gateway(tmp, protocol: str | None, duration: float, *gateway_args):
    """The bottling plant for `duration` s, routed by a PLC client process through `planthub gateway
    PROTOCOL` (None: by the routing participant over Zenoh, as `make run` does); (run folder, the
    PLC's last line, summary.json)."""
    out, sets, client = tmp / "run", [f"run.duration={duration}"], contextlib.nullcontext()
    if protocol is not None:
        tags = tmp / "tags.csv"
        export_tags(BOTTLING, "control", tags)
        port = free_port()
        endpoint = f"opc.tcp://127.0.0.1:{port}/planthub" if protocol == "opcua" else f"127.0.0.1:{port}"
        launch = ["hub", "gateway", protocol, "bottling_plant.yaml", "--object", "control", "--endpoint", endpoint,
                  *gateway_args]
        sets.append(f"objects.control.python=[{', '.join(map(repr, launch))}]")
        client = plc(f"{protocol}_plc", tags, endpoint, *LANES)
    with client as proc:
        run = subprocess.run([sys.executable, "-m", "hub", "run", str(BOTTLING), "--out", str(out),
                              *[a for s in sets for a in ("--set", s)]],
                             capture_output=True, text=True, cwd=ROOT, timeout=600)
        said = ""
        if proc is not None:
            said, err = proc.communicate(timeout=30)
            assert proc.returncode == 0, err[-2000:]
    assert run.returncode == 0, run.stderr[-3000:]
    return out, said.strip(), json.loads((out / "summary.json").read_text())
