"""The bus settings of a run (a scenario's `run.bus` section), a plain value the scenario checker fills in."""
from __future__ import annotations

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
    publish: str = "every"               # every | change: a data-plane slot goes out at each due point, or when changed
