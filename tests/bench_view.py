"""`make bench`, the view: what recording every body costs (Arrow against CSV), and the bottling
plant's real-time factor with no viewer, with `planthub view` connected, and with a browser on it,
with the page's frame rate in headless chromium (`python -m tests.bench_view [recording] [viewed]`).

Each figure is a median over rounds that take turns in one run (this 2-core machine is noisy):
read the ratios.
"""
from __future__ import annotations

import contextlib
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hub.bus import wire
from hub.bus.session import Bus
from hub.bus.settings import BusSettings
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario
from modules.source import Source

from .helpers import ROOT
from .screenshot_view import BUNDLE, CHROMIUM, FLAGS
from .view_support import Started, end, wait_for_url

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
SECONDS = 40.0      # simulated: the line fills up to ~70 bottles
ROUNDS = 3
VIEW_FROM = 20.0    # s of the plant before the first turn: about 70 bottles on the line by then
VIEW_TURN = 8.0     # s of plant time per turn: 3–5 s of wall time
VIEW_WARM = 1.5     # s of plant time run unmeasured after a viewer joined, before its turn
VIEW_ROUNDS = 3     # each round: a turn with no viewer, with `planthub view`, with a page on it
VIEWERS = ("no viewer", "planthub view, no browser", "planthub view and a headless chromium page")
PAGE = {"width": 1280, "height": 800}
HELD = 2.0          # wall s the page's frames are counted with the plant held, after its turn


def _bottle_ids(scenario) -> list[str]:
    return [ident for spec in scenario.objects if spec.module is Source
            for ident, _ in Source.bottles(spec.name, spec.params, scenario.run.seed)]


def _timed_run(overrides: dict, out: Path) -> tuple[float, int]:
    """Wall µs per communication point of one run, and its points."""
    scenario = load_scenario(PLANT, {"run.duration": SECONDS, **overrides})
    with Run(scenario, out=out) as run:
        started = time.perf_counter()
        result = run.run()
        wall = time.perf_counter() - started
    points = result.ticks // scenario.run.substeps
    return 1e6 * wall / points, points


def body_recording() -> None:
    print(f"\n## Recording every body: the bottling plant, 0–{SECONDS:g} s, {ROUNDS} rounds taking turns\n")
    base = load_scenario(PLANT)
    ids = _bottle_ids(base)
    as_csv = [f"{i}.body.{slot}" for i in ids for slot in ("position", "orientation")]
    variants = {
        "no bodies recorded": {},
        "bodies.arrows (run.record_bodies: true)": {"run.record_bodies": True},
        f"recording.csv with {len(ids)} bottles' position and orientation": {"record": list(base_record(base)) + as_csv},
    }
    samples = {name: [] for name in variants}
    sizes = {}
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(ROUNDS):
            for k, (name, overrides) in enumerate(variants.items()):
                out = Path(tmp) / f"{round_}_{k}"
                us, points = _timed_run(overrides, out)
                samples[name].append(us)
                sizes[name] = sum(f.stat().st_size for f in out.iterdir()
                                  if f.name in ("bodies.arrows", "recording.csv"))
    floor = statistics.median(samples["no bodies recorded"])
    print("| recorded | µs per point (median) | ratio to none | bodies.arrows + recording.csv, MB per 100 s simulated |")
    print("|---|---:|---:|---:|")
    for name, values in samples.items():
        mb = sizes[name] / 1e6 * (100.0 / SECONDS)
        print(f"| {name} | {statistics.median(values):.0f} | {statistics.median(values) / floor:.3f} | {mb:.1f} |")


def base_record(scenario) -> list[str]:
    return [f"{ref}" for ref, _ in scenario.record]


def cpu_seconds(pids) -> float:
    """CPU seconds (user and system, from /proc) the processes `pids` used so far; gone ones count 0."""
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / os.sysconf("SC_CLK_TCK")


def machine_cores() -> tuple[float, float]:
    """CPU seconds the machine's cores were idle and stolen by the hypervisor so far (/proc/stat)."""
    with open("/proc/stat") as f:
        fields = [int(v) for v in f.readline().split()[1:]]
    return (fields[3] + fields[4]) / os.sysconf("SC_CLK_TCK"), fields[7] / os.sysconf("SC_CLK_TCK")


