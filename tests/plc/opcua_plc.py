"""A PLC over OPC UA (asyncua's client) routing the bottling plant through `planthub gateway opcua`:
`python -m tests.plc.opcua_plc TAGS.csv ENDPOINT --lanes A,B,C,D,E [--limit S]`. It waits for the
server (up to --limit s), sets plc_ready, then answers every scan until the server goes away, and
prints how many scans and decisions it made.

It polls: one Read of `cycle` and the readers' tags, which the gateway holds while the plant steps
toward its next scan and answers once the scan's values are there (so it finds each scan as soon as
the plant is at it, and no poll in between costs the plant anything). A scan's commands and
`cycle_done` go in one write, a command only when it changes (the gateway keeps the last value
written). A subscription (publishing interval 0) works as well, at some more cost: a PublishRequest
to answer besides."""
from __future__ import annotations

import asyncio
import sys
import time

from asyncua import Client, ua

from tests.plc.routing import Routing, arguments, read_tags

POLL = 0.0005   # s before polling again when a poll found no new scan


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
    watched = ["cycle"] + [f"r{i}_read" for i in pairs]
    commands = [f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")]
    written = dict.fromkeys(commands, False)   # what the gateway holds: every command starts off
    routing, last, scans = Routing(lanes), 0, 0
    try:
        nodes = [node(t) for t in watched]
        await node("plc_ready").write_value(ua.Variant(True, ua.VariantType.Boolean))
        while time.monotonic() < deadline:
            read = await client.read_values(nodes)   # the gateway holds it until a scan begins
            values = dict(zip(watched, read))
            if values["cycle"] == last:
                await asyncio.sleep(POLL)
                continue
            cycle = values["cycle"]
            counts = [values[f"r{i}_read"] for i in pairs]
            moved = [i for i in pairs if counts[i - 1] != routing.seen[i - 1]]   # a destination only when its reader saw a bottle
            destinations = dict(zip(moved, await client.read_values([node(f"r{i}_destination") for i in moved]))) if moved else {}
            bits = routing.scan(counts, [destinations.get(i, "") for i in pairs])
            changed = [c for c in commands if bits[c] != written[c]]
            await client.write_values([node(c) for c in changed] + [node("cycle_done")],
                                      [ua.Variant(bits[c], ua.VariantType.Boolean) for c in changed]
                                      + [ua.Variant(cycle, ua.VariantType.Int32)])
            written.update((c, bits[c]) for c in changed)
            last, scans = cycle, scans + 1
        else:
            print(f"gave up after {args.limit:g} s", file=sys.stderr)
            return 1
    except (TimeoutError, ConnectionError, OSError, ua.UaError, asyncio.CancelledError):
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
