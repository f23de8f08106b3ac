"""The bus settings of a run (a scenario's `run.bus` section), a plain value the scenario checker fills in."""
from __future__ import annotations

import ipaddress
from dataclasses import dataclass

from hub.bus.tls import TlsSettings


@dataclass(frozen=True)
class BusSettings:
    """The scenario's `run.bus` section: how the hub joins Zenoh and treats participants."""

    mode: str = "peer"                   # peer | client | router
    listen: tuple[str, ...] = ()         # endpoints; none: a free loopback port
    connect: tuple[str, ...] = ()
    scouting: bool = False               # multicast scouting
    lease: float = 1.0                   # s: a participant silent this long is lost
    on_loss: str = "stop"                # stop | pause: what a lost participant does to the run
    publish_period: float = 0.0          # s between data-plane samples nobody asked a rate for
    expose: tuple[str, ...] = ("*",)     # slots on the data plane: patterns of object.component.slot
    tls: TlsSettings | None = None       # certificates for tls/ endpoints (hub/bus/tls.py)
    control: tuple[str, ...] | None = None   # access control: the certificate common names that may
                                             # act on the control plane; None: whoever joins may
    watch: tuple[str, ...] = ()          # access control: the common names that may also watch (data plane,
                                         # run state, rate requests); the control names may anyway
    publish: str = "every"               # every | change: a data-plane slot goes out at each due point, or when changed
    instructor: tuple[str, ...] = ()     # access control: the common names that may also see and inject faults
                                         # (the instructor's key, plant/<run>/@instructor/**), and watch


def exposure(settings: BusSettings) -> list[str]:
    """What these settings expose beyond this machine, said out loud (`planthub validate` and `run`
    print it). The default — listening on a free port of 127.0.0.1 — reaches only local processes,
    any of which may then serve logic, watch and command the plant."""
    out = []
    beyond = [e for e in settings.listen if not _loopback(e)]
    guarded = settings.tls is not None and settings.tls.mutual and settings.control is not None
    if beyond and not guarded:
        out.append(f"the hub listens beyond this machine ({', '.join(beyond)}) without mutual TLS and access "
                   "control: whoever reaches it may serve logic, watch and command the plant (give run.bus.tls "
                   "with mutual: true and run.bus.access)")
    if settings.tls is not None and not settings.tls.mutual:
        out.append("run.bus.tls without mutual: true: the hub does not check who connects, so any process that "
                   "reaches it may join, watch and command")
    return out


def _loopback(endpoint: str) -> bool:
    """Whether a listen endpoint (`tcp/127.0.0.1:7447`, `tls/[::1]:7447`) takes only local connections."""
    address = endpoint.split("/", 1)[-1].split("#", 1)[0]
    host = address.rsplit(":", 1)[0].strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False   # a host name: it may resolve to anything
