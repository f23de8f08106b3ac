"""What a PLC over the gateway costs the bottling plant: its first 56 s routed by the routing
participant over Zenoh (the floor: `make run`'s set-up), and by a PLC client process over OPC UA,
Modbus TCP, S7 and EtherNet/IP in lockstep — answering every communication step, and scanning every 0.1 s.
Alternated, medians of REPEATS; real-time factors from each run's summary. `python -m tests.bench_gateway`."""
from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from .gateway_support import bottling_via_gateway

DURATION = 56.0
REPEATS = 2
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
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(REPEATS):
            for j, (name, protocol, extra) in enumerate(WAYS):
                folder = Path(tmp) / f"{k}_{j}"
                folder.mkdir()
                _, _, summary = bottling_via_gateway(folder, protocol, DURATION, *extra)
                walls[name].append(summary["wall"]["seconds"])
    floor = statistics.median(walls[WAYS[0][0]])
    print(f"\n## The bottling plant routed by a PLC over the gateway ({DURATION:g} s, medians of {REPEATS})\n")
    print("| routing | wall s | real time × | wall ÷ floor's |")
    print("|---|---|---|---|")
    figures = {}
    for name, _, _ in WAYS:
        wall = statistics.median(walls[name])
        figures[name] = {"wall_s": wall, "realtime": DURATION / wall, "ratio": wall / floor}
        print(f"| {name} | {wall:.1f} | {DURATION / wall:.2f} | {wall / floor:.2f} |")
    return figures


if __name__ == "__main__":
    gateway()
