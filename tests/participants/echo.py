"""Benchmark floor: echo each payload from bench/<i>/ping back on bench/<i>/pong — bare Zenoh pub/sub
through hub.bus, no planthub protocol, no decoding."""
import sys

from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings

if __name__ == "__main__":
    endpoint, i = sys.argv[1], sys.argv[2]
    inbox = Inbox()
    with Bus(BusSettings(connect=(endpoint,)), listen=False) as bus:
        pong = bus.publisher(f"bench/{i}/pong", "zenoh/bytes")
        bus.subscribe_payloads(f"bench/{i}/ping", inbox.put)
        while (payload := inbox.get(30.0)) is not None and payload != b"stop":
            pong.put(payload)
