"""A recorded run played back in a real browser: Debian's chromium, driven by Playwright, opens
`planthub view RUN_DIR` of a recorded source_sink run, presses play and sees the bottles move, then
pauses and drags the time slider: the page shows the recorded point at or before the time it was
dragged to, and draws every bottle where the recording (read here with BodyRecording) has it.

    planthub run source_sink.yaml --record-bodies --out DIR ──► planthub view DIR ◄── http, /ws ── chromium
"""
import json
import math

import msgpack
import pytest

from hub.view.bodies_file import BodyRecording

from .helpers import ROOT
from .view_support import bodies, browser_page, playback, record

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"
RECORD = ("--set", "run.record_bodies=0.04")   # a point every 6 ticks: a seek lands between two of them
RATE = 150
POSITIONS = "window.planthub.bodies()"


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    folder = tmp_path_factory.mktemp("playback_browser")
    run_dir = record(folder, SCENARIO, *RECORD)
    with playback(folder, run_dir) as (started, url), browser_page(url, viewport=(1100, 640)) as (tab, errors):
        sent: list[dict] = []
        tab.on("websocket", lambda ws: ws.on("framesent", lambda text: sent.append(json.loads(text))))
        tab.reload()   # so that this socket's frames are seen from its first
        tab.wait_for_function("window.planthub && window.planthub.connected && window.planthub.tick === 0",
                              timeout=60_000)
        yield tab, run_dir, errors, sent
        assert started.proc.poll() is None, started.output()


def on_the_belt(positions: dict) -> dict:
    return {b: p for b, p in positions.items() if 0.15 < p[0] < 1.8}


def test_play_moves_the_bottles_and_the_slider_seeks_to_the_recorded_point(page):
    tab, run_dir, errors, sent = page
    recording = BodyRecording(run_dir)
    scene = json.loads((run_dir / "scene.json").read_text())
    assert tab.evaluate("window.planthub.hello.mode") == "playback"
    assert tab.is_visible("#playback-bar") and tab.is_disabled("#pause")
    assert tab.evaluate("window.planthub.playback") == {"time": 0, "playing": False, "speed": 1}
    assert tab.text_content("#panel-reason") == "a recorded run: nothing to operate"
    assert tab.is_disabled('button[data-slot="belt.drive.run"][data-value="false"]')

    tab.click("#play")
    tab.wait_for_function("window.planthub.playback.playing && window.planthub.tick >= 300", timeout=30_000)
    before, first = tab.evaluate(POSITIONS), tab.screenshot()
    tab.wait_for_timeout(500)
    after, second = tab.evaluate(POSITIONS), tab.screenshot()
    moved = [after[b][0] - p[0] for b, p in on_the_belt(before).items() if b in after]
    assert moved and min(moved) > 0.1, f"the bottles ride the belt (0.5 m/s of the run, played at 1×): {moved}"
    assert first != second

    tab.click("#pause")
    tab.wait_for_function("!window.planthub.playback.playing", timeout=10_000)
    box = tab.locator("#scrub").bounding_box()
    y = box["y"] + box["height"] / 2
    tab.mouse.move(box["x"] + box["width"] * 0.9, y)
    tab.mouse.down()
    for fraction in (0.8, 0.6, 0.5, 0.45):   # dragged back, through several seeks
        tab.mouse.move(box["x"] + box["width"] * fraction, y, steps=4)
    tab.mouse.up()
    tab.wait_for_timeout(500)   # the frames it sent are told to this process meanwhile
    seeks = [m for m in sent if m.get("type") == "playback" and m.get("op") == "seek"]
    assert len(seeks) >= 2, sent
    t = seeks[-1]["value"]
    i = recording.index_at(math.floor(t * RATE + 1e-6))
    tick = int(recording.ticks[i])
    assert 2.0 < t < 3.5 and tick <= t * RATE < tick + 6, (t, tick)
    tab.wait_for_function(f"window.planthub.tick === {tick} && window.planthub.playback.time === {tick / RATE}",
                          timeout=10_000)
    tab.wait_for_timeout(300)   # nothing more comes while paused
    assert tab.evaluate("window.planthub.tick") == tick
    drawn = tab.evaluate(POSITIONS)
    _, expected = bodies(msgpack.packb(recording.message(i, RATE)), scene)
    assert drawn.keys() == expected.keys() and len(drawn) >= 4
    assert all(math.dist(drawn[b], p) < 1e-6 for b, p in expected.items()), (drawn, expected)
    assert float(tab.input_value("#scrub")) == pytest.approx(tick / RATE)
    assert tab.text_content("#playback-time") == f"{tick / RATE:.2f} / 6.48 s"
    assert errors == []


def test_the_recorded_slots_are_plotted_over_the_whole_run(page):
    tab, run_dir, errors, sent = page
    assert tab.is_visible("#recorded")
    options = tab.eval_on_selector_all("#recorded-slot option", "os => os.map(o => o.value)")
    assert options == ["source.store.remaining", "sink.count.total", "sink.count.A", "sink.count.B", "bodies in play"]
    tab.select_option("#recorded-slot", "sink.count.total")
    legend = tab.text_content("#recorded .chart-legend")
    assert legend == "sink.count.total"
    assert errors == []
