"""`make bench`, bus part: lockstep steps/s with N participant processes next to bare Zenoh ping-pong
with N echo processes, measured in the same run, and the data plane's cost per point."""
from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hub.bus.session import Bus, Inbox, wait_until
from hub.bus.settings import BusSettings
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT

REPEATS = 5          # data plane: runs per case
SEGMENTS = 25        # lockstep: the floor and the hub take turns this many times per N
SEGMENT = 300        # lockstep: rounds (floor) and steps (hub) per turn
WARM_UP = 200


class PingPong:
    """The floor: bare Zenoh ping-pong through hub.bus. This process puts one 40-byte message to
    each of n echo processes and waits for all n answers, as lockstep does, with nothing else."""

    def __init__(self, n: int):
        self.n = n
        self.bus = Bus(BusSettings())
        self.inbox = Inbox()
        self.pings = [self.bus.publisher(f"bench/{i}/ping", "zenoh/bytes") for i in range(n)]
        for i in range(n):
            self.bus.subscribe_payloads(f"bench/{i}/pong", self.inbox.put)
        self.echoes = [subprocess.Popen([sys.executable, "-m", "tests.participants.echo", self.bus.endpoints[0],
                                         str(i)], cwd=ROOT) for i in range(n)]
        if not wait_until(lambda: all(p.matching for p in self.pings), 30):
            self.close()
            raise RuntimeError("echo processes did not subscribe")
        self.rate(WARM_UP)   # the first answers may still race the echoes' own declarations

    def rate(self, rounds: int) -> float:
        """Rounds per second over `rounds` round trips."""
        payload, pings, get, n = bytes(40), self.pings, self.inbox.get, self.n
        started = time.perf_counter()
        for _ in range(rounds):
            for p in pings:
                p.put(payload)
            for _ in range(n):
                if get(5.0) is None:
                    raise RuntimeError("an echo did not answer")
        return rounds / (time.perf_counter() - started)

    def close(self) -> None:
        try:
            for p in self.pings:
                p.put(b"stop")
            for e in self.echoes:
                try:
                    e.wait(5)
                except subprocess.TimeoutExpired:
                    e.kill()
                    e.wait()
        finally:
            self.bus.close()


def lockstep_scene(n: int, folder: Path, steps: int = WARM_UP + SEGMENTS * SEGMENT) -> Path:
    """n belt-drive participants fed by constants, no bodies: one physics tick per step (1 kHz)."""
    drives = "\n".join(f"""  d{i}:
    module: participant
    inputs: {{run: bool, speed_setpoint: real}}
    outputs: {{speed: real, running: bool}}
    command: [python, -m, modules.belt_drive_logic]
    cwd: {ROOT}""" for i in range(n))
    flows = "\n".join(f"  - {{from: go.value.out, to: d{i}.logic.run}}\n"
                      f"  - {{from: setpoint.value.out, to: d{i}.logic.speed_setpoint}}" for i in range(n))
    path = folder / f"lockstep{n}.yaml"
    path.write_text(f"""planthub: 1
run: {{duration: {(steps + 1) / 1000}, physics_rate: 1000}}
objects:
  go: {{module: constant, type: bool, value: true, always: true}}
  setpoint: {{module: constant, type: real, value: 0.5, always: true}}
{drives}
flows:
{flows}
""")
    return path


class HubLoop:
    """The hub's full loop with its participants, joined and warmed up before any clock starts."""

    def __init__(self, path: Path):
        self.run = Run(load_scenario(path))
        try:
            self.run.start()
            self.run.run(until_tick=WARM_UP)
        except BaseException:
            self.close()
            raise

    def rate(self, steps: int) -> float:
        """Steps per second over the next `steps` steps (one tick each)."""
        run = self.run
        started = time.perf_counter()
        run.run(until_tick=run.tick + steps)
        return steps / (time.perf_counter() - started)

    def close(self) -> None:
        self.run.close()


