"""The view's two roles: an instructor's page sees the faults (the scenario's and live ones) and injects
them, checked by the hub with a clear error back; a trainee's page never receives a fault — no board, no
fault rows in the events, no faults section in the figures — and its fault commands are refused by the
view, named, before anything goes on the bus (real hub, two real `planthub view`s, real WebSockets).

    planthub run source_sink.yaml (a belt failure scheduled at 2 s) ◄── Zenoh ──┬── view (instructor) ◄── /ws
                                                                                └── view --role trainee ◄── /ws
"""
from __future__ import annotations

import asyncio
import json

import aiohttp
import pytest

from .helpers import ROOT
from .view_support import command_rows, hub, receive, view, wait_for

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"
SCHEDULED = [{"name": "scheduled", "kind": "belt_failure", "target": "belt", "speed": 0.5, "at": 2.0, "for": 1.0}]
LIVE = {"name": "live", "kind": "belt_failure", "speed": 0.25, "for": 0.5}


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    folder = tmp_path_factory.mktemp("roles")
    with hub(folder, SCENARIO, "--set", "run.duration=120", "--set", f"faults={json.dumps(SCHEDULED)}") \
            as (started, endpoint, run_dir), \
            view(folder, "source_sink", endpoint, name="instructor") as (_, instructor), \
            view(folder, "source_sink", endpoint, "--role", "trainee", name="trainee") as (_, trainee):
        yield instructor, trainee, run_dir
        assert started.proc.poll() is None, started.output()


def fault_frames(frame) -> bool:
    """A frame that tells of a fault: the board, a fault's event row, the faults section, a fault's result."""
    if not isinstance(frame, dict):
        return False
    if frame.get("type") == "faults":
        return True
    if frame.get("type") == "events" and any(r[1] == "@fault" for r in frame.get("rows", [])):
        return True
    if frame.get("type") == "figures" and "faults" in frame.get("sections", {}):
        return True
    return frame.get("type") == "result" and frame.get("op") in ("fault", "repair")


def test_an_instructor_sees_and_injects_faults_and_a_trainee_sees_none_and_cannot_send_one(plant):
    instructor_url, trainee_url, run_dir = plant

    async def main():
        async with aiohttp.ClientSession(timeout=aiohttp.ClientTimeout(total=120)) as session:
            async with session.ws_connect(f"{instructor_url}ws", heartbeat=None) as teacher, \
                    session.ws_connect(f"{trainee_url}ws", heartbeat=None) as pupil:
                seen: list = []

                async def watch_trainee():
                    while True:
                        seen.append(await receive(pupil, 60))

                hello = await wait_for(teacher, lambda f: isinstance(f, dict) and f.get("type") == "hello")
                watching = asyncio.ensure_future(watch_trainee())
                board = await wait_for(teacher, lambda f: isinstance(f, dict) and f.get("type") == "faults"
                                       and f["scheduled"][0]["state"] == "ended", timeout=30, what="the board")
                await teacher.send_str(json.dumps({"type": "command", "op": "fault", "slot": "belt.drive",
                                                   "value": LIVE, "ref": "inject"}))
                applied = await wait_for(teacher, lambda f: isinstance(f, dict) and f.get("ref") == "inject")
                await teacher.send_str(json.dumps({"type": "command", "op": "fault", "slot": "belt.drivve",
                                                   "value": {**LIVE, "name": "bad"}, "ref": "bad"}))
                refused = await wait_for(teacher, lambda f: isinstance(f, dict) and f.get("ref") == "bad")
                rows = await wait_for(teacher, lambda f: isinstance(f, dict) and f.get("type") == "events" and any(
                    r[1] == "@fault" and "repair" in r[2] and "live" in r[2] for r in f["rows"]), timeout=20,
                    what="the live fault's repair")
                await pupil.send_str(json.dumps({"type": "command", "op": "fault", "slot": "belt.drive",
                                                 "value": {**LIVE, "name": "pupil"}, "ref": "pupil"}))
                for _ in range(100):
                    if any(isinstance(f, dict) and f.get("ref") == "pupil" for f in seen):
                        break
                    await asyncio.sleep(0.1)
                await asyncio.sleep(1.5)   # a figures message or two more
                watching.cancel()
                return hello, board, applied, refused, rows, seen

    hello, board, applied, refused, rows, seen = asyncio.run(main())
    assert hello["role"] == "instructor" and hello["role_reason"] == ""
    assert board["scheduled"][0]["name"] == "scheduled" and board["scheduled"][0]["when"] == "from 2 s for 1 s"
    assert board["kinds"]["belt_failure"]["targets"] == ["belt.drive"]
    assert applied["type"] == "result" and applied["ok"] is True, applied
    assert refused["ok"] is False and refused["error"] == "fault bad: object 'belt' has no component 'drivve' " \
                                                          "(did you mean 'drive'?)", refused
    commands = command_rows(run_dir, 10, lambda rows: any(r["value"].startswith('{"name": "live"') for r in rows)
                            and len(rows) >= 4)
    assert [(r["op"], r["slot"], r["by"]) for r in commands] == [
        ("fault", "belt.drive", "scenario"), ("repair", "belt.drive", "scenario"),
        ("fault", "belt.drive", "instructor"), ("repair", "belt.drive", "instructor")]

    trainee_hello = next(f for f in seen if isinstance(f, dict) and f.get("type") == "hello")
    assert trainee_hello["role"] == "trainee" and trainee_hello["role_reason"] == "it was started with --role trainee"
    assert any(isinstance(f, dict) and f.get("type") == "figures" for f in seen)   # it did see the plant
    assert [f for f in seen if fault_frames(f)] == []
    answer = next(f for f in seen if isinstance(f, dict) and f.get("ref") == "pupil")
    assert answer["type"] == "error" and answer["error"] == (
        "fault: this is a trainee's view (it was started with --role trainee): faults are an instructor's; "
        "the command was not sent")
