"""Watchers cannot slow the plant: the step loop hands points to the data plane's sender and never
waits for it; what the sender cannot send is skipped, counted, and told by the ticks; events are
kept; the recording is the same whoever watches.

    step loop ── offer(point) ──► outbox ── lent slices ──► sender thread ── put ──► viewers
               (skipped while the sender is busy)            (stuck in a put: no more slices)
"""
import csv
import os
import signal
import subprocess
import sys
import threading

import pytest

from hub.bus import outbox
from hub.bus.session import Bus, wait_until
from hub.bus.settings import BusSettings
from hub.live import Viewer

from .bus_support import BELT_FMU, hub, resumed_at_exit, same_files
from .dataplane_support import settle
from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario

RUN = "belt_ramp_fmu"
STOP = ROOT / "scenarios" / "stop_at_barrier.yaml"   # bottle body slots: computed only while watched


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


@pytest.fixture
def bus():
    with Bus(BusSettings()) as bus:
        yield bus


def recorded(path, column):
    with open(path / "recording.csv", newline="") as f:
        return {round(float(r["time"]) * 150): float(r[column]) for r in csv.DictReader(f)}


def samples(viewer, quiet=1.0):
    out = []
    while (sample := viewer.next(quiet)) is not None:
        out.append(sample)
    return out


def test_a_sender_stuck_in_a_put_holds_the_loop_back_not_at_all(bus, tmp_path):
    """The first put does not return until the test lets it: the run goes on all the same, every
    point after the first is skipped and counted, the event that fired meanwhile is kept, and once
    the put returns the viewer gets the first and the last point, each with its own tick."""
    with hub(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as viewer:
        master.start()
        viewer.watch("drive/logic/speed")
        viewer.watch("barrier/trigger/on_enter")
        plane = master.dataplane
        settle(master, lambda: len(plane.live) == 2)
        stuck, release = threading.Event(), threading.Event()
        speed = next(e for e in plane.exposed if str(e.ref) == "drive.logic.speed")
        real_put = speed.put

        def put(payload, attachment=None):
            stuck.set()
            release.wait(30)
            real_put(payload, attachment=attachment)
        speed.put = put
        master.run(until_tick=3)             # the points at ticks 0 and 3: the first is handed over
        assert not plane.outbox.flush(0.2)   # a slice: the sender takes it and is stuck in the put
        assert stuck.is_set()
        result = master.run(until_tick=897)
        assert result.ticks == 894 and plane.skipped == 299   # every point after the first, to 897
        release.set()
        assert plane.outbox.flush(5.0)
        master.run()                         # the last point, 900, and the end of the run
        got = samples(viewer)
    speeds = [(s.tick, s.value) for s in got if s.slot == "drive.logic.speed"]
    recording = recorded(tmp_path, "drive.logic.speed")
    assert speeds == [(0, recording[0]), (900, recording[900])]
    assert plane.skipped == 299
    with open(tmp_path / "events.csv", newline="") as f:
        enter = [round(float(r["time"]) * 150) for r in csv.DictReader(f) if r["slot"] == "barrier.trigger.on_enter"]
    point = -(-enter[0] // 3) * 3   # the point that reported it (a point every 3 ticks)
    assert len(enter) == 1 and [s.tick for s in got if s.slot == "barrier.trigger.on_enter"] == [point]


def test_under_load_every_value_comes_with_the_tick_of_its_point(bus, tmp_path):
    """No waiting here: the loop runs as fast as it can and the sender takes what its slices
    allow. Whatever arrives is a value of the recording at the tick it carries, the last point
    arrives, and what was sent and what was skipped add up to the points."""
    with hub(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as viewer:
        master.start()
        viewer.watch("drive/logic/speed")
        settle(master, lambda: len(master.dataplane.live) == 1)
        master.run()
        sent, skipped = master.dataplane.samples, master.dataplane.skipped
        got = samples(viewer)
    recording = recorded(tmp_path, "drive.logic.speed")
    assert [(s.tick, s.value) for s in got] == [(s.tick, recording[s.tick]) for s in got]
    assert got[0].tick == 0 and got[-1].tick == 900
    assert sent == len(got) and sent + skipped == len(recording) == 301


def test_the_sending_budget_is_shared_among_the_viewers(bus):
    with hub(BELT_FMU, bus=bus) as master, Viewer(RUN, bus.endpoints) as a, Viewer(RUN, bus.endpoints) as b:
        master.start()
        settle(master, lambda: master.dataplane.viewers == {a.id, b.id})
        assert master.dataplane.outbox.share == 2
        b.close()
        settle(master, lambda: master.dataplane.viewers == {a.id})
        assert master.dataplane.outbox.share == 1


def test_events_beyond_the_bound_are_counted_as_lost():
    """The events kept for the next point are bounded: a sender that takes no point for long cannot
    make the loop's memory grow; those kept go out when it does."""
    class Event:
        sent = 0

        def put(self, payload, attachment=None):
            Event.sent += 1

    box = outbox.Outbox(on_change=False)
    fired = [Event()] * 1000
    for tick in range(5):
        box.offer(tick, None, (), fired)
    box.close()
    assert box.events_lost == 5 * 1000 - outbox.MAX_EVENTS
    assert Event.sent == outbox.MAX_EVENTS


@pytest.fixture
def watchers(bus):
    """Twenty watcher processes (tests/participants/watcher.py) on plant/stop_at_barrier/**."""
    launcher = subprocess.Popen([sys.executable, "-m", "tests.participants.watcher", "stop_at_barrier",
                                 bus.endpoints[0], "20"], cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                text=True)
    try:
        pids = [int(p) for p in launcher.stdout.readline().split()]
        launcher.stdin.write("watch 20\n")
        launcher.stdin.flush()
        assert launcher.stdout.readline().strip() == "watching"
        yield pids
    finally:
        launcher.stdin.close()
        try:
            launcher.wait(30)
        except subprocess.TimeoutExpired:
            launcher.kill()
            launcher.wait()


def test_the_recording_is_the_same_whoever_watches(bus, watchers, tmp_path):
    """Twenty watcher processes on plant/**, one of them stopped (SIGSTOP) so that it reads
    nothing: every body slot of the bottle is computed while they watch, samples go out and are
    skipped, and recording.csv and events.csv are those of a run nobody watched, byte for byte."""
    run_scenario(STOP, tmp_path / "alone")
    os.kill(watchers[0], signal.SIGSTOP)
    with resumed_at_exit(watchers[0]):
        with hub(STOP, tmp_path / "watched", bus=bus) as master:
            master.start()
            plane = master.dataplane
            assert wait_until(lambda: (plane.update(), len(plane.live) == len(plane.exposed))[1], 30)
            assert wait_until(lambda: (plane.update(), len(plane.viewers) == 20)[1], 30)
            result = master.run()
            assert master.plant.components and result.ticks == 750
            sent = plane.samples
        os.kill(watchers[0], signal.SIGCONT)
    assert sent > 0
    assert same_files(tmp_path / "alone", tmp_path / "watched")
