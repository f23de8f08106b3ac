"""`planthub view RUN_DIR`: a recorded run played back. A real recording (`planthub run
--record-bodies`, a point every 0.04 s), a real view process and a WebSocket client of its own
(aiohttp's): hello says playback, the scene, figures and recorded slots come once, and the bodies
follow the playback clock — advancing with play, standing with pause, jumping with a seek to the
recorded point at or before it, faster with the speed. Every bad frame gets its error, and a folder
that holds no recording is refused, naming the file and what is wrong with it.

    planthub run source_sink.yaml --record-bodies --out DIR ──► DIR ──► planthub view DIR ◄── /ws ── client
"""
import csv
import json
import math
import time

import numpy as np
import pyarrow as pa
import pyarrow.ipc as ipc
import pytest

from hub.core.errors import PlanthubError
from hub.view.bodies_file import SCHEMA, BodyRecording
from hub.view.run_folder import RecordedRun

from .helpers import ROOT
from .view_support import bodies, planthub, playback, receive, record, talk, wait_for

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"
RATE = 150
EVERY = 6   # ticks between two recorded points (0.04 s)
RECORD = ("--set", "run.record_bodies=0.04", "--set",
          "record=[source.store.remaining, sink.count.total, belt.drive.velocity, P1.body.position]")


@pytest.fixture(scope="module")
def played(tmp_path_factory):
    folder = tmp_path_factory.mktemp("playback")
    run_dir = record(folder, SCENARIO, *RECORD)
    with playback(folder, run_dir) as (started, url):
        yield run_dir, url, BodyRecording(run_dir)
        assert started.proc.poll() is None, started.output()


def positions(recording: BodyRecording, i: int, scene: dict) -> tuple[int, dict]:
    """Point i of the recording as the bodies message has it: (tick, id → (x, y, z))."""
    import msgpack

    return bodies(msgpack.packb(recording.message(i, RATE)), scene)


def csv_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


async def opening(ws) -> dict:
    """What a page is sent when it connects, by type, up to the bodies of the first point ("bodies")."""
    got = {}
    while "bodies" not in got:
        frame = await receive(ws)
        got["bodies" if isinstance(frame, bytes) else frame["type"]] = frame
    return got


async def bodies_for(ws, seconds: float, scene: dict) -> list[tuple[float, int, dict]]:
    """The bodies frames that come within `seconds` of wall time: (wall s, tick, positions); the
    text frames in between are left out."""
    out, deadline = [], time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        try:
            frame = await receive(ws, left)
        except TimeoutError:
            break
        if isinstance(frame, bytes):
            out.append((time.monotonic(), *bodies(frame, scene)))
    return out


async def ask(ws, op: str, value=None) -> dict:
    """Send a playback frame; the state frame that answers it."""
    await ws.send_str(json.dumps({"type": "playback", "op": op, **({} if value is None else {"value": value})}))
    return await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] in ("playback", "error"),
                          what=f"the answer to {op}")


def pace(frames) -> float:
    """Plant s per wall s over the bodies frames."""
    (w0, t0, _), (w1, t1, _) = frames[0], frames[-1]
    return (t1 - t0) / RATE / (w1 - w0)


def test_a_page_is_told_playback_and_given_the_scene_figures_recorded_slots_and_the_first_point(played):
    run_dir, url, recording = played
    got = talk(url, opening)
    scene = json.loads((run_dir / "scene.json").read_text())
    summary = json.loads((run_dir / "summary.json").read_text())
    first, last = int(recording.ticks[0]), int(recording.ticks[-1])
    assert first == 0 and last == 972 and np.all(np.diff(recording.ticks) == EVERY)
    assert got["hello"] == {"type": "hello", "run": "source_sink", "mode": "playback", "control": False,
                            "reason": "a recorded run: nothing to operate", "viewer": "playback",
                            "start": 0.0, "end": last / RATE, "rate": RATE}
    assert got["scene"] == {"type": "scene", "scene": scene}
    assert got["state"] == {"type": "state", "state": "recorded", "tick": last, "time": last / RATE,
                            "reason": "reached its duration at t = 6.5 s (run.duration)"}
    figures = got["figures"]
    assert figures["final"] is True and figures["time"] == 6.5 and figures["tick"] == 975
    assert figures["sections"] == {"plant": summary["plant"]}

    recorded = got["recording"]
    assert recorded["slots"] == {"source.store.remaining": ["source.store.remaining"],
                                 "sink.count.total": ["sink.count.total"],
                                 "belt.drive.velocity": ["belt.drive.velocity"],
                                 "P1.body.position": [f"P1.body.position.{c}" for c in "xyz"],
                                 "bodies in play": ["bodies in play"]}
    rows = csv_rows(run_dir / "recording.csv")
    for column in ("sink.count.total", "belt.drive.velocity", "P1.body.position.x"):
        series = recorded["series"][column]
        assert series["ticks"] == [round(float(r["time"]) * RATE) for r in rows]
        assert series["values"] == [float(r[column]) for r in rows], column
    in_play = recorded["series"]["bodies in play"]
    assert in_play["ticks"] == recording.ticks.tolist() and max(in_play["values"]) == 6

    assert got["playback"] == {"type": "playback", "op": "open", "time": 0.0, "tick": 0, "playing": False,
                               "speed": 1.0, "jump": True}
    assert got["events"] == {"type": "events", "rows": [], "reset": True}
    assert got["slots"] == {"type": "slots", "tick": 0, "values": {
        "source.store.remaining": 6, "sink.count.total": 0, "belt.drive.velocity": float(rows[0]["belt.drive.velocity"]),
        "P1.body.position.x": float(rows[0]["P1.body.position.x"]), "P1.body.position.y": float(rows[0]["P1.body.position.y"]),
        "P1.body.position.z": float(rows[0]["P1.body.position.z"])}}
    assert bodies(got["bodies"], scene) == positions(recording, 0, scene)


