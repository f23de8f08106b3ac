"""Rewind live: a running plant put back to one of its checkpoints goes on as a run resumed from it, and its replay rewinds alike (hub/run/rewind.py)."""
from __future__ import annotations

import csv
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from hub.bus import wire
from hub.bus.live import Viewer
from hub.bus.lockstep import pid_of
from hub.bus.session import Bus, free_loopback_endpoint
from hub.bus.settings import BusSettings
from hub.physics.world import PhysicsWorld
from hub.run import checkpoint
from hub.run.assembly import Run
from hub.run.pacing import Pacer
from hub.scenario.checker import load_scenario

from .bus_support import process

ROOT = Path(__file__).resolve().parent.parent
SWITCH = ROOT / "scenarios" / "switch.yaml"
PARTICIPANT = ROOT / "scenarios" / "belt_ramp_participant.yaml"
#: what a rewind branches, and what a replay gives again byte for byte
FILES = ("recording.csv", "events.csv", "commands.csv", "recording.branch1.csv", "events.branch1.csv")


@pytest.fixture
def multibody_bottles(monkeypatch):
    """Bottles as one-link multibodies, which a checkpoint puts back bit for bit (tests/test_checkpoint.py)."""
    monkeypatch.setattr(PhysicsWorld, "MAXIMAL", False)


def _after(path: Path, seconds: float) -> list[str]:
    return [line for line in path.read_text().splitlines()[1:] if float(line.split(",")[0].strip('"')) > seconds]


def _rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _resumed(name: Path, settings: dict, saved: Path, out: Path, until: int | None = None) -> None:
    with Run(load_scenario(name, settings), out=out, resume=(checkpoint.read(saved), str(saved))) as resumed:
        resumed.run(until)


def _wait(condition, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def _planthub(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], cwd=ROOT, capture_output=True, text=True,
                          timeout=120)


def test_a_run_rewound_by_planthub_send_goes_on_as_one_resumed_from_its_checkpoint(tmp_path, multibody_bottles):
    """A paced run on the bus with a checkpoint every 0.5 s, rewound from another process to tick
    200: it goes back to its checkpoint at 150 (1 s), and every row and event after it equals those
    of a run resumed from checkpoints/150.ckpt; the branch it left is beside, its checkpoints in
    checkpoints/branch1/; the replay of its commands.csv gives the same files, byte for byte."""
    # 8 s at real time: the rewind, asked at 2 s from another process (its Python's start, the hub's
    # imports, the bus), has 6 s to come on a busy machine
    endpoint, settings, live = free_loopback_endpoint(), {"run.duration": 8.0}, tmp_path / "live"
    end = round(settings["run.duration"] * 150)
    with Bus(BusSettings(listen=(endpoint,))) as bus, \
            Run(load_scenario(SWITCH, settings), out=live, bus=bus, pacer=Pacer(150, factor=1.0),
                checkpoints=((), 75)) as run:
        run.start()
        thread = threading.Thread(target=run.run, daemon=True)
        thread.start()
        _wait(lambda: run.tick >= 300)
        sent = _planthub("send", "switch", "rewind", "200", "--connect", endpoint, "--by", "trainer")
        thread.join(60)
        assert not thread.is_alive()
        with Viewer("switch", [endpoint]) as view:   # the timeline an operator's panel shows
            timeline = wire.unpack(view.bus.ask("plant/switch/@cosim/checkpoints").payload)
        assert timeline["checkpoints"] == list(range(75, end + 1, 75)) and timeline["rate"] == 150
    assert sent.returncode == 0, sent.stderr
    assert sent.stdout.startswith("rewind applied at tick ")
    at = int(sent.stdout.split()[-1])
    assert 300 <= at < end
    assert [(r["op"], int(r["tick"]), r["value"], r["by"]) for r in _rows(live / "commands.csv")] == \
        [("rewind", at, "150", "trainer")]
    rewound = [r for r in _rows(live / "events.csv") if r["slot"] == "@run"]
    assert rewound == [{"time": "1.0", "tick": "150", "slot": "@run", "detail":
                        f"rewind to t = 1 s from t = {at / 150:g} s by trainer; the branch left: "
                        f"recording.branch1.csv, events.branch1.csv"}]
    # The branch left: the rows after the checkpoint up to the rewind, under the file's header.
    branch = (live / "recording.branch1.csv").read_text().splitlines()
    assert branch[0] == (live / "recording.csv").read_text().splitlines()[0]
    assert [round(float(line.split(",")[0]) * 150) for line in branch[1:]] == list(range(151, at + 1))
    assert sorted(int(p.stem) for p in (live / "checkpoints").glob("*.ckpt")) == list(range(75, end + 1, 75))
    assert sorted(int(p.stem) for p in (live / "checkpoints" / "branch1").glob("*.ckpt")) == \
        list(range(225, at + 1, 75))
    # From the checkpoint on, the rewound run is the run resumed from it.
    _resumed(SWITCH, settings, live / "checkpoints" / "150.ckpt", tmp_path / "resumed")
    for name in ("recording.csv", "events.csv"):
        assert _after(live / name, 1.0) == _after(tmp_path / "resumed" / name, 1.0), name
    # Its replay keeps the checkpoint at 150 in memory and rewinds at the same point.
    with Run(load_scenario(SWITCH, settings), out=tmp_path / "replayed", replay=live) as replayed:
        replayed.run()
    for name in FILES:
        assert (tmp_path / "replayed" / name).read_bytes() == (live / name).read_bytes(), name
    assert not (tmp_path / "replayed" / "checkpoints").exists()


