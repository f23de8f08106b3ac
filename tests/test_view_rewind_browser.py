"""The operator panel's checkpoint timeline in a real browser (Debian's chromium, driven by Playwright):
a paced run taking a checkpoint every 0.5 s shows them on the timeline; Rewind goes back to the one
chosen — the page's time goes back, the hub's answer is shown, commands.csv has the rewind — and a
view that only watches, joining late, shows the timeline (asked of the hub) without the button.

    planthub run switch.yaml --realtime 0.5 --checkpoint-every 0.5 ──┬── planthub view ◄── chromium tab 1
                                                                      └── planthub view --no-control (later) ◄── tab 2
"""
from __future__ import annotations

import os

import pytest

from .helpers import ROOT
from .view_support import BUNDLE, CHROMIUM, FLAGS, command_rows, hub, view

pytestmark = pytest.mark.slow   # a paced run watched in a browser

SCENARIO = ROOT / "scenarios" / "switch.yaml"
RATE = 150   # switch.yaml's physics_rate: a checkpoint every 0.5 s is one every 75 ticks
BACK = 150   # the checkpoint gone back to: t = 1 s


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    from playwright.sync_api import sync_playwright

    assert BUNDLE.is_file(), f"no {BUNDLE}: build the front-end with `make view-assets`"
    assert os.access(CHROMIUM, os.X_OK), f"no {CHROMIUM}: `make chromium` installs it"
    folder = tmp_path_factory.mktemp("rewind_browser")
    with hub(folder, SCENARIO, "--set", "run.duration=60", "--checkpoint-every", 0.5,
             realtime=0.5) as (started, endpoint, run_dir), \
            view(folder, "switch", endpoint) as (_, url), sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True, timeout=60_000)
        try:
            errors: list[str] = []

            def page(address):
                tab = browser.new_page(viewport={"width": 1100, "height": 700})
                tab.on("pageerror", lambda exc: errors.append(str(exc)))
                tab.goto(address, timeout=60_000)
                tab.wait_for_function("window.planthub && window.planthub.connected", timeout=60_000)
                return tab

            yield folder, endpoint, run_dir, page(url), page, errors
        finally:
            browser.close()
        assert started.proc.poll() is None, started.output()


def test_the_timeline_lists_the_checkpoints_and_rewind_goes_back_to_the_one_chosen(plant):
    folder, endpoint, run_dir, tab, page, errors = plant
    tab.wait_for_function("(window.planthub.checkpoints?.checkpoints.length ?? 0) >= 5", timeout=60_000)
    ticks = tab.evaluate("window.planthub.checkpoints.checkpoints")
    assert ticks[:5] == [75, 150, 225, 300, 375] and tab.evaluate("window.planthub.checkpoints.rate") == RATE
    tab.wait_for_function("document.querySelectorAll('#timeline-track .mark').length >= 5", timeout=10_000)
    options = tab.eval_on_selector_all("#rewind-to option", "os => os.map(o => [o.value, o.textContent])")
    assert ("150", "t = 1 s (tick 150)") in [tuple(o) for o in options]
    assert tab.is_visible("#rewind") and tab.is_enabled("#rewind")

    tab.select_option("#rewind-to", str(BACK))
    tab.wait_for_function("window.planthub.time >= 2.5", timeout=10_000)
    before = tab.evaluate("window.planthub.time")
    # The page's time is watched from the click on: it goes back to 1 s and on from there.
    tab.evaluate("""() => { const h = window.planthub; h.lowest = Infinity;
        setInterval(() => { if (h.time !== null) h.lowest = Math.min(h.lowest, h.time); }, 20); }""")
    tab.click("#rewind")
    tab.wait_for_function("window.planthub.results.some(r => r.op === 'rewind')", timeout=20_000)
    answer = tab.evaluate("window.planthub.results.find(r => r.op === 'rewind')")
    assert answer["ok"] is True, answer
    tab.wait_for_function(f"window.planthub.lowest < {BACK / RATE + 0.5}", timeout=20_000)
    assert tab.inner_text("#panel-result").startswith(f"{answer['id']}: ok at tick {answer['tick']}")
    rows = command_rows(run_dir, timeout=20, until=lambda rows: any(r["op"] == "rewind" for r in rows))
    assert [(r["op"], r["value"], r["by"]) for r in rows if r["op"] == "rewind"] == [("rewind", str(BACK), "view-test")]
    # The checkpoints of the branch left are forgotten: the timeline starts again from 1 s.
    tab.wait_for_function(f"window.planthub.checkpoints.time < {before}", timeout=20_000)

    with view(folder, "switch", endpoint, "--no-control", name="watcher") as (_, url):
        watcher = page(url)
        watcher.wait_for_function("(window.planthub.checkpoints?.checkpoints.length ?? 0) >= 1", timeout=30_000)
        assert watcher.evaluate("window.planthub.checkpoints.checkpoints")[:2] == [75, 150]
        assert watcher.eval_on_selector_all("#timeline-track .mark", "ms => ms.length") >= 1
        assert not watcher.is_visible("#rewind") and watcher.is_visible("#panel-reason")
    assert errors == []