def test_play_advances_pause_stands_seek_jumps_to_the_recorded_point_and_speed_paces(played):
    run_dir, url, recording = played
    scene = json.loads((run_dir / "scene.json").read_text())
    events = [[int(r["tick"]), r["slot"], r["detail"]] for r in csv_rows(run_dir / "events.csv")]

    async def conversation(ws):
        await opening(ws)
        out = {"play": await ask(ws, "play"), "playing": await bodies_for(ws, 1.2, scene)}
        out["pause"] = await ask(ws, "pause")
        out["paused"] = await bodies_for(ws, 0.6, scene)
        out["seek"] = await ask(ws, "seek", 2.05)   # tick 307: the recorded point is 306
        out["sought"] = await wait_for(ws, lambda f: isinstance(f, bytes), what="the bodies after the seek")
        out["still"] = await bodies_for(ws, 0.4, scene)
        out["back"] = await ask(ws, "seek", 0.5)
        out["back events"] = await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] == "events",
                                            what="the events after seeking back")
        await ask(ws, "seek", 0.0)
        out["speed"] = await ask(ws, "speed", 4)
        await ask(ws, "play")
        out["fast"] = await bodies_for(ws, 1.0, scene)
        await ask(ws, "seek", 6.2)
        out["end"] = await wait_for(ws, lambda f: isinstance(f, dict) and f.get("op") == "end", timeout=10,
                                    what="the end of the recording")
        out["again"] = await ask(ws, "play")
        return out

    out = talk(url, conversation)
    assert out["play"]["playing"] is True and out["play"]["jump"] is False
    playing = out["playing"]
    ticks = [tick for _, tick, _ in playing]
    assert len(ticks) >= 10 and ticks == sorted(set(ticks)) and all(t % EVERY == 0 for t in ticks), ticks
    assert 0.7 < pace(playing) < 1.3, f"played at 1×: {pace(playing):.2f} s of the run per s"
    assert all(positions(recording, recording.index_at(tick), scene)[1] == drawn for _, tick, drawn in playing)

    pause = out["pause"]
    assert pause["playing"] is False and pause["op"] == "pause"
    stood = recording.ticks[recording.index_at(pause["tick"])]
    assert [tick for _, tick, _ in out["paused"]] in ([], [stood]), "at most the point it paused at, then nothing"

    seek = out["seek"]
    assert (seek["op"], seek["tick"], seek["jump"], seek["playing"]) == ("seek", 307, True, False)
    assert bodies(out["sought"], scene) == positions(recording, recording.index_at(307), scene)
    assert bodies(out["sought"], scene)[0] == 306
    assert out["still"] == [], "paused after the seek: no more bodies"
    assert out["back events"] == {"type": "events", "reset": True, "rows": [e for e in events if e[0] <= 75]}

    assert out["speed"]["speed"] == 4.0
    fast = out["fast"]
    assert 3.0 < pace(fast) < 5.0, f"played at 4×: {pace(fast):.2f} s of the run per s"
    end = out["end"]
    assert (end["playing"], end["tick"], end["jump"]) == (False, 972, False)
    again = out["again"]
    assert (again["playing"], again["tick"], again["jump"]) == (True, 0, True), "played again from the start"


