"""Exposure is said out loud: a hub listening beyond loopback without mutual TLS and access control,
or with TLS that does not check who connects, is warned about; the loopback default is not."""
from __future__ import annotations

import pytest

from hub.bus.settings import BusSettings, exposure
from hub.bus.tls import TlsSettings

MUTUAL = TlsSettings("ca.pem", "hub.pem", "hub.key", mutual=True)


@pytest.mark.parametrize("listen", [(), ("tcp/127.0.0.1:7447",), ("tcp/127.3.2.1:7447",), ("tcp/[::1]:7447",),
                                    ("tcp/localhost:7447",)])
def test_loopback_is_no_exposure(listen):
    assert exposure(BusSettings(listen=listen)) == []


@pytest.mark.parametrize("listen", ["tcp/0.0.0.0:7447", "tcp/192.168.1.20:7447", "tcp/[::]:7447", "tcp/plant-hub.local:7447"])
def test_listening_beyond_loopback_without_mutual_tls_and_access_is_warned(listen):
    (warning,) = exposure(BusSettings(listen=(listen,)))
    assert warning.startswith(f"the hub listens beyond this machine ({listen}) without mutual TLS and access control")


def test_mutual_tls_with_access_control_beyond_loopback_is_no_exposure():
    assert exposure(BusSettings(listen=("tls/0.0.0.0:7447",), tls=MUTUAL, control=("plc",))) == []


def test_mutual_tls_without_access_control_is_still_exposure():
    (warning,) = exposure(BusSettings(listen=("tls/0.0.0.0:7447",), tls=MUTUAL))
    assert "without mutual TLS and access control" in warning


def test_tls_without_mutual_is_warned_even_on_loopback():
    (warning,) = exposure(BusSettings(listen=("tls/127.0.0.1:7447",), tls=TlsSettings("ca.pem", "hub.pem", "hub.key")))
    assert warning.startswith("run.bus.tls without mutual: true: the hub does not check who connects")


def test_validate_warns_of_a_hub_listening_on_every_interface(tmp_path):
    import subprocess
    import sys

    from .helpers import ROOT

    scene = tmp_path / "open.yaml"
    scene.write_text((ROOT / "scenarios" / "belt_bottle_sensor.yaml").read_text()
                     .replace("  seed: 0\n", "  seed: 0\n  bus: {listen: [tcp/0.0.0.0:7447]}\n"))
    proc = subprocess.run([sys.executable, "-m", "hub", "validate", str(scene)], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert ("planthub: warning: the hub listens beyond this machine (tcp/0.0.0.0:7447) without mutual TLS and "
            "access control") in proc.stderr
