"""`planthub view` against a real hub on loopback: a WebSocket client of its own (aiohttp's) gets the
hello, the scene and the bodies, sends a command that the hub applies and records, and the view's
files stay inside their folders.

    planthub run source_sink.yaml --realtime --listen tcp/127.0.0.1:P ◄── Zenoh ──► planthub view ◄── /ws ── client
"""
import asyncio
import json
import signal

import aiohttp
import pytest
from aiohttp import web

from hub.view.browser import Browser
from hub.view.http import WRITER_LIMIT, _inside

from .helpers import ROOT
from .view_support import bodies, command_rows, end, hub, planthub, receive, talk, view, wait_for

RUN = "source_sink"
SCENARIO = ROOT / "scenarios" / "source_sink.yaml"
# A bottle every 0.5 s for as long as the module's tests take (they end the run; 0.5 m/s, 2 m belt).
LONG = ("--set", "run.duration=300", "--set", "objects.source.count=200")


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    folder = tmp_path_factory.mktemp("view")
    with hub(folder, SCENARIO, *LONG) as (started_hub, endpoint, run_dir), \
            view(folder, RUN, endpoint) as (started_view, url):
        yield endpoint, run_dir, url, started_view
        assert started_hub.proc.poll() is None, started_hub.output()


async def greeting(ws) -> dict:
    """The hello and the scene, in that order; the scene."""
    hello = await receive(ws)
    assert hello == {"type": "hello", "run": RUN, "control": True, "reason": "", "viewer": "view-test",
                     "role": "instructor", "role_reason": ""}
    scene = await receive(ws)
    assert scene["type"] == "scene"
    return scene["scene"]


def on_the_belt(positions: dict) -> dict:
    """The bottles between the source's spot and the sink's (x from 0.15 to 1.8 m on the 2 m belt)."""
    return {b: p for b, p in positions.items() if 0.15 < p[0] < 1.8}


async def two_samples(ws, scene, apart: float = 1.0, since: int = 0):
    """Two bodies messages at least `apart` s of plant time apart, the first from tick `since` on and
    with two bottles or more on the belt: (positions, positions)."""
    tick0, before = -1, {}
    while len(on_the_belt(before)) < 2 or tick0 < since:
        first = await wait_for(ws, lambda f: isinstance(f, bytes), what="a bodies frame")
        tick0, before = bodies(first, scene)
    rate = scene["physics_rate"]
    while True:
        frame = await wait_for(ws, lambda f: isinstance(f, bytes), what="a bodies frame")
        tick, after = bodies(frame, scene)
        if tick >= tick0 + apart * rate:
            return before, after


def moved(before: dict, after: dict) -> list[float]:
    return [abs(after[b][0] - before[b][0]) for b in on_the_belt(before) if b in on_the_belt(after)]


def test_a_browser_gets_hello_then_the_scene_then_bodies_events_and_belt_speeds(plant):
    endpoint, run_dir, url, _ = plant

    async def conversation(ws):
        scene = await greeting(ws)
        assert scene["format"] == "planthub-scene" and scene["run"] == RUN
        assert ["drive.run", "bool", "target"] in scene["objects"]["belt"]["slots"]
        seen = {"bytes": [], "events": [], "slots": [], "checkpoints": []}
        while not all(seen.values()):
            frame = await wait_for(ws, lambda f: True, what="frames")
            kind = "bytes" if isinstance(frame, bytes) else frame["type"]
            if kind == "bytes" and not all(bodies(frame, scene)):
                continue   # the plant at tick 0, or no bottle out yet (the view may join before the first step)
            if kind in seen:
                seen[kind].append(frame)
        return scene, seen

    scene, seen = talk(url, conversation)   # (a bodies message with bottles in play comes within wait_for's limit)
    tick, positions = bodies(seen["bytes"][0], scene)
    assert all(len(p) == 3 and abs(p[1]) < 0.06 and 0.0 < p[2] < 0.2 for p in positions.values()), positions
    assert all(len(row) == 3 and isinstance(row[0], int) for row in seen["events"][0]["rows"])
    assert {r[1] for f in seen["events"] for r in f["rows"]} <= {"source.store.released", "source.store.waiting",
                                                                  "sink.bin.taken"}
    assert set(seen["slots"][0]["values"]) == {"belt.drive.velocity"}
    # The panel's timeline: this run takes no checkpoint, so a rewind has nothing to go back to.
    timeline = seen["checkpoints"][0]
    assert timeline["checkpoints"] == [] and timeline["rate"] == scene["physics_rate"], timeline


