"""Live participants: a viewer watches slots by key expression (published only while watched, at the
rate it asked for); an operator command is applied at the next point, recorded, and replayed bit for bit.
The runs that compare every sample with the recording go at the data plane's pace (EveryPoint); what
the sender skips under load: tests/test_watchers.py.

    hub ── plant/<run>/drive/logic/speed ──► viewer
    hub ◄── plant/<run>/@cosim/command ───── operator (set drive.logic.speed_setpoint 0.3)
"""
import csv

import pytest

from hub.bus.commands import CommandError, Commands
from hub.bus.session import Bus, wait_until
from hub.bus.settings import BusSettings
from hub.core.slots import SlotType
from hub.live import Viewer
from hub.run.plant import Plant
from hub.run.recorder import Recorder
from hub.scenario.checker import load_scenario

from .bus_support import BELT_FMU, hub, same_files
from .dataplane_support import every_point, settle
from .fmus.fmu_support import build
from .helpers import ROOT

RUN = "belt_ramp_fmu"
STOP = ROOT / "scenarios" / "stop_at_barrier.yaml"   # records the bottle's position, not its velocity


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


@pytest.fixture
def bus():
    with Bus(BusSettings()) as bus:
        yield bus


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def samples_until(viewer, last_tick, slot=None):
    """Samples up to the one at `last_tick` (of `slot`, if given); fails after 5 s without one."""
    out = []
    while not out or out[-1].tick < last_tick or (slot and out[-1].slot != slot):
        sample = viewer.next(5.0)
        assert sample is not None, f"no sample after tick {out[-1].tick if out else None}"
        out.append(sample)
    return out