def session_pids(sid: int) -> list[int]:
    """The processes of session `sid` now (a browser's renderer and GPU processes come and go)."""
    pids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid:
                pids.append(int(entry))
    return pids


class ViewProcess:
    """`planthub view RUN --connect ENDPOINT --port 0` in a session of its own, as an operator starts
    it in another terminal; ended with SIGTERM (then SIGKILL) and reaped."""

    def __init__(self, folder: Path, run: str, endpoint: str, name: str):
        out, err = folder / f"{name}.out", folder / f"{name}.err"
        with open(out, "w") as o, open(err, "w") as e:
            proc = subprocess.Popen([sys.executable, "-m", "hub", "view", run, "--connect", endpoint, "--port", "0",
                                     "--name", name], cwd=ROOT, stdout=o, stderr=e,
                                    stdin=subprocess.DEVNULL, start_new_session=True,
                                    env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.started = Started(proc, out, err)
        try:
            self.url = wait_for_url(self.started, 60.0)
        except BaseException:
            self.close()
            raise

    def cpu(self) -> float:
        return cpu_seconds([self.started.proc.pid])

    def close(self) -> None:
        end(self.started.proc)


class Chromium:
    """Debian's chromium, headless, in a session of its own (a browser on the operator's desktop,
    not a child of the hub's terminal), driven by Playwright over its DevTools socket; pages open
    and close per turn. Its CPU is that of every process in its session."""

    def __init__(self, folder: Path, playwright):
        self.err = folder / "chromium.err"
        with open(self.err, "w") as e:
            self.proc = subprocess.Popen([CHROMIUM, *FLAGS, "--remote-debugging-port=0",
                                          f"--user-data-dir={folder / 'chromium-profile'}", "about:blank"],
                                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=e,
                                         start_new_session=True)
        try:
            address = self._devtools(30.0)
            self.browser = playwright.chromium.connect_over_cdp(address, timeout=30_000)
        except BaseException:
            self.close()
            raise

    def _devtools(self, timeout: float) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = re.search(r"DevTools listening on (ws://\S+)", self.err.read_text())
            if found:
                return found.group(1)
            if self.proc.poll() is not None:
                break
            time.sleep(0.1)
        raise RuntimeError(f"{CHROMIUM} gave no DevTools address within {timeout:g} s:\n{self.err.read_text()}")

    def open(self, url: str):
        """A page on the view, once it has drawn the scene and a few frames (shaders compiled)."""
        page = self.browser.contexts[0].new_page()
        try:
            page.set_viewport_size(PAGE)
            page.goto(url, timeout=60_000)
            page.wait_for_function("window.planthub && window.planthub.connected && window.planthub.scene "
                                   "&& window.planthub.frames > 10", timeout=60_000)
        except BaseException:
            page.close()
            raise
        return page

    def cpu(self) -> float:
        return cpu_seconds(session_pids(self.proc.pid))

    def settle(self, most: float = 15.0) -> None:
        """Wait until chromium falls idle (started, or a page closed), so that no turn pays for it."""
        deadline, used = time.monotonic() + most, self.cpu()
        while time.monotonic() < deadline:
            time.sleep(0.5)
            now = self.cpu()
            if (now - used) / 0.5 < 0.05:
                return
            used = now

    def close(self) -> None:
        try:
            if getattr(self, "browser", None) is not None:
                self.browser.close()
        finally:
            end(self.proc)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.proc.pid, signal.SIGKILL)   # a helper process chromium left behind


class Stopwatch:
    """Wall time the hub's loop spends in some methods (the view's feed: Broadcast.observe and the data
    plane's publish), summed: what a viewer costs the hub's own thread, apart from the machine."""

    def __init__(self, *methods):
        self.seconds = 0.0
        for owner, name in methods:
            setattr(owner, name, self._timed(getattr(owner, name)))

    def _timed(self, method):
        clock = time.perf_counter

        def timed(*args, **kwargs):
            started = clock()
            try:
                return method(*args, **kwargs)
            finally:
                self.seconds += clock() - started
        return timed