def test_a_participant_on_the_bus_is_restored_on_a_rewind_while_the_run_is_paused(tmp_path, multibody_bottles):
    """The ramp's logic served by a launched participant: rewound while paused (at once, the run
    still held), the same process is handed its state at the checkpoint over the bus, and the run
    goes on as one resumed from it."""
    live = tmp_path / "live"
    with Bus(BusSettings()) as bus, \
            Run(load_scenario(PARTICIPANT), out=live, bus=bus, checkpoints=((300,), None)) as run, \
            Viewer("belt_ramp_participant", bus.endpoints) as operator:
        run.start()
        slave = next(c.slave for c in run.plant.components if getattr(getattr(c, "slave", None), "on_bus", False))
        pid = pid_of(slave)
        run.run(600)
        paused = operator.command("pause", wait=None)
        _wait(run.commands.pending)
        thread = threading.Thread(target=run.run, daemon=True)
        thread.start()
        assert operator.answer(paused, 10)["ok"]
        answer = operator.command("rewind", value=450, by="trainer", wait=10)
        assert answer["ok"], answer
        _wait(lambda: run.tick == 300)   # back at once, still held
        assert pid_of(slave) == pid is not None   # the same process, handed its state at 300
        assert operator.command("resume", wait=10)["ok"]
        thread.join(60)
        assert not thread.is_alive()
    assert [(r["op"], r["value"]) for r in _rows(live / "commands.csv")] == \
        [("pause", ""), ("rewind", "300"), ("resume", "")]
    _resumed(PARTICIPANT, {}, live / "checkpoints" / "300.ckpt", tmp_path / "resumed")
    assert _after(live / "recording.csv", 2.0)
    for name in ("recording.csv", "events.csv"):
        assert _after(live / name, 2.0) == _after(tmp_path / "resumed" / name, 2.0), name
    with Run(load_scenario(PARTICIPANT), out=tmp_path / "replayed", replay=live) as replayed:   # its own bus
        replayed.run()
    for name in FILES:
        assert (tmp_path / "replayed" / name).read_bytes() == (live / name).read_bytes(), name


def test_a_rewind_during_faults_puts_back_those_in_effect_at_the_checkpoint(tmp_path, multibody_bottles):
    """Saved at 0.9 s with the belt failing and the reader misreading; rewound from 4 s, when the
    belt's failure and the blade's (stuck from the reader's second bottle on, 2.1 s) had ended:
    the belt fails again, the schedule counts the reader's bottles from where it was, and the run
    goes on as one resumed from the checkpoint, the blade stuck and both repaired again."""
    faults = [{"name": "stuck", "kind": "part_stuck", "target": "sw", "after": {"event": "reader.trigger.on_enter",
                                                                               "count": 2}, "for": 1.0},
              {"name": "slow", "kind": "belt_failure", "target": "sw.main", "speed": 0.3, "at": 0.5, "for": 1.0},
              {"name": "misread", "kind": "reader_fault", "target": "reader", "reads": "wrong", "destination": "Q",
               "at": 0.2}]
    settings = {"faults": faults, "record": ["a.body.position", "b.body.position", "sw.blade.in_working",
                                             "reader.trigger.destination"]}
    live = tmp_path / "live"
    with Bus(BusSettings()) as bus, \
            Run(load_scenario(SWITCH, settings), out=live, bus=bus, checkpoints=((135,), None)) as run, \
            Viewer("switch", bus.endpoints) as operator:
        run.start()
        run.run(600)
        assert set(run.faults.active) == {"misread"}
        asked = operator.command("rewind", value=140, wait=None)
        _wait(run.commands.pending)
        run.run(602)   # rewound at its first point, then on to tick 602 again
        assert operator.answer(asked, 5)["ok"]
        run.run()
        faults_seen = run.summary().section("faults").as_dict()
    with Run(load_scenario(SWITCH, settings), out=tmp_path / "resumed",
             resume=(checkpoint.read(live / "checkpoints" / "135.ckpt"), "135.ckpt")) as resumed:
        resumed.run()
        assert resumed.summary().section("faults").as_dict() == faults_seen
    for name in ("recording.csv", "events.csv"):
        assert _after(live / name, 0.9) == _after(tmp_path / "resumed" / name, 0.9), name
    repairs = sorted(r["slot"] for r in _rows(live / "commands.csv") if r["op"] == "repair")
    assert repairs == ["sw.blade", "sw.blade", "sw.main", "sw.main"]   # in the branch left and again after


