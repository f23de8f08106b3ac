"""`make bench`, bus part: lockstep steps/s with N participant processes next to bare Zenoh ping-pong
with N echo processes, measured in the same run; the data plane's cost per point; and the bottling
plant's real-time factor with 0, 1 and 20 watcher processes on `plant/<run>/**`, taking turns in one run."""
from __future__ import annotations

import os
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
POINT_COST_RUN = 4.0  # s of belt_bottle_sensor: at 4.4 s its bottle falls off the belt's end, and the physics
                      # watch (run.watch) stops the run
SEGMENTS = 25        # lockstep: the floor and the hub take turns this many times per N
SEGMENT = 300        # lockstep: rounds (floor) and steps (hub) per turn
WARM_UP = 200
PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
PLANT_FROM = 20.0    # s of the plant before the first turn: about 70 bottles on the line by then
PLANT_TURN = 3.0     # s of plant time per turn
PLANT_ROUNDS = 5     # each round: a turn with 0, 1 and 20 watchers
WATCHERS = (0, 1, 20)


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
    print(f"\n## Data plane: cost per communication point (belt_bottle_sensor, 150 Hz, {POINT_COST_RUN:g} s)\n")
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
    scenario = load_scenario(path, {"run.duration": POINT_COST_RUN})
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


class Watchers:
    """n watcher processes (tests/participants/watcher.py) on `plant/<run>/**`, started once and
    turned on and off between turns, so no turn pays for their start-up. They run in a session of
    their own, as HMIs an operator starts do: with Linux's autogroup scheduling the kernel then
    shares the two cores between the hub's session and the watchers' as two groups, instead of
    between the hub's thread and twenty watchers one by one."""

    def __init__(self, run: str, endpoint: str, n: int):
        self.launcher = subprocess.Popen([sys.executable, "-m", "tests.participants.watcher", run, endpoint, str(n)],
                                         cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                         start_new_session=True)
        self.pids = [int(pid) for pid in self.launcher.stdout.readline().split()]
        if len(self.pids) != n:
            raise RuntimeError("the watchers did not start")
        self.on = 0

    def _say(self, line: str) -> str:
        self.launcher.stdin.write(line + "\n")
        self.launcher.stdin.flush()
        return self.launcher.stdout.readline()

    def watch(self, n: int) -> None:
        self.on = n
        if n and self._say(f"watch {n}").strip() != "watching":
            raise RuntimeError("the watchers did not subscribe")

    def mark(self) -> None:
        """Count from here."""
        if self.on and self._say("mark").strip() != "marked":
            raise RuntimeError("the watchers did not answer")

    def stop(self) -> list[tuple[int, int]]:
        """(samples, distinct points) each watcher that was on took in since the mark."""
        if not self.on:
            return []
        self.on = 0
        return [tuple(int(x) for x in item.split("/")) for item in self._say("stop").split()]

    def cpu(self) -> float:
        """CPU seconds all watchers used so far (user and system, from /proc)."""
        total = 0
        for pid in self.pids:
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])
        return total / os.sysconf("SC_CLK_TCK")

    def settle(self, most: float = 10.0) -> None:
        """Wait until the watchers have taken in what they were sent (their CPU falls idle), so that a
        turn does not pay for the one before."""
        deadline, used = time.monotonic() + most, self.cpu()
        while time.monotonic() < deadline:
            time.sleep(0.5)
            now = self.cpu()
            if (now - used) / 0.5 < 0.03:   # cores: twenty watchers without a viewer use about 0.01
                return
            used = now

    def close(self) -> None:
        try:
            self.launcher.stdin.close()
            self.launcher.wait(30)
        except (OSError, subprocess.TimeoutExpired):
            self.launcher.kill()
            self.launcher.wait()


