"""A PLC over OPC UA (asyncua's client) routing the bottling plant through `planthub gateway opcua`:
`python -m tests.plc.opcua_plc TAGS.csv ENDPOINT --lanes A,B,C,D,E [--limit S]`. It waits for the
server (up to --limit s), sets plc_ready, then answers every scan until the server goes away, and
prints how many scans and decisions it made.

It does not poll: it subscribes to `cycle` and the readers' tags (publishing interval 0: the server
sends a change as soon as it has one) and answers each new `cycle`. The gateway writes a scan's
values before its `cycle`, so the notifications of a scan's values come before (or with, earlier in
the list) the one of its number. A scan's commands and `cycle_done` go in one write, a command only
when it changes (the gateway keeps the last value written)."""
from __future__ import annotations

import asyncio
import sys
import time

from asyncua import Client, ua
from asyncua.common.subscription import DataChangeEvent, StatusChangeEvent

from tests.plc.routing import Routing, arguments, read_tags

QUIET = 1.0   # s without a notification after which the PLC asks whether the server is still there


async def main(args) -> int:
    tags = read_tags(args.tags)
    client = Client(args.endpoint, timeout=5)
    deadline = time.monotonic() + args.limit
    while True:
        try:
            await client.connect()
            break
        except (TimeoutError, OSError):
            if time.monotonic() > deadline:
                print(f"no OPC UA server at {args.endpoint} within {args.limit:g} s", file=sys.stderr)
                return 1
            await asyncio.sleep(0.1)
    uri = tags["cycle"]["opcua_node"].split(";")[0][len("nsu="):]
    ns = await client.get_namespace_index(uri)
    node = lambda tag: client.get_node(ua.NodeId(tags[tag]["opcua_node"].split(";s=")[1], ns))
    lanes = args.lanes.split(",")
    pairs = range(1, len(lanes) + 1)
    watched = ["cycle"] + [f"r{i}_read" for i in pairs] + [f"r{i}_destination" for i in pairs]
    by_node = {node(t).nodeid: t for t in watched}
    values = {t: 0 for t in watched} | {f"r{i}_destination": "" for i in pairs}
    commands = [f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")]
    written = dict.fromkeys(commands, False)   # what the gateway holds: every command starts off
    routing, last, scans = Routing(lanes), 0, 0
    try:
        subscription = await client.create_subscription(0, None)   # iterator mode: events in the order sent
        await subscription.subscribe_data_change([node(t) for t in watched])
        await node("plc_ready").write_value(ua.Variant(True, ua.VariantType.Boolean))
        while time.monotonic() < deadline:
            event = await subscription.next_event(timeout=min(QUIET, max(deadline - time.monotonic(), 0.001)))
            if event is None:
                await node("cycle").read_value()   # raises once the gateway stopped with the run
                continue
            if isinstance(event, StatusChangeEvent):
                break   # the server ended the subscription (it is stopping)
            if not isinstance(event, DataChangeEvent) or event.node.nodeid not in by_node:
                continue
            values[by_node[event.node.nodeid]] = event.value
            if values["cycle"] == last:
                continue
            cycle = values["cycle"]
            counts = [values[f"r{i}_read"] for i in pairs]
            bits = routing.scan(counts, [values[f"r{i}_destination"] for i in pairs])
            changed = [c for c in commands if bits[c] != written[c]]
            await client.write_values([node(c) for c in changed] + [node("cycle_done")],
                                      [ua.Variant(bits[c], ua.VariantType.Boolean) for c in changed]
                                      + [ua.Variant(cycle, ua.VariantType.Int32)])
            written.update((c, bits[c]) for c in changed)
            last, scans = cycle, scans + 1
        else:
            print(f"gave up after {args.limit:g} s", file=sys.stderr)
            return 1
    except (TimeoutError, ConnectionError, OSError, ua.UaError, asyncio.CancelledError, StopAsyncIteration):
        pass   # the gateway stopped with the run
    finally:
        print(f"scans {scans} decisions {routing.decisions}")
        try:
            await client.disconnect()
        except Exception:
            pass
    return 0


if __name__ == "__main__":
    raise SystemExit(asyncio.run(main(arguments(__doc__))))
