"""The view's two roles and its labels in a real browser (Debian's chromium, driven by Playwright): the
instructor's page shows the faults panel and injects a fault with it (the hub records it; a refused one
is said on the page), the trainee's page of the same run shows no faults panel and never receives a
fault; the plant's belts, sensors and switches are named on hover and by tags; the legend names every
kind of thing drawn; the camera following a bottle lets go of it when the bottle leaves the plant; the
exercise's goals show live and its score at the end.

    planthub run switch.yaml --realtime 0.1 ───┬── planthub view (instructor) ◄── chromium tab 1
      (a ─ b ─[reader]─╮blade╭─ main_end)     └── planthub view --role trainee ◄── chromium tab 2
"""
from __future__ import annotations

import json

import pytest

from .helpers import ROOT
from .view_support import command_rows, hub, two_pages, views

pytestmark = pytest.mark.slow   # one paced run (a tenth of real time, then real time), watched by two browser tabs

SCENARIO = ROOT / "scenarios" / "switch.yaml"
EXERCISE = {"task": "Deliver both bottles, each to its lane.", "goals": [{"delivered": 2, "name": "both delivered"}]}


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    folder = tmp_path_factory.mktemp("roles_browser")
    # At a tenth of real time, so the plant is still there for the tests before the camera's,
    # however slow the machine; the camera's test paces it up to real time from the panel (A
    # leaves the plant at about 4 s, the run ends at 5 s).
    with hub(folder, SCENARIO, "--set", "run.duration=5", "--set", f"exercise={json.dumps(EXERCISE)}",
             realtime=0.1) as (started, endpoint, run_dir), \
            views(folder, "switch", endpoint, ("instructor", ()), ("trainee", ("--role", "trainee"))) as both, \
            two_pages(*(url for _, url in both)) as ((teacher, pupil), errors):
        yield teacher, pupil, run_dir, errors


def test_the_instructor_injects_a_fault_from_the_panel_and_the_trainee_sees_none(pages):
    teacher, pupil, run_dir, errors = pages
    teacher.wait_for_function("window.planthub.faults !== null", timeout=30_000)
    assert teacher.is_visible("#faults-box") and not pupil.is_visible("#faults-box")
    assert teacher.inner_text("#role") == "instructor" and pupil.inner_text("#role") == "trainee"
    targets = teacher.evaluate("window.planthub.faults.kinds.part_stuck.targets")
    assert targets == ["sw.blade"]

    teacher.select_option("#fault-kind", "belt_failure")
    assert teacher.eval_on_selector_all("#fault-target option", "os => os.map(o => o.value)") == \
        teacher.evaluate("window.planthub.faults.kinds.belt_failure.targets")
    teacher.select_option("#fault-target", "sw.main")
    teacher.fill('#fault-params [data-param="speed"]', "0.5")
    teacher.fill("#fault-for", "0.2")
    teacher.click("#fault-inject")
    teacher.wait_for_function("window.planthub.results.some(r => r.op === 'fault' && r.ok)", timeout=20_000)
    rows = command_rows(run_dir, 20, lambda rows: any(r["op"] == "repair" for r in rows))
    assert [(r["op"], r["slot"], r["by"]) for r in rows] == [("fault", "sw.main", "instructor"),
                                                            ("repair", "sw.main", "instructor")]
    assert json.loads(rows[0]["value"]) == {"name": "live 1: belt_failure sw.main", "kind": "belt_failure",
                                            "speed": 0.5, "for": 0.2}
    teacher.wait_for_function("window.planthub.events.some(r => r[1] === '@fault')", timeout=20_000)

    # A target the hub does not know (put into the list by hand): its refusal is said on the page.
    teacher.evaluate("""() => { const o = document.createElement('option'); o.value = 'sw.mian';
                                document.querySelector('#fault-target').append(o); }""")
    teacher.select_option("#fault-target", "sw.mian")
    teacher.click("#fault-inject")
    teacher.wait_for_function("window.planthub.results.some(r => r.op === 'fault' && r.ok === false)",
                              timeout=20_000)
    said = teacher.inner_text("#fault-result")
    assert "refused: fault live 2: belt_failure sw.mian: object 'sw' has no component 'mian'" in said, said

    # The trainee's page, connected all along, has seen the plant and none of it.
    pupil.wait_for_function("window.planthub.figures !== null", timeout=20_000)
    assert pupil.evaluate("window.planthub.faults") is None
    assert pupil.evaluate("window.planthub.events.filter(r => r[1] === '@fault').length") == 0
    assert pupil.evaluate("window.planthub.results.length") == 0
    assert "faults" not in pupil.evaluate("Object.keys(window.planthub.figures.sections)")
    assert errors == []