def bus_lockstep() -> None:
    print("\n## Lockstep over Zenoh: steps/s with N participant processes (loopback, 2 cores)\n")
    print("Bare ping-pong: the hub puts one 40-byte message to each of N echo processes and waits for N "
          "answers. Hub: the full loop (an empty physics world at 1 kHz, step messages, outputs decoded, "
          f"Python belt-drive participants). Both set up side by side, then taking turns of {SEGMENT} "
          f"rounds or steps, {SEGMENTS} times: medians, and the median of the {SEGMENTS} ratios of "
          "neighbouring turns. Echo processes and participants alike run in this process's session (the "
          "hub launches its participants in a process group of their own, in its session), so the "
          "scheduler treats both sides the same.\n")
    print("| participants | bare Zenoh ping-pong rounds/s | hub lockstep steps/s | ping-pong / hub |")
    print("|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2, 4):
            floor, hub = [], []
            pong = PingPong(n)
            try:
                loop = HubLoop(lockstep_scene(n, Path(tmp)))
                try:
                    for _ in range(SEGMENTS):
                        floor.append(pong.rate(SEGMENT))
                        hub.append(loop.rate(SEGMENT))
                finally:
                    loop.close()
            finally:
                pong.close()
            ratio = statistics.median(f / h for f, h in zip(floor, hub))
            print(f"| {n} | {statistics.median(floor):.0f} | {statistics.median(hub):.0f} | {ratio:.2f} |",
                  flush=True)


def data_plane() -> None:
    print("\n## Data plane: cost per communication point (belt_bottle_sensor, 150 Hz, 20 s)\n")
    print("Every slot exposed (`expose: ['*']`); the viewer, another process, subscribes to `plant/<run>/**`, "
          "at every point or asking for one sample each 0.05 s; `change`: with `run.bus.publish: change`.\n")
    print("| bus | subscribers | µs per point | samples per point |")
    print("|---|---|---:|---:|")
    path = ROOT / "scenarios" / "belt_bottle_sensor.yaml"
    cases = (("none", None, None, "every"), ("open", 0, None, "every"), ("open", 1, None, "every"),
             ("open", 1, 0.05, "every"), ("open", 1, None, "change"))
    costs, per_point = {case: [] for case in cases}, {}
    for _ in range(REPEATS):   # the cases take turns, so a change in the machine's load hits all alike
        for case in cases:
            cost, samples = point_cost(path, *case[1:])
            costs[case].append(cost)
            per_point[case] = samples
    for case in cases:
        label, subscribers, period, publish = case
        shown = "—" if subscribers is None else f"{subscribers}" + (f", every {period:g} s" if period else "")
        shown += ", change" if publish == "change" else ""
        print(f"| {label} | {shown} | {1e6 * statistics.median(costs[case]):.0f} | {per_point[case]:.1f} |")


def point_cost(path: Path, subscribers: int | None, period: float | None, publish: str) -> tuple[float, float]:
    """Seconds per communication point and data-plane samples per point of one run."""
    scenario = load_scenario(path, {"run.duration": 20.0})
    points = scenario.run.end_tick // scenario.run.substeps
    bus = Bus(BusSettings(publish=publish)) if subscribers is not None else None
    viewer = None
    try:
        with Run(scenario, bus=bus) as run:
            run.start()   # bus set-up and joining are not timed
            if subscribers:
                viewer = subprocess.Popen([sys.executable, "-m", "tests.participants.viewer", scenario.name,
                                           bus.endpoints[0], *([str(period)] * bool(period))],
                                          cwd=ROOT, stdout=subprocess.DEVNULL)
                plane = run.dataplane
                if not wait_until(lambda: (plane.update(), len(plane.live) == len(plane.exposed)
                                           and bool(plane.requests) == bool(period))[1], 30):
                    raise RuntimeError("the viewer did not subscribe")
            started = time.perf_counter()
            run.run(until_tick=scenario.run.end_tick - scenario.run.substeps)
            cost = (time.perf_counter() - started) / points
            samples = run.dataplane.samples / points if run.dataplane is not None else 0.0
    finally:
        if bus is not None:
            bus.close()
        if viewer is not None:
            try:
                viewer.wait(15)
            except subprocess.TimeoutExpired:
                viewer.kill()
                viewer.wait()
    return cost, samples


if __name__ == "__main__":
    parts = sys.argv[1:] or ["lockstep", "dataplane"]   # e.g. `python -m tests.bench_bus lockstep`
    unknown = set(parts) - {"lockstep", "dataplane"}
    if unknown:
        raise SystemExit(f"unknown part {', '.join(sorted(unknown))}: give lockstep and/or dataplane")
    if "lockstep" in parts:
        bus_lockstep()
    if "dataplane" in parts:
        data_plane()