def watched_plant() -> None:
    print(f"\n## The bottling plant watched: {', '.join(map(str, WATCHERS))} watcher processes on `plant/<run>/**`\n")
    print(f"scenarios/bottling_plant.yaml with the routing in the hub (`objects.control.runs: hub`), "
          f"from {PLANT_FROM:g} s on, {PLANT_ROUNDS} rounds of turns of {PLANT_TURN:g} s of plant time with "
          f"{', '.join(map(str, WATCHERS))} watchers, in one run. A watcher is a hub.live.Viewer in a process of "
          "its own on loopback, all of them in a session apart from the hub's; after they subscribe, the plant "
          "runs unmeasured until the first point taken after it has gone out (`first point`, wall s: the first "
          "put on a key after its subscribers changed costs Zenoh the most) and the points for newcomers, lent "
          "the whole budget, are done. Real-time factor: median of the "
          "turns; ratio: median over the rounds of each turn against the mean of the turns without watchers "
          "before and after its round (the plant grows slower as it fills); per "
          "point of the plant in the turn: samples the hub sent, points it skipped, samples and points each "
          "watcher took in (median); CPU in cores over the turn. Between turns the watchers get the time to "
          "take in what they were sent.\n")
    warm_most = 30.0   # plant s the warm-up may take at most
    rounds_end = PLANT_FROM + PLANT_ROUNDS * (len(WATCHERS) * PLANT_TURN + (len(WATCHERS) - 1) * warm_most) + PLANT_TURN
    scenario = load_scenario(PLANT, {"objects.control.runs": "hub", "run.duration": rounds_end})
    rate, substeps = scenario.run.physics_rate, scenario.run.substeps
    bus = Bus(BusSettings())
    turns = {n: [] for n in WATCHERS}
    try:
        with Run(scenario, bus=bus) as run:
            run.start()
            run.run(until_tick=round(PLANT_FROM * rate))
            plane = run.dataplane
            watchers = Watchers(scenario.name, bus.endpoints[0], max(WATCHERS))
            try:
                # A last turn without watchers, so that each turn with watchers has one before and after it.
                for n in [n for _ in range(PLANT_ROUNDS) for n in WATCHERS] + [WATCHERS[0]]:
                    watchers.watch(n)
                    want = len(plane.exposed) if n else 0
                    if not wait_until(lambda: (plane.update(), len(plane.live) == want)[1], 30):
                        raise RuntimeError("the watchers did not (un)subscribe")
                    time.sleep(0.5)   # the other watchers' subscriptions reach the hub as well
                    subscribed, began = run.tick, time.perf_counter()
                    while n and (plane.outbox.sent_tick < subscribed or plane.outbox.welcoming) \
                            and run.tick < subscribed + warm_most * rate:
                        run.run(until_tick=run.tick + 10 * substeps)
                    first = time.perf_counter() - began
                    watchers.settle()   # what the newcomers were sent is theirs, not the turn's
                    watchers.mark()
                    sent, skipped = plane.samples, plane.skipped
                    cpu, own = watchers.cpu(), time.process_time()
                    began = time.perf_counter()
                    run.run(until_tick=run.tick + round(PLANT_TURN * rate))
                    wall = time.perf_counter() - began
                    if run.stopped_by:
                        raise RuntimeError(f"the plant ended before the benchmark did: {run.stopped_by}")
                    own = time.process_time() - own
                    cpu = watchers.cpu() - cpu
                    got = watchers.stop()
                    watchers.settle()
                    turns[n].append((PLANT_TURN / wall, plane.samples - sent, plane.skipped - skipped,
                                     statistics.median(g[0] for g in got) if got else 0,
                                     statistics.median(g[1] for g in got) if got else 0,
                                     cpu / wall, own / wall, first))
            finally:
                watchers.close()
    finally:
        bus.close()
    points = PLANT_TURN * rate / substeps
    print("| watchers | real-time factor | ratio to none | first point s | samples sent per point | points skipped "
          "| each watcher: samples per point | points it saw | watchers' CPU | hub's CPU |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    none = turns[WATCHERS[0]]
    for n in WATCHERS:
        t = turns[n][:PLANT_ROUNDS]
        med = lambda k: statistics.median(x[k] for x in t)
        # Against the turns without watchers before and after it: the plant grows slower as it fills.
        ratio = 1.0 if n == WATCHERS[0] else \
            statistics.median(x[0] / ((a[0] + b[0]) / 2) for x, a, b in zip(t, none, none[1:]))
        first = f"{med(7):.1f}" if n else "—"
        print(f"| {n} | {med(0):.2f}× | {ratio:.2f} | {first} | {med(1) / points:.1f} | {100 * med(2) / points:.0f} % "
              f"| {med(3) / points:.1f} | {100 * med(4) / points:.0f} % | {med(5):.2f} | {med(6):.2f} |", flush=True)


if __name__ == "__main__":
    parts = sys.argv[1:] or ["lockstep", "dataplane", "watched"]   # e.g. `python -m tests.bench_bus watched`
    unknown = set(parts) - {"lockstep", "dataplane", "watched"}
    if unknown:
        raise SystemExit(f"unknown part {', '.join(sorted(unknown))}: give lockstep, dataplane and/or watched")
    if "lockstep" in parts:
        bus_lockstep()
    if "dataplane" in parts:
        data_plane()
    if "watched" in parts:
        watched_plant()
