"""A PLC over OPC UA (asyncua's client) routing the bottling plant through `planthub gateway opcua`:
`python -m tests.plc.opcua_plc TAGS.csv ENDPOINT --lanes A,B,C,D,E [--limit S]`. It waits for the
server (up to --limit s), sets plc_ready, then answers every scan until the server goes away, and
prints how many scans and decisions it made."""
from __future__ import annotations

import asyncio
import sys
import time

from asyncua import Client, ua

from tests.plc.routing import Routing, arguments, read_tags


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
    watched = [node("cycle")] + [node(f"r{i}_read") for i in pairs] + [node(f"r{i}_destination") for i in pairs]
    commands = [f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")]
    command_nodes = [node(c) for c in commands]
    done = node("cycle_done")
    routing, last, scans = Routing(lanes), 0, 0
    await node("plc_ready").write_value(ua.Variant(True, ua.VariantType.Boolean))
    try:
        while time.monotonic() < deadline:
            values = await client.read_values(watched)
            cycle = values[0]
            if cycle == last:
                await asyncio.sleep(0.0005)
                continue
            counts, destinations = values[1:1 + len(lanes)], values[1 + len(lanes):]
            bits = routing.scan(counts, destinations)
            await client.write_values(command_nodes + [done],
                                      [ua.Variant(bits[c], ua.VariantType.Boolean) for c in commands]
                                      + [ua.Variant(cycle, ua.VariantType.Int32)])
            last, scans = cycle, scans + 1
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