def test_a_browser_command_reaches_the_hub_is_recorded_and_stops_the_belts_bottles(plant):
    endpoint, run_dir, url, _ = plant

    async def conversation(ws):
        scene = await greeting(ws)
        running = moved(*await two_samples(ws, scene))
        await ws.send_str(json.dumps({"type": "command", "op": "force", "slot": "belt.drive.run", "value": False,
                                      "ref": "stop-1"}))
        result = await wait_for(ws, lambda f: isinstance(f, dict) and f.get("ref") == "stop-1", what="the result")
        # The bottles come to rest within 0.3 s of plant time (the belt's k); measured from 0.5 s on.
        stopped = moved(*await two_samples(ws, scene, since=result["tick"] + scene["physics_rate"] // 2))
        await ws.send_str(json.dumps({"type": "command", "op": "release", "slot": "belt.drive.run", "ref": "go"}))
        released = await wait_for(ws, lambda f: isinstance(f, dict) and f.get("ref") == "go", what="the result")
        return running, result, stopped, released

    running, result, stopped, released = talk(url, conversation)
    assert result["type"] == "result" and result["ok"] is True and result["error"] == "", result
    assert result["op"] == "force" and result["slot"] == "belt.drive.run" and result["id"].startswith("view-test-")
    assert running and min(running) > 0.3, f"the bottles ran at 0.5 m/s before: {running}"
    assert stopped and max(stopped) < 0.005, f"and stand after: {stopped}"
    assert released["ok"] is True
    rows = command_rows(run_dir, until=lambda rows: len(rows) >= 2)
    assert [(r["op"], r["slot"], r["value"], r["by"]) for r in rows[:2]] == [
        ("force", "belt.drive.run", "false", "view-test"), ("release", "belt.drive.run", "", "view-test")]
    assert int(rows[0]["tick"]) == result["tick"]


@pytest.mark.parametrize("sent, error", [
    ("{not json", "not JSON: Expecting property name enclosed in double quotes: line 1 column 2 (char 1)"),
    ("[1, 2]", "expected a JSON object with a type, got [1, 2]"),
    ('{"type": "shout"}', 'unknown type "shout": expected command, rate or playback'),
    ('{"type": "command", "op": "explode"}',
     'unknown op "explode": expected one of set, force, release, stop, pause, resume, step, pace, rewind, fault, '
     'repair'),
    ('{"type": "command", "op": "force", "slot": "belt", "value": false}',
     'force needs a slot object.component.slot (at most 200 characters), got "belt"'),
    ('{"type": "command", "op": "step", "value": -3}', "step takes a number of points from 1 to 100000, got -3"),
    ('{"type": "command", "op": "fault", "slot": "belt.drive.run", "value": {"name": "x"}}',
     'fault needs the part it acts on, object.component (at most 200 characters), got "belt.drive.run"'),
    ('{"type": "command", "op": "repair", "value": "x"}', 'repair takes a map with the fault\'s name, got "x"'),
    ('{"type": "command", "op": "pace", "value": NaN}', "not JSON: NaN is not a JSON number"),
    ('{"type": "command", "op": "rewind", "value": 1.5}',
     "rewind takes the tick to go back to (a whole number, 0 or more), got 1.5"),
    ('{"type": "command", "op": "rewind", "slot": "belt.drive.run", "value": 3}', 'rewind takes no slot, got "belt.drive.run"'),
    ('{"type": "rate", "period": "fast"}',
     'rate takes a period in s, more than 0 and at most 3600, or null; got "fast"'),
    (b"\x00\x01", "expected a JSON text frame, got a binary one"),
    ('{"type": "playback", "op": "play"}',
     "this view shows the run 'source_sink' live: playback is for a recorded run (`planthub view RUN_DIR`)"),
])
def test_a_malformed_frame_gets_an_error_frame_and_the_view_goes_on(plant, sent, error):
    endpoint, run_dir, url, started = plant

    async def conversation(ws):
        await greeting(ws)
        await (ws.send_bytes(sent) if isinstance(sent, bytes) else ws.send_str(sent))
        answer = await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] == "error", what="an error frame")
        await ws.send_str('{"type": "rate", "period": 0.1}')
        after = await wait_for(ws, lambda f: isinstance(f, bytes), what="a bodies frame after it")
        return answer, after

    answer, after = talk(url, conversation)
    assert answer["error"] == error
    assert after and started.proc.poll() is None


@pytest.mark.parametrize("headers", [
    {"Origin": "http://attacker.example"},                  # another site's page in the same browser
    {"Host": "attacker.example:8765"},                      # a name of another site made to point at 127.0.0.1
    {"Host": "attacker.example:8765", "Origin": "http://attacker.example:8765"},
])
def test_a_page_of_another_site_may_not_use_the_socket(plant, headers):
    endpoint, run_dir, url, _ = plant
    with pytest.raises(aiohttp.WSServerHandshakeError) as info:
        talk(url, greeting, **headers)
    assert info.value.status == 403