@pytest.mark.parametrize("sent, error", [
    ('{"type": "playback"}', "unknown playback op null: expected one of play, pause, speed, seek"),
    ('{"type": "playback", "op": "rewind"}', 'unknown playback op "rewind": expected one of play, pause, speed, seek'),
    ('{"type": "playback", "op": "play", "value": 1}', "play takes no value, got 1"),
    ('{"type": "playback", "op": "pause", "value": "now"}', 'pause takes no value, got "now"'),
    ('{"type": "playback", "op": "speed"}', "speed takes a factor of the recorded pace from 0.1 to 10, got null"),
    ('{"type": "playback", "op": "speed", "value": 20}',
     "speed takes a factor of the recorded pace from 0.1 to 10, got 20"),
    ('{"type": "playback", "op": "speed", "value": 0.05}',
     "speed takes a factor of the recorded pace from 0.1 to 10, got 0.05"),
    ('{"type": "playback", "op": "speed", "value": true}',
     "speed takes a factor of the recorded pace from 0.1 to 10, got true"),
    ('{"type": "playback", "op": "seek", "value": "1.0"}', 'seek takes a time in s of the recorded run, got "1.0"'),
    ('{"type": "playback", "op": "seek", "value": 99}', "seek to 99 s: the recording spans 0 to 6.48 s"),
    ('{"type": "playback", "op": "seek", "value": -0.5}', "seek to -0.5 s: the recording spans 0 to 6.48 s"),
    ('{"type": "playback", "op": "seek", "value": Infinity}', "not JSON: Infinity is not a JSON number"),
    ('{"type": "command", "op": "stop", "ref": "s"}', "a recorded run: nothing to operate: the command was not sent"),
    ('{"type": "rate", "period": 0}', "rate takes a period in s, more than 0 and at most 3600, or null; got 0"),
    ('{"type": "shout"}', 'unknown type "shout": expected command, rate or playback'),
    ("[]", "expected a JSON object with a type, got []"),
])
def test_a_bad_frame_gets_its_error_and_the_playback_goes_on(played, sent, error):
    run_dir, url, recording = played

    async def conversation(ws):
        await opening(ws)
        await ws.send_str(sent)
        answer = await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] == "error", what="an error frame")
        return answer, await ask(ws, "seek", 1.0)

    answer, after = talk(url, conversation)
    assert answer["error"] == error
    if '"command"' in sent:
        assert answer == {"type": "error", "op": "stop", "slot": "", "ref": "s", "error": error}
    assert after["op"] == "seek" and after["tick"] == 150


def view(tmp_path, *args) -> tuple[int, str]:
    """`planthub view ARGS…` that ends by itself: (exit status, stderr)."""
    with planthub(tmp_path, "refused", "view", *args) as started:
        code = started.proc.wait(60)
    return code, started.output()[1].strip()


def test_a_folder_without_a_body_recording_is_a_usage_error_that_says_how_to_record_one(tmp_path):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "summary.json").write_text("{}")
    assert view(tmp_path, tmp_path / "run") == (2, (
        f"planthub: {tmp_path / 'run'}: no body recording (bodies.arrows); record one with `planthub run "
        "--record-bodies` or `run.record_bodies: true`"))


def test_a_broken_body_recording_is_named(tmp_path):
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "bodies.arrows").write_bytes(b"not arrow at all, but long enough to be read")
    code, err = view(tmp_path, tmp_path / "run")
    assert code == 1 and err.startswith(f"planthub: {tmp_path / 'run' / 'bodies.arrows'}: not an Arrow stream ("), err


def test_what_is_not_a_run_folder_and_options_of_a_live_view_are_refused(tmp_path):
    assert view(tmp_path, "runs/nowhere") == (2, (
        "planthub: runs/nowhere: no such run folder (give the folder `planthub run --record-bodies --out DIR` "
        "wrote, or join a running plant: `planthub view RUN --connect ENDPOINT`)"))
    assert view(tmp_path, "bottling_plant") == (2, (
        "planthub: bottling_plant: no such run folder, and no --connect: join a running plant with "
        "`planthub view bottling_plant --connect ENDPOINT` (the hub's --listen), or play a recorded run with "
        "`planthub view RUN_DIR`"))
    assert view(tmp_path, tmp_path, "--no-control", "--timeout", "3") == (2, (
        f"planthub: --no-control, --timeout: for joining a running plant; {tmp_path} is a recorded run, "
        "played back from its files"))


@pytest.fixture(scope="module")
def recorded(played):
    return played[0]


def copy(recorded, to, *leave_out: str):
    to.mkdir(parents=True)
    for path in recorded.iterdir():
        if path.name not in leave_out:
            (to / path.name).write_bytes(path.read_bytes())
    return to


def broken(recorded, tmp_path, name: str, text: str):
    folder = copy(recorded, tmp_path / "run")
    (folder / name).write_text(text)
    with pytest.raises(PlanthubError) as info:
        RecordedRun(folder)
    return str(info.value).replace(str(folder), "RUN")


