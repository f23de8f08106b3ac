"""A PLC over EtherNet/IP (pylogix's client, as for a ControlLogix) routing the bottling plant through
`planthub gateway enip`: `python -m tests.plc.enip_plc TAGS.csv HOST:PORT --lanes A,B,C,D,E [--limit S]`.
It waits for the server (up to --limit s), sets plc_ready, then answers every scan until the server
goes away, and prints how many scans and decisions it made. Tags by name, as a Logix program has them.

It polls `cycle` with the readers' counters in one request (in lockstep the gateway holds a poll
made between two scans until the next begins, and answers the whole request from that scan), reads
a destination only when its reader saw a bottle, and writes a command only when it changes (the
gateway keeps the last value written, so a command not written holds its value) in one request with
`cycle_done`."""
from __future__ import annotations

import sys
import time

from pylogix import PLC

from tests.plc.routing import Routing, arguments

POLL = 0.0005   # s before polling `cycle` again when a poll found no new scan (in lockstep the gateway holds a poll until one begins)


def main(args) -> int:
    host, port = args.endpoint.rsplit(":", 1)
    lanes = args.lanes.split(",")
    pairs = range(1, len(lanes) + 1)
    commands = [f"sw{i}_{kind}" for i in pairs for kind in ("work", "base")]
    written = dict.fromkeys(commands, False)   # what the gateway holds: every command starts off
    routing, last, scans = Routing(lanes), 0, 0
    deadline = time.monotonic() + args.limit
    with PLC(host) as plc:
        plc.Port, plc.SocketTimeout = int(port), 5.0
        while plc.Write("plc_ready", True).Status != "Success":
            if time.monotonic() > deadline:
                print(f"no EtherNet/IP server at {args.endpoint} within {args.limit:g} s", file=sys.stderr)
                return 1
            time.sleep(0.1)
        try:
            while time.monotonic() < deadline:
                polled = plc.Read(["cycle"] + [f"r{i}_read" for i in pairs])   # held until a scan begins
                if any(v.Status != "Success" for v in polled):
                    break   # the gateway stopped with the run (pylogix says so in the status)
                cycle, values = polled[0].Value, polled[1:]
                if cycle == last:
                    time.sleep(POLL)
                    continue
                counts = [v.Value for v in values]
                # a string only when its reader saw a bottle (pylogix 1.1.6 reads an SSTRING right only alone)
                read = {i: plc.Read(f"r{i}_destination") for i in pairs if counts[i - 1] != routing.seen[i - 1]}
                if any(r.Status != "Success" for r in read.values()):
                    break
                destinations = [read[i].Value if i in read else "" for i in pairs]
                bits = routing.scan(counts, destinations)
                changed = [(c, bits[c]) for c in commands if bits[c] != written[c]]
                if any(r.Status != "Success" for r in plc.Write(changed + [("cycle_done", cycle)])):
                    break
                written.update(changed)
                last, scans = cycle, scans + 1
            else:
                print(f"gave up after {args.limit:g} s", file=sys.stderr)
                return 1
        except OSError:
            pass   # the gateway stopped with the run (anything else is this PLC's own bug: it fails the test)
        finally:
            print(f"scans {scans} decisions {routing.decisions}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(arguments(__doc__)))