def test_belts_sensors_and_switches_are_named_by_tags_and_on_hover_and_the_legend_is_complete(pages):
    teacher, _, _, errors = pages
    assert teacher.evaluate("window.planthub.labels()") == []   # off by default
    assert not teacher.is_visible("#tags")
    teacher.check("#labels")
    tags = teacher.evaluate("window.planthub.labels()")
    named = sorted((t["kind"], t["object"]) for t in tags)
    assert named == [("belt", "sw"), ("belt", "sw"), ("part", "sw"), ("trigger", "branch_end"),
                     ("trigger", "main_end"), ("trigger", "reader")], named   # the switch's main belt and branch
    assert sorted(teacher.eval_on_selector_all("#tags .tag", "ts => ts.map(t => t.textContent)")) == \
        ["branch_end", "main_end", "reader", "sw", "sw", "sw"]

    # A bottle crossing the reader's beam is in front of it, and the hover rightly names the bottle:
    # hover again (away and back) until none is, within the 2 s of plant time a crossing takes.
    reader = next(t for t in tags if t["object"] == "reader")
    said = ""
    for _ in range(40):
        teacher.mouse.move(0, 0)
        teacher.mouse.move(*reader["at"])
        teacher.wait_for_selector("#tooltip:not([hidden])", timeout=5_000)
        said = teacher.inner_text("#tooltip")
        if not said.startswith("bottle"):
            break
        teacher.wait_for_timeout(500)
    assert "reader" in said and "sensor" in said, said
    teacher.uncheck("#labels")
    assert teacher.evaluate("window.planthub.labels()") == [] and not teacher.is_visible("#tags")

    drawn = set(teacher.evaluate("window.planthub.scene.items.map(i => i.kind)"))
    legend = set(teacher.eval_on_selector_all("#legend [data-kind]", "es => es.map(e => e.dataset.kind)"))
    assert drawn <= legend, f"drawn but not in the legend: {drawn - legend}"
    states = teacher.eval_on_selector_all("#legend [data-state]", "es => es.map(e => e.dataset.state)")
    assert states == ["empty", "filled", "capped", "followed"]
    assert errors == []


def test_the_camera_lets_go_of_a_bottle_that_leaves_the_plant_and_the_score_shows_at_the_end(pages):
    teacher, pupil, _, errors = pages
    teacher.wait_for_function("'A' in window.planthub.bodies()", timeout=60_000)
    teacher.select_option("#follow", "A")
    assert teacher.input_value("#follow") == "A"
    teacher.fill("#pace-value", "1")   # the instructor's panel: on at real time
    teacher.click("#pace")
    teacher.wait_for_function("window.planthub.results.some(r => r.op === 'pace' && r.ok)", timeout=20_000)
    # A runs along the main line into main_end, whose sink takes it out of the plant.
    teacher.wait_for_function("window.planthub.lost.includes('A')", timeout=60_000)
    assert teacher.input_value("#follow") == ""
    assert "A left the plant" in teacher.inner_text("#camera-note")
    assert "A" not in teacher.eval_on_selector_all("#follow option", "os => os.map(o => o.value)")

    for page in (teacher, pupil):   # the exercise: its goal live, and the score once the run ended
        page.wait_for_function("window.planthub.exercise && window.planthub.exercise.ended", timeout=90_000)
        assert page.inner_text("#exercise .task") == EXERCISE["task"]
        assert page.get_attribute('#exercise [data-goal="both delivered"]', "class") == "goal met"
        assert page.inner_text("#exercise-score").startswith("Score: 100 % (1 of 1 points) — passed")
    assert errors == []