def test_a_viewer_gets_every_point_of_the_slot_it_watches_and_nothing_else_is_sent(bus, tmp_path):
    with every_point(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as viewer:
        master.start()
        viewer.watch("drive/logic/speed")
        settle(master, lambda: len(master.dataplane.live) == 1)
        master.run()
        samples = samples_until(viewer, 900)
        published = master.dataplane.samples
    recorded = [(round(float(r["time"]) * 150), float(r["drive.logic.speed"])) for r in rows(tmp_path / "recording.csv")]
    assert [(s.tick, s.value) for s in samples] == recorded
    assert {s.slot for s in samples} == {"drive.logic.speed"}
    assert published == len(recorded) == 301   # 40 exposed slots, one watched


def test_a_viewer_asks_for_a_slower_rate(bus):
    with every_point(BELT_FMU, bus=bus) as master, Viewer(RUN, bus.endpoints) as viewer:
        master.start()
        viewer.watch("drive/logic/*", period=0.1)
        settle(master, lambda: len(master.dataplane.live) == 4 and master.dataplane.requests)   # inputs too
        master.run()
        samples = samples_until(viewer, 885, "drive.logic.speed")
    speed_ticks = [s.tick for s in samples if s.slot == "drive.logic.speed"]
    assert speed_ticks == list(range(0, 900, 15))   # every 0.1 s = every fifth point of 20 ms


def test_an_event_is_sent_whenever_it_fires_whatever_the_rate(bus):
    """Not at the data plane's pace: an event at a point the sender skipped goes out with the next."""
    with hub(STOP, bus=bus) as master, Viewer("stop_at_barrier", bus.endpoints) as viewer:
        master.start()
        viewer.watch("barrier/trigger/*", period=100.0)
        settle(master, lambda: master.dataplane.requests and len(master.dataplane.live) > 2)
        master.run()
        events = []
        while (sample := viewer.next(1.0)) is not None:
            if sample.slot == "barrier.trigger.on_enter":
                events.append(sample)
    assert len(events) == 1 and events[0].value is None and events[0].tick > 0


def test_a_body_slot_is_computed_only_while_someone_watches_it(bus):
    with every_point(STOP, bus=bus) as master:
        bottle = next(c for c in master.plant.components if (c.obj, c.name) == ("bottle", "body"))
        master.start()
        assert "velocity" not in bottle.needed
        with Viewer("stop_at_barrier", bus.endpoints) as viewer:
            viewer.watch("bottle/body/velocity")
            settle(master, lambda: "velocity" in bottle.needed)
            master.run(until_tick=150)
            moving = samples_until(viewer, 150)[-1]
        settle(master, lambda: "velocity" not in bottle.needed)
    assert moving.value[0] > 0.4   # the belt pushes it along x at about its speed, 0.5 m/s


def test_a_live_command_is_applied_at_the_next_point_recorded_and_replayed_bit_for_bit(bus, tmp_path):
    live, replay = tmp_path / "live", tmp_path / "replay"
    with hub(BELT_FMU, live, bus=bus) as master, Viewer(RUN, bus.endpoints) as operator:
        master.run(until_tick=150)
        operator.wait_for_hub()
        ident = operator.command("set", "drive.logic.speed_setpoint", 0.3, by="hmi", wait=None)
        assert wait_until(master.commands.pending, 5.0)
        master.run()
        answer = operator.answer(ident, 5.0)
    assert answer == {"id": ident, "ok": True, "tick": 153, "error": ""}
    assert (live / "commands.csv").read_text() == "time,tick,op,slot,value,by\n1.02,153,set,drive.logic.speed_setpoint,0.3,hmi\n"
    assert "1.02,153,drive.logic.speed_setpoint,set 0.3 by hmi" in (live / "events.csv").read_text()
    speeds = [float(r["drive.logic.speed"]) for r in rows(live / "recording.csv")]
    assert speeds[50] == 0.5 and speeds[80] == 0.3   # ramped to 0.5, then down to the new setpoint

    with hub(BELT_FMU, replay, replay=live) as master:   # no bus: the commands come from the recording
        master.run()
    assert same_files(live, replay, ("recording.csv", "events.csv", "commands.csv"))


def test_a_stop_command_ends_the_run_and_the_replay_ends_at_the_same_tick(bus, tmp_path):
    with hub(BELT_FMU, tmp_path / "live", bus=bus) as master, Viewer(RUN, bus.endpoints) as operator:
        master.run(until_tick=30)
        ident = operator.command("stop", by="operator", wait=None)
        assert wait_until(master.commands.pending, 5.0)
        result = master.run()
        assert operator.answer(ident, 5.0)["tick"] == 33
    assert result.stopped_by == "stopped by an operator at t = 0.22 s"
    with hub(BELT_FMU, tmp_path / "replay", replay=tmp_path / "live") as master:
        assert master.run().stopped_by == "stopped by an operator at t = 0.22 s"
    assert same_files(tmp_path / "live", tmp_path / "replay")


def test_a_refused_command_is_answered_and_changes_nothing(bus, tmp_path):
    with hub(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as operator:
        master.run(until_tick=30)
        ident = operator.command("set", "drive.logic.sped", 1.0, wait=None)
        assert wait_until(master.commands.pending, 5.0)
        master.run(until_tick=60)
        answer = operator.answer(ident, 5.0)
    assert answer["ok"] is False
    assert answer["error"] == "no slot 'drive.logic.sped' (did you mean 'drive.logic.speed'?)"
    assert not (tmp_path / "commands.csv").exists()


@pytest.fixture(scope="module")
def commands():
    scenario = load_scenario(ROOT / "scenarios" / "stop_at_barrier.yaml")
    with Plant(scenario) as plant:
        yield Commands(plant, Recorder([], 150))


@pytest.mark.parametrize("message, error", [
    ({"op": "set", "slot": "belt.drive.sped", "value": 1.0}, "no slot 'belt.drive.sped' (did you mean 'belt.drive.speed'?)"),
    ({"op": "set", "slot": "belt.drive.speed", "value": "fast"}, "belt.drive.speed is real: expected a finite number, got 'fast'"),
    ({"op": "force", "slot": "belt.drive.run", "value": 1}, "belt.drive.run is bool: expected true or false, got 1"),
    ({"op": "set", "slot": "stop.value.set"}, "stop.value.set is read by its own component within the step; "
                                               "command the slot that feeds it instead"),
    ({"op": "freeze"}, "expected a map with op one of set, force, release, stop, pause, resume, step, pace, checkpoint, rewind, fault, repair, got {'op': 'freeze'}"),
])
def test_bad_commands_are_named(commands, message, error):
    with pytest.raises(CommandError) as info:
        commands.parse(message)
    assert str(info.value) == error



def test_a_slot_watched_while_a_point_without_it_is_under_way_goes_out_after_it(bus):
    """The sender's next due tick follows the slots watched now: a slot that was cold (computed
    only once watched) is left out of the point under way, its first point is skipped while that
    one is sent, and it must go out at the next. (It once took its due tick from the point under
    way, which held no slot, and never offered another.)"""
    from hub.bus.dataplane import _Exposed
    from hub.bus.outbox import Outbox
    from hub.core.slots import SlotRef

    viewer = Bus(BusSettings(mode="client", connect=bus.endpoints), listen=False)
    got = []
    try:
        viewer.subscribe("plant/x/belt/drive/velocity", got.append)
        publisher = bus.publisher("plant/x/belt/drive/velocity", "planthub/real", lossy=True)
        assert wait_until(lambda: publisher.matching, 5)
        entry = _Exposed(SlotRef("belt", "drive", "velocity"), publisher.key, 0, SlotType.REAL, publisher, None)
        outbox = Outbox(on_change=False)
        try:
            assert outbox.offer(3, [0.5], (), ())                  # the slot was cold at this point
            assert not outbox.offer(6, [0.5], (entry,), ())        # the sender has not taken the first
            assert outbox.flush(2.0)
            assert outbox.wanted <= 9, "the watched slot is due at the next point"
            assert outbox.offer(9, [0.5], (entry,), ()) and outbox.flush(2.0)
        finally:
            outbox.close()
        assert wait_until(lambda: got, 5), "its sample arrives"
    finally:
        viewer.close()