def test_a_broken_scene_is_named(recorded, tmp_path):
    folder = copy(recorded, tmp_path / "no_scene", "scene.json")
    with pytest.raises(PlanthubError) as info:
        RecordedRun(folder)
    assert str(info.value) == (f"{folder / 'scene.json'}: no such file: the scene of the body recording beside "
                               "it (`planthub run --record-bodies` writes both)")
    assert broken(recorded, tmp_path / "a", "scene.json", "{") == (
        "RUN/scene.json is not JSON: Expecting property name enclosed in double quotes: line 1 column 2 (char 1)")
    assert broken(recorded, tmp_path / "b", "scene.json", '{"format": "glTF"}') == (
        "RUN/scene.json is not a planthub-scene document (the scene `planthub run --record-bodies` writes)")
    assert broken(recorded, tmp_path / "c", "scene.json", '{"format": "planthub-scene", "version": 7}') == (
        "RUN/scene.json is version 7; this view reads version 1")
    assert broken(recorded, tmp_path / "d", "scene.json",
                  '{"format": "planthub-scene", "version": 1, "physics_rate": 0}') == (
        "RUN/scene.json: physics_rate is 0, not a positive whole number of ticks per s")


def test_an_empty_body_recording_is_named(recorded, tmp_path):
    folder = copy(recorded, tmp_path / "run", "bodies.arrows")
    with pa.OSFile(str(folder / "bodies.arrows"), "wb") as sink:
        ipc.new_stream(sink, SCHEMA).close()
    with pytest.raises(PlanthubError) as info:
        RecordedRun(folder)
    assert str(info.value) == (f"{folder / 'bodies.arrows'}: no recorded point (the run was killed before its "
                               "first batch was written)")


def test_a_broken_event_log_recording_or_summary_is_named_with_its_line(recorded, tmp_path):
    header = "time,tick,slot,detail\n"
    assert broken(recorded, tmp_path / "a", "events.csv", header + "0.1,15,a.b.c,\n0.2,soon,a.b.c,\n0.3,45,a.b.c,\n") \
        == "RUN/events.csv:3: the tick 'soon' is not a whole number"
    assert broken(recorded, tmp_path / "b", "events.csv", "when,what\n") == (
        "RUN/events.csv is not an event log planthub wrote: its header is 'when, what', not 'time, tick, slot, detail'")
    assert broken(recorded, tmp_path / "c", "events.csv", header + "0.1,15\n0.2,30,a.b.c,\n") == (
        "RUN/events.csv:2: 2 columns, but its header names 4")
    assert broken(recorded, tmp_path / "d", "events.csv", "") == "RUN/events.csv is empty: not even its header"
    assert broken(recorded, tmp_path / "e", "recording.csv", '"t","x.y.z"\n0.0,1\n') == (
        "RUN/recording.csv is not a recording planthub wrote: its first column is 't', not 'time'")
    assert broken(recorded, tmp_path / "f", "recording.csv", '"time","x.y.z"\n0.0,1\nlater,2\n0.2,3\n') == (
        "RUN/recording.csv:3: the time 'later' is not a finite number")
    assert broken(recorded, tmp_path / "f2", "recording.csv", '"time","x.y.z"\n0.0,1\ninf,2\n') == (
        "RUN/recording.csv:3: the time 'inf' is not a finite number")
    assert broken(recorded, tmp_path / "g", "summary.json", "[1") == (
        "RUN/summary.json is not JSON: Expecting ',' delimiter: line 1 column 3 (char 2)")
    assert broken(recorded, tmp_path / "h", "summary.json", "[1]") == (
        "RUN/summary.json is not a planthub run summary (a JSON object)")


def test_a_folder_without_the_other_files_plays_and_says_what_it_lacks(recorded, tmp_path):
    folder = copy(recorded, tmp_path / "run", "events.csv", "recording.csv", "summary.json")
    run = RecordedRun(folder)
    assert run.notes == [f"no {folder / 'events.csv'}: the event log stays empty",
                         f"no {folder / 'recording.csv'}: no recorded slots to plot",
                         f"no {folder / 'summary.json'} (a run killed outright writes none): no figures"]
    assert run.figures() is None and run.events.rows == [] and len(run.slots) == 0
    cut = copy(recorded, tmp_path / "cut")
    text = (cut / "events.csv").read_text()
    (cut / "events.csv").write_text(text + "6.5,975,sink.bin")   # a run killed while it wrote the line
    lines = text.count("\n") + 1
    run = RecordedRun(cut)
    assert run.notes == [f"{cut / 'events.csv'}:{lines}: the last line is cut short (3 of 4 columns); played "
                         "without it"]
    assert len(run.events.rows) == lines - 2
    assert math.isclose(run.end, 6.48)
