"""`make bench`, bus part: lockstep steps/s with N participant processes next to bare Zenoh ping-pong
with N echo processes, measured in the same run, and the data plane's cost per point."""
from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hub.bus import Bus, Inbox, wait_until
from hub.master import Master
from hub.plant import Plant
from hub.recorder import Recorder
from hub.scenario import BusSettings, load_scenario

from .helpers import ROOT

STEPS = 3000
REPEATS = 5


def ping_pong(n: int, rounds: int) -> float:
    """Rounds per second: the hub side puts one ~40-byte message to each of n echo processes and
    waits for all n answers, as lockstep does, with nothing else."""
    payload = bytes(40)
    with Bus(BusSettings()) as bus:
        inbox = Inbox()
        pings = [bus.publisher(f"bench/{i}/ping", "zenoh/bytes") for i in range(n)]
        for i in range(n):
            bus.subscribe_payloads(f"bench/{i}/pong", inbox.put)
        echoes = [subprocess.Popen([sys.executable, "-m", "tests.participants.echo", bus.endpoints[0], str(i)],
                                   cwd=ROOT) for i in range(n)]
        try:
            if not wait_until(lambda: all(p.matching for p in pings), 30):
                raise RuntimeError("echo processes did not subscribe")

            def round_trip():
                for p in pings:
                    p.put(payload)
                for _ in range(n):
                    if inbox.get(5.0) is None:
                        raise RuntimeError("an echo did not answer")
            for _ in range(200):   # warm-up: the first answer may still race the echo's own declarations
                round_trip()
            started = time.perf_counter()
            for _ in range(rounds):
                round_trip()
            return rounds / (time.perf_counter() - started)
        finally:
            for p in pings:
                p.put(b"stop")
            for e in echoes:
                try:
                    e.wait(5)
                except subprocess.TimeoutExpired:
                    e.kill()
                    e.wait()


def lockstep_scene(n: int, folder: Path) -> Path:
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
run: {{duration: {STEPS / 1000}, physics_rate: 1000}}
objects:
  go: {{module: constant, type: bool, value: true, always: true}}
  setpoint: {{module: constant, type: real, value: 0.5, always: true}}
{drives}
flows:
{flows}
""")
    return path


def lockstep(path: Path) -> float:
    """Steps per second of the hub's loop with its participants (joined before the clock starts)."""
    scenario = load_scenario(path)
    with Plant(scenario) as plant:
        with Master(plant, Recorder([], scenario.run.physics_rate)) as master:
            master.start()
            master.run(until_tick=200)   # warm-up
            end = scenario.run.end_tick - scenario.run.substeps   # the last step closes the run: not timed
            started = time.perf_counter()
            result = master.run(until_tick=end)
            return (result.ticks / scenario.run.substeps) / (time.perf_counter() - started)


def bus_lockstep() -> None:
    print("\n## Lockstep over Zenoh: steps/s with N participant processes (loopback, 2 cores)\n")
    print("Bare ping-pong: the hub puts one 40-byte message to each of N echo processes and waits for N "
          "answers. Hub: the full loop (an empty physics world at 1 kHz, step messages, outputs decoded, "
          "Python belt-drive participants). Medians of 5, measured alternately in this run.\n")
    print("| participants | bare Zenoh ping-pong rounds/s | hub lockstep steps/s | ping-pong / hub |")
    print("|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2, 4):
            path = lockstep_scene(n, Path(tmp))
            floor, hub = [], []
            for _ in range(REPEATS):
                floor.append(ping_pong(n, STEPS))
                hub.append(lockstep(path))
            f, h = statistics.median(floor), statistics.median(hub)
            print(f"| {n} | {f:.0f} | {h:.0f} | {f / h:.2f} |")


def data_plane() -> None:
    print("\n## Data plane: cost per communication point (belt_bottle_sensor, 150 Hz, 20 s)\n")
    print("Every slot exposed (`expose: ['*']`); the viewer, another process, subscribes to `plant/<run>/**`, "
          "at every point or asking for one sample each 0.05 s.\n")
    print("| bus | subscribers | µs per point | samples per point |")
    print("|---|---|---:|---:|")
    path = ROOT / "scenarios" / "belt_bottle_sensor.yaml"
    cases = (("none", None, None), ("open", 0, None), ("open", 1, None), ("open", 1, 0.05))
    costs, per_point = {case: [] for case in cases}, {}
    for _ in range(REPEATS):   # the cases take turns, so a change in the machine's load hits all alike
        for case in cases:
            cost, samples = point_cost(path, *case[1:])
            costs[case].append(cost)
            per_point[case] = samples
    for case in cases:
        label, subscribers, period = case
        shown = "—" if subscribers is None else f"{subscribers}" + (f", every {period:g} s" if period else "")
        print(f"| {label} | {shown} | {1e6 * statistics.median(costs[case]):.0f} | {per_point[case]:.1f} |")


def point_cost(path: Path, subscribers: int | None, period: float | None) -> tuple[float, float]:
    """Seconds per communication point and data-plane samples per point of one run."""
    scenario = load_scenario(path, {"run.duration": 20.0})
    points = scenario.run.end_tick // scenario.run.substeps
    with Plant(scenario) as plant:
        bus = Bus(BusSettings()) if subscribers is not None else None
        viewer = None
        try:
            with Master(plant, Recorder([], scenario.run.physics_rate), bus=bus) as master:
                master.start()   # bus set-up and joining are not timed
                if subscribers:
                    viewer = subprocess.Popen([sys.executable, "-m", "tests.participants.viewer", scenario.name,
                                               bus.endpoints[0], *([str(period)] * bool(period))],
                                              cwd=ROOT, stdout=subprocess.DEVNULL)
                    plane = master.dataplane
                    if not wait_until(lambda: (plane.update(), len(plane.live) == len(plane.exposed)
                                               and bool(plane.requests) == bool(period))[1], 30):
                        raise RuntimeError("the viewer did not subscribe")
                started = time.perf_counter()
                master.run(until_tick=scenario.run.end_tick - scenario.run.substeps)
                cost = (time.perf_counter() - started) / points
                samples = master.dataplane.samples / points if master.dataplane is not None else 0.0
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
    bus_lockstep()
    data_plane()
