"""Live faults: an instructor injects a fault into a running plant on the instructor's key, checked as a
scenario's fault is, recorded in commands.csv and replayed bit for bit; a `fault` on the operators' key
is refused, named; the hub's board of faults goes out on the instructor's key only.

    hub ◄── plant/<run>/@instructor/command ── instructor (fault belt.drive belt_failure for 0.5 s)
    hub ◄── plant/<run>/@cosim/command ─────── operator (fault …: refused, an instructor's)
    stop_at_barrier.yaml:  bottle ─► belt ─[barrier]   (the barrier stops the belt)
"""
import csv

from hub.bus import wire
from hub.bus.session import Bus, Inbox, wait_until
from hub.bus.settings import BusSettings
from hub.live import Viewer

from .bus_support import hub, same_files
from .helpers import ROOT

STOP = ROOT / "scenarios" / "stop_at_barrier.yaml"
RUN = "stop_at_barrier"
SLOW = {"name": "slow", "kind": "belt_failure", "speed": 0.2, "for": 0.5}


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_an_instructors_fault_is_applied_recorded_ended_after_its_duration_and_replayed_bit_for_bit(tmp_path):
    live, replay = tmp_path / "live", tmp_path / "replay"
    record = {"record": ["bottle.body.position", "belt.drive.running", "belt.drive.speed"]}
    with Bus(BusSettings()) as bus, hub(STOP, live, record, bus=bus) as master, \
            Viewer(RUN, bus.endpoints) as instructor:
        master.run(until_tick=30)
        ident = instructor.command("fault", "belt.drive", SLOW, by="instructor", wait=None, instructor=True)
        assert wait_until(master.commands.pending, 5.0)
        master.run()
        answer = instructor.answer(ident, 5.0)
        faults = [s for s in master.summary().sections if s.key == "faults"]
    assert answer == {"id": ident, "ok": True, "tick": 33, "error": ""}
    assert [(f.name, f.target, f.start, f.end) for f in faults[0].started] == [("slow", "belt.drive", 33, 108)]
    commands = [(r["tick"], r["op"], r["slot"], r["value"], r["by"]) for r in rows(live / "commands.csv")]
    assert commands == [
        ("33", "fault", "belt.drive", '{"name": "slow", "kind": "belt_failure", "speed": 0.2, "for": 0.5}',
         "instructor"),
        ("108", "repair", "belt.drive", '{"name": "slow"}', "instructor")]   # 0.5 s = 75 ticks later
    events = [(r["tick"], r["slot"], r["detail"]) for r in rows(live / "events.csv")]
    assert events[:2] == [
        ("33", "@fault", 'fault {"name": "slow", "kind": "belt_failure", "speed": 0.2, "for": 0.5} by instructor'),
        ("108", "@fault", 'repair {"name": "slow"} by instructor')]

    with hub(STOP, replay, record, replay=live) as master:   # no bus: the recorded commands do it all
        master.run()
    assert same_files(live, replay, ("recording.csv", "events.csv", "commands.csv"))


