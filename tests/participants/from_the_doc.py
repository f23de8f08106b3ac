"""The belt drive as a participant written from schemas/wire.md alone: literal keys and msgpack
structures, no planthub protocol code — what a participant in another language does. (Zenoh is
reached through hub.bus only because every Zenoh call of this project lives there.)"""
import hmac
import os
import sys
import time
import uuid

import msgpack

from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings


def main() -> int:
    run, name = os.environ["PLANTHUB_RUN"], os.environ["PLANTHUB_NAME"]
    base = f"plant/{run}/@cosim"
    me = f"{base}/logic/{name}"
    ident = uuid.uuid4().hex
    inbox = Inbox()
    settings = BusSettings(connect=tuple(os.environ["PLANTHUB_CONNECT"].split(",")),
                           lease=float(os.environ.get("PLANTHUB_LEASE", "1")))
    with Bus(settings, listen=False) as bus:
        bus.subscribe(f"{me}/welcome", lambda m: inbox.put(("welcome", m.payload)))
        bus.subscribe(f"{me}/step", lambda m: inbox.put(("step", m.payload)))
        bus.subscribe(f"{base}/state", lambda m: inbox.put(("state", m.payload)))
        bus.subscribe(f"{me}/checkpoint", lambda m: inbox.put(("checkpoint", m.payload)))
        bus.watch_tokens(f"{base}/hub", lambda m: inbox.put(("hub", m.alive)))
        output = bus.publisher(f"{me}/output", "application/msgpack")
        answer = bus.publisher(f"{me}/checkpoint_answer", "application/msgpack")
        bus.declare_token(me)
        hello = msgpack.packb({"protocol": 1, "name": name, "id": ident, "agent": "from-the-doc",
                               "token": os.environ["PLANTHUB_TOKEN"],   # launched by the hub
                               "inputs": [["speed_setpoint", "real"], ["run", "bool"]],   # our own order
                               "outputs": [["running", "bool"], ["speed", "real"]]})
        hub_seen, said_hello, welcome = False, 0.0, None
        deadline = time.monotonic() + 30
        while welcome is None:
            if time.monotonic() > deadline:
                return 2
            if hub_seen and time.monotonic() - said_hello > 0.5:
                bus.put(f"{me}/hello", hello, "application/msgpack")
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
        ramp, speed, last = welcome["parameters"]["ramp"], 0.0, None
        key = os.environ["PLANTHUB_TOKEN"].encode()   # launched: steps and outputs are sealed with it

        def sealed(body: bytes) -> bytes:
            return hmac.digest(key, body, "sha256")[:16] + body

        output.put(sealed(msgpack.packb([-1, [False, speed]])))
        at = -1   # the last step answered: a save is of the state after it
        while True:
            item = inbox.get(30)
            if item is None:
                return 3
            kind, payload = item
            if kind == "state" and msgpack.unpackb(payload)["state"] == "stopped":
                return 0
            if kind not in ("step", "checkpoint"):
                continue
            tag, body = payload[:16], payload[16:]
            if not hmac.compare_digest(tag, hmac.digest(key, body, "sha256")[:16]):
                continue   # not the hub's
            if kind == "checkpoint":   # item 9: the state is ours to encode, here the speed as msgpack
                request = msgpack.unpackb(body)
                reply = {"op": request["op"], "tag": request["tag"], "step": request["step"]}
                if request["op"] == "save" and request["step"] != at:
                    reply["error"] = f"asked to save after step {request['step']}, my last step is {at}"
                elif request["op"] == "save":
                    reply["state"] = msgpack.packb(["belt drive", speed])
                else:
                    what, speed = msgpack.unpackb(request["state"])
                    last, at, reply["ok"] = None, request["step"], True
                answer.put(sealed(msgpack.packb(reply)))
                continue
            n, _tick, _ticks, t, h, (setpoint, go) = msgpack.unpackb(body)
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
            last, at = (n, sealed(msgpack.packb([n, [speed != 0.0, speed]]))), n
            output.put(last[1])


if __name__ == "__main__":
    raise SystemExit(main())
