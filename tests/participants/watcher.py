"""Benchmark watchers: hub.live.Viewers on `plant/<run>/**`, each in its own process, turned on and off through stdin.

`python -m tests.participants.watcher RUN ENDPOINT N` starts N watcher processes and prints their
process ids on one line; then, on stdin, `watch K` lets the first K of them subscribe (it answers
`watching` once they have), `mark` starts their counts afresh, `stop` closes their viewers and
prints one line `SAMPLES/POINTS ...` for each that watched (samples taken since the mark, and the
distinct ticks of those that carry a value: the points it saw); end of input ends them all. Staying alive between turns keeps the start-up of
twenty processes out of the measured windows. The bench starts this in a session of its own, as
an operator's HMIs would be: Linux's autogroup scheduling then shares the CPU between the hub's
session and the watchers' as two groups (`python -m tests.bench_bus`, tests/README.md).

Without N, one watcher: `watch`, `mark` and `stop` on stdin, `watching`, `marked` and
`SAMPLES POINTS` back.
"""
import subprocess
import sys
import threading

from hub.live import Viewer


def one(run: str, endpoint: str) -> None:
    viewer = counter = None
    stop = threading.Event()
    seen = {"samples": 0, "ticks": set()}

    def take(v):
        while not stop.is_set():
            sample = v.next(0.2)
            if sample is not None:
                seen["samples"] += 1
                if sample.value is not None:   # an event carries the tick where it fired, not of a point sent
                    seen["ticks"].add(sample.tick)

    for line in sys.stdin:
        command = line.strip()
        if command == "watch" and viewer is None:
            viewer = Viewer(run, [endpoint])
            viewer.watch("**")
            seen["samples"], seen["ticks"] = 0, set()
            stop.clear()
            counter = threading.Thread(target=take, args=(viewer,), daemon=True)
            counter.start()
            print("watching", flush=True)
        elif command == "mark":
            seen["samples"], seen["ticks"] = 0, set()
            print("marked", flush=True)
        elif command == "stop" and viewer is not None:
            stop.set()
            counter.join(5.0)
            viewer.close()
            viewer = None
            print(seen["samples"], len(seen["ticks"]), flush=True)
    if viewer is not None:
        viewer.close()


def many(run: str, endpoint: str, n: int) -> None:
    procs = [subprocess.Popen([sys.executable, "-m", "tests.participants.watcher", run, endpoint],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True) for _ in range(n)]
    print(" ".join(str(p.pid) for p in procs), flush=True)
    on = []
    try:
        for line in sys.stdin:
            command, *count = line.split()
            if command == "watch":
                on = procs[:int(count[0])]
                for p in on:
                    p.stdin.write("watch\n")
                    p.stdin.flush()
                for p in on:
                    p.stdout.readline()
                print("watching", flush=True)
            elif command == "mark":
                for p in on:
                    p.stdin.write("mark\n")
                    p.stdin.flush()
                for p in on:
                    p.stdout.readline()
                print("marked", flush=True)
            elif command == "stop":
                for p in on:
                    p.stdin.write("stop\n")
                    p.stdin.flush()
                print(" ".join("/".join(p.stdout.readline().split()) for p in on), flush=True)
                on = []
    finally:
        for p in procs:
            try:
                p.stdin.close()
                p.wait(10)
            except (OSError, subprocess.TimeoutExpired):
                p.kill()
                p.wait()


if __name__ == "__main__":
    if len(sys.argv) > 3:
        many(sys.argv[1], sys.argv[2], int(sys.argv[3]))
    else:
        one(sys.argv[1], sys.argv[2])
