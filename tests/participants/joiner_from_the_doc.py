"""The belt drive as a participant that joins by itself, written from schemas/wire.md alone: literal
keys and msgpack structures, the seal key agreed as item 7 says (X25519, HKDF-SHA256) with the
`cryptography` primitives, no planthub protocol code — what a joiner in another language does.
With --no-key it says hello without `key`, as a participant written before sealed joiners: its
messages then go unsealed. (Zenoh is reached through hub.bus only because every Zenoh call of this
project lives there.)

    python -m tests.participants.joiner_from_the_doc --run RUN --name drive --connect ENDPOINT [--no-key]
"""
import argparse
import hmac
import sys
import time
import uuid

import msgpack

from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--run", required=True)
    parser.add_argument("--name", required=True)
    parser.add_argument("--connect", required=True)
    parser.add_argument("--no-key", action="store_true")
    args = parser.parse_args()
    run, name = args.run, args.name
    base = f"plant/{run}/@cosim"
    me = f"{base}/logic/{name}"
    ident = uuid.uuid4().hex
    inbox = Inbox()
    hello = {"protocol": 1, "name": name, "id": ident, "agent": "joiner-from-the-doc",
             "inputs": [["speed_setpoint", "real"], ["run", "bool"]],   # our own order
             "outputs": [["running", "bool"], ["speed", "real"]]}
    private = None
    if not args.no_key:
        from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PrivateKey
        from cryptography.hazmat.primitives.serialization import Encoding, PublicFormat

        private = X25519PrivateKey.generate()
        hello["key"] = private.public_key().public_bytes(Encoding.Raw, PublicFormat.Raw)   # 32 bytes: bin
    with Bus(BusSettings(connect=(args.connect,)), listen=False) as bus:
        bus.subscribe(f"{me}/welcome", lambda m: inbox.put(("welcome", m.payload)))
        bus.subscribe(f"{me}/step", lambda m: inbox.put(("step", m.payload)))
        bus.subscribe(f"{base}/state", lambda m: inbox.put(("state", m.payload)))
        bus.watch_tokens(f"{base}/hub", lambda m: inbox.put(("hub", m.alive)))
        output = bus.publisher(f"{me}/output", "application/msgpack")
        bus.declare_token(me)
        packed = msgpack.packb(hello, use_bin_type=True)
        hub_seen, said_hello, welcome = False, 0.0, None
        deadline = time.monotonic() + 30
        while welcome is None:
            if time.monotonic() > deadline:
                return 2
            if hub_seen and time.monotonic() - said_hello > 0.5:
                bus.put(f"{me}/hello", packed, "application/msgpack")
                said_hello = time.monotonic()
            item = inbox.get(0.1)
            if item is None:
                continue
            if item[0] == "hub":
                hub_seen = item[1]
            elif item[0] == "welcome":
                message = msgpack.unpackb(item[1])
                if message["id"] == ident:
                    if not message["accepted"]:
                        print(message["error"], file=sys.stderr)
                        return 1
                    welcome = message
        key = None
        if private is not None:
            from cryptography.hazmat.primitives import hashes
            from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PublicKey
            from cryptography.hazmat.primitives.kdf.hkdf import HKDF

            shared = private.exchange(X25519PublicKey.from_public_bytes(welcome["key"]))
            info = b"planthub seal 1" + run.encode() + name.encode() + ident.encode()
            key = HKDF(algorithm=hashes.SHA256(), length=32, salt=None, info=info).derive(shared)

        def sealed(body: bytes) -> bytes:
            return body if key is None else hmac.digest(key, body, "sha256")[:16] + body

        ramp, speed, last = welcome["parameters"]["ramp"], 0.0, None
        output.put(sealed(msgpack.packb([-1, [False, speed]])))
        while True:
            item = inbox.get(30)
            if item is None:
                return 3
            kind, payload = item
            if kind == "state" and msgpack.unpackb(payload)["state"] == "stopped":
                return 0
            if kind != "step":
                continue
            if key is not None:
                tag, payload = payload[:16], payload[16:]
                if not hmac.compare_digest(tag, hmac.digest(key, payload, "sha256")[:16]):
                    continue   # not the hub's
            n, _tick, _ticks, t, h, (setpoint, go) = msgpack.unpackb(payload)
            if last is not None and last[0] == n:
                output.put(last[1])
                continue
            target = setpoint if go else 0.0
            gap, most = target - speed, ramp * h
            if gap != 0.0:
                if ramp == 0.0 or abs(gap) <= most * (1.0 + 1e-9):
                    speed = target
                else:
                    speed += most if gap > 0 else -most
            last = (n, sealed(msgpack.packb([n, [speed != 0.0, speed]])))
            output.put(last[1])


if __name__ == "__main__":
    raise SystemExit(main())
