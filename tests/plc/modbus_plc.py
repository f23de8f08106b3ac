"""A PLC over Modbus TCP (pymodbus's client) routing the bottling plant through `planthub gateway
modbus`: `python -m tests.plc.modbus_plc TAGS.csv HOST:PORT --lanes A,B,C,D,E [--limit S]`. It
waits for the server (up to --limit s), sets plc_ready, then answers every scan until the server
goes away, and prints how many scans and decisions it made.

Each request is a round trip the plant waits on in lockstep: a scan's inputs come with the poll that
sees the new `cycle` (all input registers in one read; the gateway holds a poll between two scans
until the next begins), the command coils go in one write and only when one of them changes (the
gateway keeps the last value written), then `cycle_done`. It runs as a PLC's cyclic program does,
one request after another: pymodbus's blocking client (its asyncio client took 0.2 ms more a round trip)."""
from __future__ import annotations

import struct
import sys
import time

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

from tests.plc.routing import Routing, arguments, read_tags

POLL = 0.0005   # s before polling `cycle` again when a poll found no new scan


def text(words: list[int]) -> str:
    return struct.pack(f">{len(words)}H", *words).rstrip(b"\0").decode()


def main(args) -> int:
    tags = read_tags(args.tags)
    address = lambda tag: int(tags[tag]["modbus_address"])
    host, port = args.endpoint.rsplit(":", 1)
    client = ModbusTcpClient(host, port=int(port), timeout=5, retries=0)
    deadline = time.monotonic() + args.limit
    while not client.connect():
        if time.monotonic() > deadline:
            print(f"no Modbus server at {args.endpoint} within {args.limit:g} s", file=sys.stderr)
            return 1
        time.sleep(0.1)
    lanes = args.lanes.split(",")
    pairs = range(1, len(lanes) + 1)
    inputs = [t for t in tags.values() if t["modbus_table"] == "input_register"]
    first = min(int(t["modbus_address"]) for t in inputs)
    count = max(int(t["modbus_address"]) + int(t["modbus_count"]) for t in inputs) - first
    words = lambda regs, tag: regs[address(tag) - first:address(tag) - first + int(tags[tag]["modbus_count"])]
    commands = sorted((f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")), key=address)
    start = address(commands[0])
    assert [address(c) for c in commands] == list(range(start, start + len(commands))), "command coils not contiguous"
    routing, last, scans = Routing(lanes), 0, 0
    written = [False] * len(commands)   # the coils as the gateway holds them: every command starts off
    try:
        client.write_coil(address("plc_ready"), True)
        while time.monotonic() < deadline:
            regs = client.read_input_registers(first, count=count).registers
            cycle = words(regs, "cycle")[0]
            if cycle == last:
                time.sleep(POLL)
                continue
            counts = [words(regs, f"r{i}_read")[0] for i in pairs]
            destinations = [text(words(regs, f"r{i}_destination")) for i in pairs]
            bits = routing.scan(counts, destinations)
            coils = [bits[c] for c in commands]
            if coils != written:
                client.write_coils(start, coils)
                written = coils
            client.write_register(address("cycle_done"), cycle)
            last, scans = cycle, scans + 1
        print(f"gave up after {args.limit:g} s", file=sys.stderr)
        return 1
    except (ModbusException, ConnectionError, OSError, AttributeError):
        pass   # the gateway stopped with the run (a read that got no answer has no registers)
    finally:
        print(f"scans {scans} decisions {routing.decisions}")
        client.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(arguments(__doc__)))
