"""A PLC over S7 (python-snap7's client) routing the bottling plant through `planthub gateway s7`:
`python -m tests.plc.s7_plc TAGS.csv HOST:PORT --lanes A,B,C,D,E [--limit S]`. It waits for the
server (up to --limit s), sets plc_ready (M0.0), then answers every scan until the server goes away,
and prints how many scans and decisions it made. Its addresses are the tag table's `s7_address`."""
from __future__ import annotations

import re
import struct
import sys
import time

import snap7
from snap7.error import S7Error
from snap7.type import Area

from tests.plc.routing import Routing, arguments, read_tags

AREAS = {"I": Area.PE, "Q": Area.PA, "M": Area.MK}
POLL = 0.0005   # s before polling `cycle` again when a poll found no new scan (in lockstep the gateway holds a poll until one begins)


def where(address: str) -> tuple[str, int, int]:
    """(area, byte, bit or -1) of I0.0, QW4, MD8, DB1.DBB18."""
    db = re.fullmatch(r"DB1\.DBB(\d+)", address)
    if db:
        return "DB", int(db[1]), -1
    area, size, byte, bit = re.fullmatch(r"([IQM])([WD]?)(\d+)(?:\.(\d))?", address).groups()
    return area, int(byte), int(bit) if bit is not None else -1


def main(args) -> int:
    tags = read_tags(args.tags)
    at = {name: where(row["s7_address"]) for name, row in tags.items()}
    host, port = args.endpoint.rsplit(":", 1)
    client = snap7.Client()
    deadline = time.monotonic() + args.limit
    while True:
        try:
            client.connect(host, 0, 1, int(port))
            break
        except (S7Error, OSError):   # (python-snap7 raises its own errors and OSError alike)
            if time.monotonic() > deadline:
                print(f"no S7 server at {args.endpoint} within {args.limit:g} s", file=sys.stderr)
                return 1
            time.sleep(0.1)
    lanes = args.lanes.split(",")
    pairs = range(1, len(lanes) + 1)
    commands = [f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")]
    q_bytes = max(at[c][1] for c in commands) + 1
    counters = [at[f"r{i}_read"][1] for i in pairs]
    i_bytes = max(counters) + 2
    routing, last, scans = Routing(lanes), 0, 0
    written = bytearray(q_bytes)   # the Q image as the gateway holds it: every command starts off
    try:
        _, byte, bit = at["plc_ready"]
        client.write_area(Area.MK, 0, byte, bytearray([1 << bit]))
        while time.monotonic() < deadline:
            cycle = struct.unpack(">H", client.read_area(Area.MK, 0, at["cycle"][1], 2))[0]
            if cycle == last:
                time.sleep(POLL)
                continue
            inputs = client.read_area(Area.PE, 0, 0, i_bytes)
            counts = [struct.unpack_from(">H", inputs, b)[0] for b in counters]
            moved = [i for i in pairs if counts[i - 1] != routing.seen[i - 1]]
            destinations = [""] * len(lanes)
            for i in moved:   # a string only when its reader saw a bottle: S7 STRING, max length then length
                raw = client.db_read(1, at[f"r{i}_destination"][1], 2 + 16)
                destinations[i - 1] = raw[2:2 + raw[1]].decode()
            bits = routing.scan(counts, destinations)
            out = bytearray(q_bytes)
            for c in commands:
                _, byte, bit = at[c]
                out[byte] |= bits[c] << bit
            if out != written:   # a request less when no command changes (the gateway keeps what was written)
                client.write_area(Area.PA, 0, 0, out)
                written = out
            client.write_area(Area.MK, 0, at["cycle_done"][1], bytearray(struct.pack(">H", cycle)))
            last, scans = cycle, scans + 1
        print(f"gave up after {args.limit:g} s", file=sys.stderr)
        return 1
    except (S7Error, OSError):   # the gateway stopped with the run: python-snap7 raises its own errors then
        pass   # (anything else is this PLC's own bug: a traceback and a failed exit, which the tests check)
    finally:
        print(f"scans {scans} decisions {routing.decisions}")
        try:
            client.disconnect()
        except (S7Error, OSError):
            pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main(arguments(__doc__)))