async def status(url: str, path: str) -> int:
    """The status of GET `path`, sent as written (a client library would resolve the `..` first)."""
    host, port = url.removeprefix("http://").rstrip("/").rsplit(":", 1)
    reader, writer = await asyncio.open_connection(host, int(port))
    writer.write(f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nConnection: close\r\n\r\n".encode())
    await writer.drain()
    line = await asyncio.wait_for(reader.readline(), 10)
    writer.close()
    return int(line.split()[1])


def test_the_robot_files_come_from_pybullet_data_and_nothing_outside_it(plant):
    endpoint, run_dir, url, _ = plant

    async def requests():
        return [await status(url, path) for path in (
            "/pybullet_data/kuka_iiwa/model.urdf", "/pybullet_data/../x", "/pybullet_data/%2e%2e/%2e%2e/etc/passwd",
            "/pybullet_data//etc/passwd", "/pybullet_data/kuka_iiwa/", "/assets/../../../etc/passwd", "/")]

    assert asyncio.run(requests()) == [200, 404, 404, 404, 404, 404, 200]


def test_a_path_out_of_its_folder_is_not_found_even_when_the_file_is_there(tmp_path):
    (tmp_path / "served").mkdir()
    (tmp_path / "served" / "robot.urdf").write_text("<robot/>")
    (tmp_path / "secret").write_text("key")
    (tmp_path / "served" / "link").symlink_to(tmp_path / "secret")
    assert _inside(tmp_path / "served", "robot.urdf").status == 200
    for path in ("../secret", str(tmp_path / "secret"), "link", "nul\0byte"):
        with pytest.raises(web.HTTPNotFound):
            _inside(tmp_path / "served", path)


def test_a_missing_front_end_is_said_with_how_to_build_it_and_sigterm_ends_the_view(plant, tmp_path):
    endpoint, run_dir, url, _ = plant
    with view(tmp_path, RUN, endpoint, "--bundle", tmp_path / "nothing", name="view-bare") as (started, bare):
        async def index():
            async with aiohttp.ClientSession(timeout=aiohttp.ClientTimeout(total=10)) as session:
                async with session.get(bare) as response:
                    return response.status, await response.text()

        code, text = asyncio.run(index())
        assert end(started.proc, signal.SIGTERM) == 143
    missing = f"the view's front-end is not built (no {tmp_path / 'nothing' / 'index.html'}): build it with " \
              "`make view-assets` (cd hub/view/web && npm ci && npm run build)"
    assert code == 503 and missing in text
    assert missing in started.output()[1]


def test_sigint_ends_the_view_with_130(plant, tmp_path):
    endpoint, run_dir, url, _ = plant
    with view(tmp_path, RUN, endpoint, name="view-short") as (started, short):
        assert end(started.proc, signal.SIGINT) == 130


def test_a_run_nobody_serves_is_named_with_its_endpoint(plant, tmp_path):
    endpoint, run_dir, url, _ = plant
    with planthub(tmp_path, "lost", "view", "no_such_run", "--connect", endpoint, "--port", 0,
                  "--timeout", 2) as started:
        assert started.proc.wait(30) == 1
    assert started.output()[1].strip() == (
        f"planthub: no scene from the hub of run 'no_such_run' at {endpoint} within 2 s: is `planthub run` going "
        "there (--listen on that endpoint), and is the run named 'no_such_run' (its scenario's name)?")


def test_a_folder_with_connect_is_refused_and_told_how_to_play_it_back(tmp_path):
    with planthub(tmp_path, "folder", "view", "runs/bottling_plant", "--connect", "tcp/127.0.0.1:9") as started:
        assert started.proc.wait(30) == 2
    assert started.output()[1].strip() == (
        "planthub: runs/bottling_plant names a folder, and --connect joins a running plant by its run's name "
        "(`planthub view bottling_plant --connect tcp/127.0.0.1:7447`); to play the recorded run back, leave out "
        "--connect: `planthub view runs/bottling_plant`")


def test_a_browser_that_does_not_read_makes_no_queue_and_gets_the_newest_bodies_frame():
    """A real socket whose reader stops: the frames that come meanwhile replace each other in the
    browser's one-frame box, and when it reads again the newest is what it gets last."""
    frames, size = 400, 256 * 1024   # 100 MB if each went out: far more than the socket's buffers hold

    async def main():
        pushed, read = asyncio.Event(), asyncio.Event()
        seen = {}

        async def handler(request):
            ws = web.WebSocketResponse(compress=False, writer_limit=WRITER_LIMIT)
            await ws.prepare(request)
            browser = Browser(ws)
            writer = asyncio.get_running_loop().create_task(browser.write())
            for n in range(frames):
                browser.send_bodies(n.to_bytes(2, "little") * (size // 2))
                await asyncio.sleep(0)   # the writer has its turn after each
            seen["dropped"] = browser.dropped
            pushed.set()
            await asyncio.wait_for(read.wait(), 30)
            browser.closing = True
            writer.cancel()
            await asyncio.gather(writer, return_exceptions=True)
            await ws.close()
            return ws

        app = web.Application()
        app.router.add_get("/ws", handler)
        runner = web.AppRunner(app)
        await runner.setup()
        await web.TCPSite(runner, "127.0.0.1", 0).start()
        try:
            async with aiohttp.ClientSession() as session:
                async with session.ws_connect(f"http://127.0.0.1:{runner.addresses[0][1]}/ws",
                                              max_msg_size=2 * size) as ws:
                    await asyncio.wait_for(pushed.wait(), 30)   # not reading meanwhile
                    received = []
                    while not received or received[-1] != frames - 1:
                        message = await asyncio.wait_for(ws.receive(), 10)
                        received.append(int.from_bytes(message.data[:2], "little"))
                    read.set()
        finally:
            await runner.cleanup()
        return seen["dropped"], received

    dropped, received = asyncio.run(main())
    assert received[-1] == frames - 1 and received == sorted(received)
    assert dropped == frames - len(received) and len(received) < 60, (dropped, len(received))


def test_a_view_that_only_watches_says_why_and_sends_no_command(plant, tmp_path):
    endpoint, run_dir, url, _ = plant
    with view(tmp_path, RUN, endpoint, "--no-control", name="view-watch") as (started, watching):
        async def conversation(ws):
            hello = await receive(ws)
            await ws.send_str('{"type": "command", "op": "stop", "ref": "s"}')
            return hello, await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] == "error", what="an error")

        hello, refused = talk(watching, conversation)
    assert hello == {"type": "hello", "run": RUN, "control": False, "viewer": "view-watch",
                     "reason": "it was started with --no-control", "role": "instructor", "role_reason": ""}
    assert refused == {"type": "error", "op": "stop", "slot": "", "ref": "s",
                       "error": "this view only watches (it was started with --no-control): the command was not sent"}
    assert plant[3].proc.poll() is None


def test_pause_and_resume_from_the_browser_and_the_runs_state_comes_back(plant):
    endpoint, run_dir, url, _ = plant

    async def conversation(ws):
        await greeting(ws)
        states = []

        async def command(op):
            await ws.send_str(json.dumps({"type": "command", "op": op, "ref": op}))
            while True:
                frame = await wait_for(ws, lambda f: isinstance(f, dict), what=f"the result of {op}")
                if frame["type"] == "state":
                    states.append(frame["state"])
                if frame.get("ref") == op:
                    return frame

        paused = await command("pause")
        resumed = await command("resume")
        while "paused" not in states or "running" not in states[states.index("paused"):]:
            frame = await wait_for(ws, lambda f: isinstance(f, dict) and f["type"] == "state", what="the state")
            states.append(frame["state"])
        return paused, resumed, states

    paused, resumed, states = talk(url, conversation)
    assert paused["ok"] and resumed["ok"] and resumed["tick"] >= paused["tick"]
    assert states.index("running", states.index("paused")) > states.index("paused")


def test_a_malformed_host_or_origin_is_refused_not_a_server_error(plant):
    """urlsplit raises on "[::1": the request is refused (403), not answered with a 500 and a traceback."""
    import aiohttp

    _, _, url, _ = plant

    async def main():
        async with aiohttp.ClientSession() as session:
            async with session.get(f"{url}ws", headers={"Origin": "http://[::1", "Upgrade": "websocket",
                                                         "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
                                                         "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="}) as r:
                return r.status, await r.text()
    status, text = asyncio.run(main())
    assert status == 403 and "malformed Host" in text, (status, text)


def test_a_rewind_from_the_browser_is_answered_by_the_hub_with_its_reason(plant):
    endpoint, run_dir, url, _ = plant

    async def conversation(ws):
        await greeting(ws)
        await ws.send_str(json.dumps({"type": "command", "op": "rewind", "value": 10, "ref": "back"}))
        return await wait_for(ws, lambda f: isinstance(f, dict) and f.get("ref") == "back", what="the answer")

    answer = talk(url, conversation)
    assert answer["type"] == "result" and answer["op"] == "rewind" and answer["ok"] is False, answer
    assert answer["error"].startswith("rewind 10: no checkpoint at or before tick 10 (t = "), answer
    assert answer["error"].endswith("this run has taken none yet (planthub run --checkpoint-at, --checkpoint-every, "
                                    "or planthub send RUN checkpoint)"), answer