def test_a_rewind_that_cannot_be_done_is_refused_with_the_reason(tmp_path):
    """A tick past the present, none at or before the tick (the ticks it has listed), not a tick,
    and a run without a folder: each refused, named, and the run goes on."""
    with Bus(BusSettings()) as bus, Viewer("switch", bus.endpoints) as operator:
        with Run(load_scenario(SWITCH), out=tmp_path / "run", bus=bus, checkpoints=((225,), None)) as run:
            run.start()
            run.run(300)

            def refused(value) -> str:
                asked = operator.command("rewind", value=value, wait=None)
                _wait(run.commands.pending)
                run.run(run.tick + 1)
                answer = operator.answer(asked, 5)
                assert not answer["ok"]
                return answer["error"]

            assert refused(200) == ("rewind 200: no checkpoint at or before tick 200 (t = 1.33333 s); this run has "
                                    "checkpoints at ticks 225")
            at = run.tick + 1
            assert refused(900) == (f"rewind 900: tick 900 (t = 6 s) is in the future: the run is at tick {at} "
                                    f"(t = {at / 150:g} s)")
            assert refused(-3) == "rewind takes the tick to go back to (a whole number, 0 or more), got -3"
            assert refused("1 s") == "rewind takes the tick to go back to (a whole number, 0 or more), got '1 s'"
            run.run()
        assert not (tmp_path / "run" / "commands.csv").exists()   # nothing refused is recorded
        with Run(load_scenario(SWITCH), out=tmp_path / "early", bus=bus) as run:
            run.start()
            run.run(30)
            assert refused(0) == ("rewind 0: no checkpoint at or before tick 0 (t = 0 s); this run has taken none "
                                  "yet (planthub run --checkpoint-at, --checkpoint-every, or planthub send RUN "
                                  "checkpoint)")
        with Run(load_scenario(SWITCH), bus=bus) as run:
            run.start()
            run.run(30)
            assert refused(0) == ("rewind: this run keeps no checkpoints to go back to: it has no folder "
                                  "(planthub run --out)")


def test_planthub_run_rewound_by_planthub_send_and_replayed_gives_the_same_files(tmp_path):
    """Both sides on the command line: `planthub run --realtime 1 --listen … --checkpoint-every 1`
    rewound by `planthub send RUN rewind 150` (sent again while the run is not that far or has
    no checkpoint that early yet), then `planthub run --replay` of its folder: the same files, branch included."""
    endpoint, live = free_loopback_endpoint(), tmp_path / "live"
    with process("-m", "hub", "run", PARTICIPANT, "--realtime", "1", "--listen", endpoint, "--out", live,
                 "--checkpoint-every", "1", "-q") as run:
        for _ in range(20):
            sent = _planthub("send", "belt_ramp_participant", "rewind", "150", "--connect", endpoint)
            if sent.returncode == 0 or not ("no checkpoint at or before" in sent.stderr
                                            or "is in the future" in sent.stderr):
                break
            time.sleep(0.3)
        out, err = run.communicate(timeout=120)
    assert sent.returncode == 0, sent.stderr
    assert run.returncode == 0, err
    replayed = _planthub("run", PARTICIPANT, "--replay", live, "--out", tmp_path / "replayed", "-q")
    assert replayed.returncode == 0, replayed.stderr
    for name in FILES:
        assert (tmp_path / "replayed" / name).read_bytes() == (live / name).read_bytes(), name


def test_a_resumed_run_rewinds_to_where_it_resumed(tmp_path, multibody_bottles):
    """The checkpoint a run resumed from is one it may go back to: its files are cut back to their
    headers, and it goes on as the run resumed from it did."""
    from hub.bus.commands import Command

    with Run(load_scenario(SWITCH), out=tmp_path / "saved", checkpoints=((150,), None)) as run:
        run.run(300)
    saved = tmp_path / "saved" / "checkpoints" / "150.ckpt"
    _resumed(SWITCH, {}, saved, tmp_path / "resumed")
    with Run(load_scenario(SWITCH), out=tmp_path / "rewound", resume=(checkpoint.read(saved), str(saved))) as run:
        run.run(400)
        assert run.rewinder.refuse(run.tick, 100) == ("rewind 100: no checkpoint at or before tick 100 "
                                                      "(t = 0.666667 s); this run has checkpoints at ticks 150")
        assert run.rewinder.request(run.tick, Command("rewind", value=200), now=True) == 150
        assert run.tick == 150
        run.run()
    for name in ("recording.csv", "events.csv"):
        rewound = (tmp_path / "rewound" / name).read_text().splitlines()
        assert [line for line in rewound if "@run" not in line] == \
            (tmp_path / "resumed" / name).read_text().splitlines(), name
    assert len((tmp_path / "rewound" / "recording.branch1.csv").read_text().splitlines()) == 1 + 250


def test_a_rewind_to_a_checkpoint_file_that_is_gone_is_refused(tmp_path):
    with Run(load_scenario(SWITCH), out=tmp_path, checkpoints=((150,), None)) as run:
        run.run(300)
        (tmp_path / "checkpoints" / "150.ckpt").unlink()
        assert run.rewinder.refuse(run.tick, 200) == \
            f"rewind 200: its checkpoint {tmp_path / 'checkpoints' / '150.ckpt'} is gone"
