"""The view in a real browser: Debian's chromium, driven by Playwright, opens `planthub view` of the
bottling plant running at half real time, sees the bottles move, and stops the magazine belt with
its Stop button — the hub records the command and the bottles on that belt stand.

    planthub run bottling_plant.yaml --realtime 0.5 --listen … ◄── Zenoh ──► planthub view ◄── http, /ws ── chromium
"""
import math

import pytest

from .helpers import ROOT
from .view_support import browser_page, command_rows, hub, view

SCENARIO = ROOT / "scenarios" / "bottling_plant.yaml"
RUN = "bottling_plant"
# The magazine b00 (x from -7.0 to 0.07, along y = 0) carries the depalletiser's bottles from the
# first second on; it first stops by itself when its first bottle reaches the separator, after
# 14 s of plant time (28 s here). Its bottles are taken from x = -6.3 on, clear of the spots where
# the depalletiser (-6.95) and the robot (-6.5, from 25 s) put them.
BELT = "b00"
STOP = f'button[data-op="force"][data-slot="{BELT}.drive.run"][data-value="false"]'


def on_the_magazine(positions: dict) -> dict:
    return {b: p for b, p in positions.items() if -6.3 < p[0] < -0.1 and abs(p[1]) < 0.05 and p[2] < 0.2}


def moved(before: dict, after: dict) -> list[float]:
    ours = on_the_magazine(after)
    return [math.dist(p, ours[b]) for b, p in on_the_magazine(before).items() if b in ours]


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    folder = tmp_path_factory.mktemp("browser")
    with hub(folder, SCENARIO, realtime=0.5) as (started, endpoint, run_dir), \
            view(folder, RUN, endpoint) as (_, url), browser_page(url) as (tab, errors):
        yield tab, run_dir, errors
        assert started.proc.poll() is None, started.output()


def test_the_page_shows_the_bottles_moving_and_its_stop_button_stops_a_belt(page):
    tab, run_dir, errors = page
    positions = "window.planthub.bodies()"
    tab.wait_for_function(f"Object.keys({positions}).filter(b => {{ const p = {positions}[b]; "
                          "return p[0] > -6.3 && p[0] < -0.1; }).length >= 3", timeout=60_000)
    before, first = tab.evaluate(positions), tab.screenshot()
    frames = tab.evaluate("window.planthub.frames")
    tab.wait_for_timeout(1000)
    after, second = tab.evaluate(positions), tab.screenshot()
    running = moved(before, after)
    assert running and min(running) > 0.05, f"the bottles on {BELT} run (0.25 m per s of wall time): {running}"
    assert first != second
    assert tab.evaluate("window.planthub.frames") > frames

    tab.click(STOP, timeout=10_000)
    rows = command_rows(run_dir, timeout=20, until=lambda rows: any(r["slot"] == f"{BELT}.drive.run" for r in rows))
    assert [(r["op"], r["slot"], r["value"], r["by"]) for r in rows] == [("force", f"{BELT}.drive.run", "false",
                                                                          "view-test")]
    # At rest 0.3 s of plant time after the command (the belt's k): measured from 0.5 s on.
    settled = int(rows[0]["tick"]) + 75
    tab.wait_for_function(f"window.planthub.tick >= {settled}", timeout=30_000)
    before = tab.evaluate(positions)
    tab.wait_for_function(f"window.planthub.tick >= {settled + 150}", timeout=30_000)
    tab.wait_for_timeout(200)   # the drawn positions follow the newest message (interpolated)
    after = tab.evaluate(positions)
    standing = moved(before, after)
    assert standing and max(standing) < 0.005, f"the bottles on {BELT} stand: {standing}"
    assert errors == []
