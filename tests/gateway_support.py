"""Support for the gateway's tests: free loopback ports, the tag table of a scenario's participant
object, and a PLC client process (tests/plc/) that is always stopped."""
from __future__ import annotations

import contextlib
import socket
import subprocess
import sys

from .helpers import ROOT


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