def test_a_fault_on_the_operators_key_is_refused_and_a_bad_one_is_named(tmp_path):
    with Bus(BusSettings()) as bus, hub(STOP, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as someone:
        sent = [("fault", "belt.drive", SLOW, False),
                ("fault", "belt.drive", {"name": "x", "kind": "sensor_stuck", "value": True}, True),
                ("fault", "barier.trigger", {"name": "y", "kind": "sensor_stuck", "value": True}, True),
                ("fault", "barrier.trigger", {"name": "z", "kind": "sensor_stuck", "value": True, "for": -1}, True)]
        answers, tick = [], 15
        for op, slot, value, instructor in sent:   # one at a time: each is answered at its own point
            master.run(until_tick=tick)
            ident = someone.command(op, slot, value, wait=None, instructor=instructor)
            assert wait_until(master.commands.pending, 5.0)
            tick += 15
            master.run(until_tick=tick)
            answers.append(someone.answer(ident, 5.0))
    assert [a["ok"] for a in answers] == [False] * 4
    assert answers[0]["error"] == ("fault: faults are an instructor's: put it on plant/<run>/@instructor/command "
                                   "(under run.bus.access, with a certificate named in access.instructor)")
    assert answers[1]["error"] == ("fault x: belt.drive is not a sensor (a volume trigger: on_enter and occupied), "
                                   "which sensor_stuck needs")
    assert answers[2]["error"] == "fault y: unknown object 'barier' (did you mean 'barrier'?)"
    assert answers[3]["error"] == "fault z: `for` is how long it lasts, s: above 0 and at most 86400, got -1"
    assert not (tmp_path / "commands.csv").exists()


def test_the_board_of_faults_goes_out_on_the_instructors_key_and_no_fault_row_on_the_public_events(tmp_path):
    with Bus(BusSettings()) as bus, hub(STOP, tmp_path, bus=bus) as master, \
            Viewer(RUN, bus.endpoints) as instructor, Bus(BusSettings(connect=tuple(bus.endpoints)),
                                                          listen=False) as watcher:
        board, public, private = Inbox(), Inbox(), Inbox()
        watcher.subscribe_payloads(wire.instructor_key(RUN, "faults"), board.put)
        watcher.subscribe_payloads(wire.control_key(RUN, "events"), public.put)
        watcher.subscribe_payloads(wire.instructor_key(RUN, "events"), private.put)
        master.run(until_tick=15)
        instructor.command("fault", "belt.drive", {"name": "slow", "kind": "belt_failure", "speed": 0.5},
                           wait=None, instructor=True)
        assert wait_until(master.commands.pending, 5.0)
        master.run()   # the bottle reaches the barrier, later: a public event
        assert wait_until(lambda: not board.empty(), 5.0)
        boards = [wire.unpack(p) for p in board.drain()]
        private_rows = [r for p in private.drain() for r in wire.unpack(p)]
        public_rows = [r for p in public.drain() for r in wire.unpack(p)]
    last = boards[-1]
    assert last["kinds"]["sensor_stuck"]["targets"] == ["barrier.trigger"]
    assert last["kinds"]["belt_failure"]["targets"] == ["belt.drive"]
    assert last["active"] == [{"name": "slow", "kind": "belt_failure", "target": "belt.drive",
                               "parameters": {"speed": 0.5}, "until": None}]
    assert [r[1] for r in private_rows] == ["@fault"]
    assert public_rows and all(r[1] != "@fault" for r in public_rows)


def test_the_public_figures_hold_no_fault_and_judge_recovery_only_when_the_run_ends(tmp_path):
    """An exercise's `recover_within` measure names the faults: a trainee reads the figures, so until
    the run's last figures (`ended`) the goal says it is judged at the end, and the faults section
    is never there."""
    overrides = {"faults": [{"name": "slow", "kind": "belt_failure", "target": "belt", "speed": 0.5, "at": 1.0}],
                 "exercise": {"task": "Keep the bottles coming.",
                              "goals": [{"delivered": 1}, {"recover_within": 30, "name": "recovered"}]}}
    with Bus(BusSettings()) as bus, hub(ROOT / "scenarios" / "source_sink.yaml", tmp_path, overrides, bus=bus) \
            as master:
        master.run()
        broadcast = master.link.view
        running = broadcast.figures_message(master.tick, 1.0)
        ended = broadcast.figures_message(master.tick, 1.0, ended=True)
        assert "faults" in [s.key for s in master.summary().sections]   # the summary keeps it
    assert "faults" not in running["sections"] and "faults" not in ended["sections"]
    goals = {g["name"]: g for g in running["sections"]["exercise"]["goals"]}
    assert goals["recovered"]["met"] is None and goals["recovered"]["measured"] == "judged when the run ends"
    assert [g["met"] for name, g in goals.items() if name != "recovered"] == [True]   # the others live
    final = {g["name"]: g for g in ended["sections"]["exercise"]["goals"]}
    assert final["recovered"]["met"] is True and final["recovered"]["measured"].startswith("slow: ")


def test_a_run_resumed_from_a_checkpoint_taken_during_a_live_fault_keeps_the_fault(tmp_path, monkeypatch):
    """The plant runs with no fault of its own; an instructor's fault (the belt at a fifth of its
    speed, 33 → 108) is in effect when the checkpoint is taken (60): the run resumed from it keeps
    the fault and ends it at the same tick, and goes on bit for bit. Bottles as multibodies, as
    tests/test_checkpoint.py resumes them bit for bit."""
    from hub.physics.world import PhysicsWorld
    from hub.run import checkpoint

    monkeypatch.setattr(PhysicsWorld, "MAXIMAL", False)
    record = {"record": ["bottle.body.position", "belt.drive.running", "belt.drive.speed"]}
    with Bus(BusSettings()) as bus, hub(STOP, tmp_path / "whole", record, bus=bus) as master, \
            Viewer(RUN, bus.endpoints) as instructor:
        master.run(until_tick=30)
        ident = instructor.command("fault", "belt.drive", SLOW, by="instructor", wait=None, instructor=True)
        assert wait_until(master.commands.pending, 5.0)
        master.run(until_tick=60)
        assert instructor.answer(ident, 5.0)["ok"]
        data = checkpoint.capture(master)
        master.run()
    with Bus(BusSettings()) as bus, hub(STOP, tmp_path / "resumed", record, bus=bus,
                                        resume=(data, "checkpoint")) as resumed:
        resumed.run()
        faults = [s for s in resumed.summary().sections if s.key == "faults"]
    assert [(f.name, f.start, f.end) for f in faults[0].started] == [("slow", 33, 108)]

    def after(name):
        return [r for r in rows(tmp_path / name) if int(r.get("tick") or round(float(r["time"]) * 150)) > 60]

    assert after("resumed/recording.csv") == after("whole/recording.csv")
    assert after("resumed/events.csv") == after("whole/events.csv")
