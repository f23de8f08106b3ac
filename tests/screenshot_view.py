"""`make screenshot`: the bottling plant in `planthub view`, shot in headless chromium for the README (hub/view/bottling_plant.png).

    planthub run bottling_plant.yaml --realtime --listen … ◄── Zenoh ──► planthub view ◄── http, /ws ── chromium (Playwright)

`python -m tests.screenshot_view OUT.png`: the plant runs paced at real time on loopback; once about
BOTTLES bottles are on the line the camera is framed on the plant (the page's Fit button) and the
page is shot at 1280×800. Every process started here is stopped, however it ends.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from .helpers import ROOT
from .view_support import hub, view

SCENARIO = ROOT / "scenarios" / "bottling_plant.yaml"
RUN = "bottling_plant"
CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]
BUNDLE = ROOT / "build" / "view" / "index.html"
SIZE = {"width": 1280, "height": 800}
BOTTLES = 40        # bottles in play when the picture is taken: the magazine and the filler busy
SETTLE_MS = 1500    # after Fit: the camera's damping comes to rest and the newest samples are drawn


def shoot(out: Path) -> int:
    """The picture in `out`; the number of bottles it shows."""
    from playwright.sync_api import sync_playwright

    if not BUNDLE.is_file():
        raise SystemExit(f"no {BUNDLE}: build the front-end with `make view-assets`")
    with tempfile.TemporaryDirectory() as tmp, hub(Path(tmp), SCENARIO, "-q") as (started, endpoint, _), \
            view(Path(tmp), RUN, endpoint, name="screenshot") as (_, url), sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True, timeout=60_000)
        try:
            page = browser.new_page(viewport=SIZE)
            errors: list[str] = []
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.goto(url, timeout=60_000)
            page.wait_for_function("window.planthub && window.planthub.connected && window.planthub.scene",
                                   timeout=60_000)
            page.wait_for_function(f"Object.keys(window.planthub.bodies()).length >= {BOTTLES}", timeout=120_000,
                                   polling=250)
            page.click("#fit")
            page.wait_for_timeout(SETTLE_MS)
            shown = len(page.evaluate("window.planthub.bodies()"))
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
            if errors:
                raise SystemExit(f"the page failed: {errors}")
        finally:
            browser.close()
        if started.proc.poll() is not None:
            raise SystemExit("the run ended before the picture was taken:\n" + "\n".join(started.output()))
    return shown


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        raise SystemExit("usage: python -m tests.screenshot_view OUT.png")
    out = Path(argv[0])
    shown = shoot(out)
    print(f"{out}: the bottling plant with {shown} bottles, {SIZE['width']}×{SIZE['height']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
