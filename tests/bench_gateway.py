"""What a PLC over the gateway costs the bottling plant: its first 56 s routed by the routing
participant over Zenoh (the floor: `make run`'s set-up), and by a PLC client process over OPC UA,
Modbus TCP, S7 and EtherNet/IP in lockstep — answering every communication step, and scanning every 0.1 s.
Each PLC's run between two runs of the floor, its ratio to their mean (the machine's load drifts over
the minutes a round takes); medians of REPEATS rounds. `python -m tests.bench_gateway`."""
from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from .gateway_support import bottling_via_gateway

DURATION = 56.0
REPEATS = 3
WAYS = [("routing participant over Zenoh (floor)", None, ()),
        ("OPC UA, lockstep, a scan every step", "opcua", ()),
        ("Modbus TCP, lockstep, a scan every step", "modbus", ()),
        ("OPC UA, lockstep, a scan every 0.1 s", "opcua", ("--scan", "0.1")),
        ("Modbus TCP, lockstep, a scan every 0.1 s", "modbus", ("--scan", "0.1")),
        ("S7, lockstep, a scan every step", "s7", ()),
        ("S7, lockstep, a scan every 0.1 s", "s7", ("--scan", "0.1")),
        ("EtherNet/IP, lockstep, a scan every step", "enip", ()),
        ("EtherNet/IP, lockstep, a scan every 0.1 s", "enip", ("--scan", "0.1"))]


def gateway() -> dict:
    walls = {name: [] for name, _, _ in WAYS}
    ratios = {name: [] for name, _, _ in WAYS}
    with tempfile.TemporaryDirectory() as tmp:
        def wall(protocol, extra):
            folder = Path(tempfile.mkdtemp(dir=tmp))
            return bottling_via_gateway(folder, protocol, DURATION, *extra)[2]["wall"]["seconds"]

        floor_name = WAYS[0][0]
        for _ in range(REPEATS):
            before = wall(None, ())
            walls[floor_name].append(before)
            for name, protocol, extra in WAYS[1:]:
                walls[name].append(wall(protocol, extra))
                after = wall(None, ())
                walls[floor_name].append(after)
                ratios[name].append(walls[name][-1] / ((before + after) / 2))
                before = after
    print(f"\n## The bottling plant routed by a PLC over the gateway ({DURATION:g} s, medians of {REPEATS})\n")
    print("| routing | wall s | real time × | wall ÷ the floor's beside it |")
    print("|---|---|---|---|")
    figures = {}
    for name, _, _ in WAYS:
        median = statistics.median(walls[name])
        ratio = statistics.median(ratios[name]) if ratios[name] else 1.0
        figures[name] = {"wall_s": median, "realtime": DURATION / median, "ratio": ratio}
        print(f"| {name} | {median:.1f} | {DURATION / median:.2f} | {ratio:.2f} |")
    return figures


if __name__ == "__main__":
    gateway()