def message_cost(run, repeats: int = 200) -> tuple[float, float, int]:
    """The hub's own cost of one bodies message now, µs: all of it (state, looks, msgpack) and the
    looks' part; and the bodies in it."""
    view = run.link.view
    tick = run.tick
    rows = view.world.scene_state().rows.tolist()
    started = time.perf_counter()
    for _ in range(repeats):
        wire.pack(view.message(tick))
    whole = (time.perf_counter() - started) / repeats
    started = time.perf_counter()
    for _ in range(repeats):
        for look in view.looks:
            look.look(rows)
    looks = (time.perf_counter() - started) / repeats
    return 1e6 * whole, 1e6 * looks, len(rows)


def viewed_plant() -> None:
    if not BUNDLE.is_file():
        raise SystemExit(f"no {BUNDLE}: build the front-end with `make view-assets`")
    print(f"\n## The bottling plant viewed: {', '.join(VIEWERS)}\n")
    print(f"scenarios/bottling_plant.yaml with the routing in the hub (`objects.control.runs: hub`) in this "
          f"process, on the bus as `planthub run --listen` puts it, from {VIEW_FROM:g} s on: {VIEW_ROUNDS} rounds "
          f"of turns of {VIEW_TURN:g} s of plant time with no viewer, with `planthub view` connected (its bodies, "
          f"events, figures and belt speeds relayed to nobody) and with a {PAGE['width']}×{PAGE['height']} page of "
          "it open in headless chromium (software WebGL), in one run; a last turn without a viewer closes the "
          "rounds. The view and chromium each run in a session of their own, as an operator starts them. Before "
          f"a turn with a viewer the plant runs {VIEW_WARM:g} s unmeasured once it joined. Real-time factor: "
          "median of the turns; ratio: median over the rounds of each turn against the mean of the turns without "
          "a viewer before and after its round (the plant grows slower as it fills), lowest–highest in brackets; "
          "the hub's feed: the share "
          "of wall time its loop spent in the view's broadcast and the data plane's publishing; CPU in cores over "
          "the turn, the hub's of all its threads (chromium, started once, has only a blank page open outside "
          "the page's turns), and the machine's cores idle and stolen by the hypervisor; the page's frames per "
          f"second of wall time over the turn and over {HELD:g} s after it with the plant held (the machine to "
          "itself), and the bottles it drew at the turn's end (of the 150 in the scene).\n")
    turns_end = VIEW_FROM + VIEW_ROUNDS * (len(VIEWERS) * VIEW_TURN + 2 * VIEW_WARM + 10.0) + VIEW_TURN + 10.0
    scenario = load_scenario(PLANT, {"objects.control.runs": "hub", "run.duration": turns_end})
    rate = scenario.run.physics_rate
    turns = {kind: [] for kind in VIEWERS}
    costs = []
    bus = Bus(BusSettings())
    try:
        with tempfile.TemporaryDirectory() as tmp, Run(scenario, bus=bus) as run:
            from playwright.sync_api import sync_playwright

            run.start()
            run.run(until_tick=round(VIEW_FROM * rate))
            broadcast, endpoint = run.link.view, bus.endpoints[0]
            feed = Stopwatch((broadcast, "observe"), (run.link.dataplane, "publish"))

            def warm(joined) -> None:
                """Run until the viewer is served (`joined()`), then VIEW_WARM s more: not measured."""
                limit = run.tick + round(10.0 * rate)
                while not joined() and run.tick < limit:
                    run.run(until_tick=run.tick + scenario.run.substeps)
                run.run(until_tick=run.tick + round(VIEW_WARM * rate))

            def turn(kind: str, view=None, chromium=None, page=None) -> None:
                sent, own, fed, machine = broadcast.sent, time.process_time(), feed.seconds, machine_cores()
                cpu = [p.cpu() if p is not None else 0.0 for p in (view, chromium)]
                frames = page.evaluate("window.planthub.frames") if page is not None else 0
                began = time.perf_counter()
                run.run(until_tick=run.tick + round(VIEW_TURN * rate))
                wall = time.perf_counter() - began
                if run.stopped_by:
                    raise RuntimeError(f"the plant ended before the benchmark did: {run.stopped_by}")
                own = time.process_time() - own
                idle, steal = (b - a for a, b in zip(machine, machine_cores()))
                cpu = [(p.cpu() - c) / wall if p is not None else None for p, c in zip((view, chromium), cpu)]
                fps = drawn = held = None
                if page is not None:
                    fps = (page.evaluate("window.planthub.frames") - frames) / wall
                    drawn = page.evaluate("Object.keys(window.planthub.bodies()).length")
                    frames, began = page.evaluate("window.planthub.frames"), time.perf_counter()
                    time.sleep(HELD)   # the plant held: the page draws its last sample with the machine to itself
                    held = (page.evaluate("window.planthub.frames") - frames) / (time.perf_counter() - began)
                turns[kind].append((VIEW_TURN / wall, (broadcast.sent - sent) / VIEW_TURN, own / wall, *cpu,
                                    fps, drawn, (feed.seconds - fed) / wall, own / VIEW_TURN, held,
                                    idle / wall, steal / wall))

            with sync_playwright() as playwright:
                chromium = Chromium(Path(tmp), playwright)
                try:
                    chromium.settle()
                    for round_ in range(VIEW_ROUNDS):
                        turn(VIEWERS[0], chromium=chromium)
                        view = ViewProcess(Path(tmp), scenario.name, endpoint, f"bench-view-{round_}")
                        try:
                            sent = broadcast.sent
                            warm(lambda: broadcast.sent > sent)
                            turn(VIEWERS[1], view, chromium)
                            costs.append(message_cost(run))
                            page = chromium.open(view.url)
                            try:
                                tick = run.tick
                                warm(lambda: page.evaluate("window.planthub.tick") > tick)
                                turn(VIEWERS[2], view, chromium, page)
                            finally:
                                page.close()
                        finally:
                            view.close()
                        chromium.settle()
                    turn(VIEWERS[0], chromium=chromium)
                finally:
                    chromium.close()
    finally:
        bus.close()
    print("| viewer | real-time factor | ratio to none | bodies messages per plant s | hub's feed, % of wall "
          "| hub's CPU | hub's CPU ms per plant s | view's CPU | chromium's CPU | idle, stolen | page frames/s "
          "| held | bottles drawn |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    none = turns[VIEWERS[0]]
    shown = lambda v, fmt: "—" if v is None else fmt.format(v)
    for kind in VIEWERS:
        t = turns[kind][:VIEW_ROUNDS]
        med = lambda k: None if t[0][k] is None else statistics.median(x[k] for x in t)
        ratios = [1.0] if kind == VIEWERS[0] else [x[0] / ((a[0] + b[0]) / 2) for x, a, b in zip(t, none, none[1:])]
        ratio = f"{statistics.median(ratios):.3f}" + ("" if kind == VIEWERS[0] else
                                                      f" ({min(ratios):.2f}–{max(ratios):.2f})")
        print(f"| {kind} | {med(0):.2f}× | {ratio} | {med(1):.1f} | {100 * med(7):.1f} | {med(2):.2f} "
              f"| {1000 * med(8):.0f} | {shown(med(3), '{:.2f}')} | {shown(med(4), '{:.2f}')} "
              f"| {med(10):.2f}, {med(11):.2f} | {shown(med(5), '{:.1f}')} | {shown(med(9), '{:.1f}')} "
              f"| {shown(med(6), '{:.0f}')} |", flush=True)
    whole, looks, bodies = (statistics.median(c[k] for c in costs) for k in range(3))
    print(f"\nThe hub's own cost of one bodies message ({bodies:.0f} bodies in play, median of the rounds): "
          f"{whole:.0f} µs, of it {looks:.0f} µs the bottles' fill and destination (modules/plant/look.py).")


PARTS = {"recording": body_recording, "viewed": viewed_plant}


def main(parts: list[str]) -> int:
    unknown = set(parts) - set(PARTS)
    if unknown:
        raise SystemExit(f"unknown part {', '.join(sorted(unknown))}: give {' and/or '.join(PARTS)}")
    for name in parts or PARTS:   # e.g. `python -m tests.bench_view viewed`
        PARTS[name]()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
