"""The command line as a user meets it: exit codes, messages, outputs, help, -v/-q, JUnit."""
import argparse
import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from datetime import datetime
from pathlib import Path
from xml.etree import ElementTree

import pytest

from hub.bus.session import free_loopback_endpoint
from hub.cli.exits import TABLE
from hub.cli.main import parser

from .bus_support import output_of, process
from .fmus.fmu_support import build
from .helpers import ROOT


@pytest.fixture(scope="module")
def fmus():
    return build(ROOT / "build" / "fmus")


def planthub(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_validate_ok():
    proc = planthub("validate", "scenarios/belt_bottle_sensor.yaml")
    assert proc.returncode == 0
    assert proc.stdout == ("scenarios/belt_bottle_sensor.yaml: ok — 3 objects, 0 flows, 3 recorded slots, "
                           "3.5 s at 150 Hz\n")


def test_validate_reports_problems_on_stderr_with_exit_code_3(write_scenario):
    path = write_scenario("planthub: 1\nobjects:\n  b: {module: botle, position: [0, 0, 0]}\n")
    proc = planthub("validate", path)
    assert proc.returncode == 3 and proc.stdout == ""
    assert proc.stderr == (f"planthub: 1 problem in scenario:\n"
                           f"  - {path}:3: objects.b.module: unknown module 'botle' (did you mean 'bottle'?)\n")


def test_bad_set_option_is_named():
    proc = planthub("validate", "scenarios/belt_bottle_sensor.yaml", "--set", "run.physics_rate")
    assert proc.returncode == 2
    assert "planthub validate: error: argument --set: expected KEY=VALUE, got 'run.physics_rate'\n" in proc.stderr


def test_run_writes_recording_and_event_log(tmp_path):
    proc = planthub("run", "scenarios/stop_at_barrier.yaml", "--out", tmp_path / "o", "--set", "run.duration=3")
    assert proc.returncode == 0, proc.stderr
    header = (tmp_path / "o" / "recording.csv").read_text().splitlines()[0]
    assert header.startswith('"time","bottle.body.position.x","bottle.body.position.y"')
    events = (tmp_path / "o" / "events.csv").read_text().splitlines()
    assert events[0] == "time,tick,slot,detail" and events[1].endswith(",barrier.trigger.on_enter,bottle")
    assert f"recording    {tmp_path / 'o' / 'recording.csv'}" in proc.stdout
    assert "simulated    3.000 s  (450 ticks at 150 Hz, communication step 20 ms)" in proc.stdout


def test_describe_lists_modules_and_a_modules_slots():
    listing = planthub("describe")
    assert listing.returncode == 0
    from modules import CATALOGUE

    assert [line.split()[0] for line in listing.stdout.splitlines()] == sorted(CATALOGUE)
    conveyor = planthub("describe", "conveyor")
    assert "  drive.speed            real    target  target belt speed, m/s" in conveyor.stdout
    assert "  length         required" in conveyor.stdout


def test_describe_unknown_module_suggests():
    proc = planthub("describe", "convayor")
    assert proc.returncode == 2
    assert proc.stderr == "planthub: unknown module 'convayor' (did you mean 'conveyor'?)\n"


def test_describe_a_thing_a_module_is_suggests_the_modules_that_are_one():
    """A newcomer's `belt` is no module's name; the modules whose descriptions start by calling
    themselves one are suggested, and an unknown word gets the names there are."""
    from hub.core.registry import default_registry

    registry = default_registry()
    assert registry.suggest("belt") == (" (did you mean 'conveyor' or 'curve' or 'pusher' or 'stopper'? their "
                                        "descriptions say 'belt')")
    assert registry.suggest("gate") == " (did you mean 'stopper'? their descriptions say 'gate')"
    assert registry.suggest("xyzzy") == f" (known: {', '.join(registry.names())})"


def test_console_script_is_installed():
    script = Path(sys.executable).parent / "planthub"   # installed beside the interpreter by make
    proc = subprocess.run([str(script), "describe", "bottle"], capture_output=True, text=True)
    assert proc.returncode == 0 and "tag.id" in proc.stdout


# --- conventions: version, help, exit codes, -v/-q, the summary, describe, JUnit -------------------

def test_version_is_the_installed_distributions():
    from importlib.metadata import version

    proc = planthub("--version")
    assert proc.returncode == 0 and proc.stdout == f"planthub {version('planthub')}\n"


def test_run_help_shows_an_example_and_the_exit_codes():
    proc = planthub("run", "--help")
    assert proc.returncode == 0
    assert "example:\n  planthub run scenarios/stop_at_barrier.yaml --set run.duration=3 --out runs/short\n" in proc.stdout
    assert TABLE in proc.stdout
    assert TABLE in planthub("--help").stdout


def test_every_subcommand_and_positional_has_help_and_every_subcommand_an_example():
    top, handlers = parser()
    (sub,) = [a for a in top._actions if isinstance(a, argparse._SubParsersAction)]
    helped = {choice.dest: choice.help for choice in sub._choices_actions}
    assert sorted(helped) == sorted(sub.choices) == sorted(handlers)
    for name, command in sub.choices.items():
        assert helped[name], f"`planthub --help` shows no help for {name}"
        text = command.format_help()
        assert f"example:\n  planthub {name} " in text, f"`planthub {name} --help` shows no example"
        assert "-v, --verbose" in text and "-q, --quiet" in text, f"{name} takes no -v/-q"
        for action in command._actions:
            if not action.option_strings:
                assert action.help, f"planthub {name}: the positional {action.dest!r} has no help"


def test_a_usage_error_exits_2_with_the_usage():
    proc = planthub("run", "scenarios/stop_at_barrier.yaml", "--no-such-option")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("usage: planthub run ")
    assert proc.stderr.endswith("planthub run: error: unrecognized arguments: --no-such-option\n")


def test_a_set_value_that_is_no_yaml_is_a_usage_error():
    proc = planthub("validate", "scenarios/belt_bottle_sensor.yaml", "--set", "objects.belt.k=[1")
    assert proc.returncode == 2
    assert "planthub validate: error: argument --set: objects.belt.k=[1: not valid YAML: " in proc.stderr


def test_an_expectation_that_fails_exits_1(write_scenario):
    path = write_scenario(SENSOR_WITH_EXPECTATIONS)
    proc = planthub("test", path)
    assert proc.returncode == 1, proc.stderr
    assert proc.stdout.splitlines()[-1] == "1 passed, 1 failed"


FAILING = """
    planthub: 1
    run: {duration: 1}
    objects:
      belt: {module: conveyor, position: [0, 0, 0], length: 2}
      drive:
        module: participant
        inputs: {run: bool}
        outputs: {speed: real}
        command: [python, -c, "raise SystemExit(3)"]
    flows:
      - {from: drive.logic.speed, to: belt.drive.speed}
    """


def test_a_run_that_fails_exits_1_and_its_summary_says_how(write_scenario, tmp_path):
    path = write_scenario(FAILING)
    proc = planthub("run", path, "--out", tmp_path / "out")
    assert proc.returncode == 1
    assert "  failed       failed at t = 0 s: participant 'drive': its process exited with code 3 before it could " \
           "join" in proc.stdout.splitlines()
    assert proc.stderr.splitlines()[-2:] == [
        "planthub: waiting for participant 'drive' to join (launched, up to 10 s)",
        "planthub: participant 'drive': its process exited with code 3 before it could join"]
    ended = json.loads((tmp_path / "out" / "summary.json").read_text())["ended"]
    assert ended == {"kind": "failed", "reason": "failed at t = 0 s: participant 'drive': its process exited "
                                                 "with code 3 before it could join"}


def test_a_test_whose_run_fails_is_an_error_in_the_junit_file(write_scenario, tmp_path):
    path = write_scenario(textwrap.dedent(FAILING) + "expect:\n  - {name: the belt runs, slot: belt.drive.speed, is: {'>': 0}}\n")
    proc = planthub("test", path, "--junit", tmp_path / "report.xml")
    assert proc.returncode == 1 and proc.stdout == ""
    suite = ElementTree.parse(tmp_path / "report.xml").getroot().find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("1", "0", "1")
    (case,) = suite.findall("testcase")
    assert case.get("name") == "the run"
    assert case.find("error").get("message") == ("participant 'drive': its process exited with code 3 "
                                                 "before it could join")


def test_a_test_of_a_scenario_that_does_not_load_is_an_error_in_the_junit_file(write_scenario, tmp_path):
    """CI reads the report: a bad scenario is an error there, not a missing file (exit 3 still)."""
    path = write_scenario("planthub: 1\nobjects:\n  b: {module: botle}\n")
    proc = planthub("test", path, "--junit", tmp_path / "report.xml")
    assert proc.returncode == 3
    suite = ElementTree.parse(tmp_path / "report.xml").getroot().find("testsuite")
    assert (suite.get("name"), suite.get("tests"), suite.get("errors")) == (path.stem, "1", "1")
    (case,) = suite.findall("testcase")
    assert case.get("name") == "the run"
    assert f"{path}:3: objects.b.module: unknown module 'botle' (did you mean 'bottle'?)" in case.find("error").text


@pytest.mark.slow
def test_a_plants_event_table_is_listed_with_v(tmp_path):
    """More kinds of event than the summary lists one a line (the bottling plant's) are counted;
    -v lists them. (The routing runs in the hub: where it runs changes no event, and it saves
    starting a participant twice.)"""
    args = ("run", "scenarios/bottling_plant.yaml", "--set", "run.duration=30", "--set", "objects.control.runs=hub")
    plain, verbose = planthub(*args, "--out", tmp_path / "plain"), planthub(*args, "--out", tmp_path / "v", "-v")
    assert plain.returncode == verbose.returncode == 0, plain.stderr + verbose.stderr
    (events,) = [line for line in plain.stdout.splitlines() if line.startswith("  events ")]
    assert events.endswith("slots, listed with -v and in events.csv)")
    assert "×  first at" not in plain.stdout
    assert sum("×  first at" in line for line in verbose.stdout.splitlines()) > 12


def test_quiet_silences_the_notices_and_keeps_the_summary(tmp_path):
    args = ("run", "scenarios/stop_at_barrier.yaml", "--bus", "--set", "run.duration=1", "--out", tmp_path)
    loud, quiet = planthub(*args), planthub(*args, "-q")
    assert loud.returncode == quiet.returncode == 0
    assert loud.stderr.startswith("planthub: run 'stop_at_barrier' on the bus (peer, tcp/127.0.0.1:")
    assert quiet.stderr == ""
    assert quiet.stdout.startswith("planthub run stop_at_barrier  (scenarios/stop_at_barrier.yaml)\n")
    assert "  bus          0 participants, " in quiet.stdout


def test_zenohs_log_goes_to_stderr_as_rust_log_says(tmp_path):
    env = {**os.environ, "RUST_LOG": "zenoh=info", "NO_COLOR": "1"}
    proc = subprocess.run([sys.executable, "-m", "hub", "run", "scenarios/stop_at_barrier.yaml", "--bus",
                           "--set", "run.duration=1", "--out", str(tmp_path)],
                          capture_output=True, text=True, cwd=ROOT, env=env)
    assert proc.returncode == 0, proc.stderr
    assert " INFO " in proc.stderr and "zenoh::" in proc.stderr   # Zenoh's own lines, on stderr
    assert "zenoh::" not in proc.stdout and proc.stdout.startswith("planthub run stop_at_barrier  ")


def test_the_event_table_leaves_the_logics_events_to_verbose(fmus, tmp_path):
    plain = planthub("run", "scenarios/switch_logic.yaml", "--out", tmp_path / "plain")
    verbose = planthub("run", "scenarios/switch_logic.yaml", "--out", tmp_path / "verbose", "-v")
    assert plain.returncode == verbose.returncode == 0, plain.stderr + verbose.stderr
    assert "  events       12  (2 of them inside the logic, listed with -v)" in plain.stdout.splitlines()
    assert "    sw.blade.on_working " in plain.stdout and "sw.logic." not in plain.stdout
    assert "  events       12" in verbose.stdout.splitlines()
    assert "    sw.logic.WorkingPosStartAnim_got     1×  first at 0.1133 s" in verbose.stdout.splitlines()
    events = json.loads((tmp_path / "plain" / "summary.json").read_text())["events"]
    assert len(events) == 10   # summary.json keeps every event, each marked
    assert [slot for slot, e in events.items() if e["logic"]] == ["sw.logic.WorkingPosStartAnim_got",
                                                                  "sw.logic.BasePosStartAnim_got"]


def test_the_summary_opens_with_how_the_run_ended_then_the_plants_figures(tmp_path):
    sensor = planthub("run", "scenarios/belt_bottle_sensor.yaml", "--out", tmp_path / "sensor")
    assert sensor.stdout.splitlines()[1] == "  ended        reached its duration at t = 3.5 s (run.duration)"
    assert json.loads((tmp_path / "sensor" / "summary.json").read_text())["ended"] == {
        "kind": "duration", "reason": "reached its duration at t = 3.5 s (run.duration)"}
    plant = planthub("run", "scenarios/source_sink.yaml", "--out", tmp_path / "plant", "--set", "run.orders=4")
    starts = [line.split()[0] for line in plant.stdout.splitlines() if line.startswith("  ") and line[2] != " "]
    assert starts[:9] == ["ended", "bottles", "delivered", "misrouted", "on", "throughput", "jams", "orders", "simulated"]
    assert json.loads((tmp_path / "plant" / "summary.json").read_text())["ended"]["kind"] == "completed"


def test_ctrl_c_exits_130_with_the_summary_so_far(tmp_path):
    with process("-m", "hub", "run", "scenarios/stop_at_barrier.yaml", "--realtime", "1", "-v",
                 "--set", "run.duration=600", "--out", tmp_path) as proc:
        line = proc.stderr.readline()   # said once the run is under way
        assert line == f"planthub: running stop_at_barrier to t = 600 s, writing to {tmp_path}\n"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err == "planthub: SIGINT: the run stops at the next communication point\n"   # not said twice
    assert "\n  stopped      interrupted by SIGINT at t = " in out
    assert json.loads((tmp_path / "summary.json").read_text())["ended"]["kind"] == "stopped"


INTERRUPTED = """
    planthub: 1
    run: {duration: 600, communication_step: 0.02}
    objects:
      belt: {module: conveyor, position: [0, 0, 0], length: 2, speed: 0.5}
      bottle: {module: bottle, position: [0.04, 0, 0]}
      gate: {module: light_barrier, position: [1.5, 0, 0.05]}
    record: [bottle.body.position]
    expect:
      - {name: the belt runs at 0.1 s, slot: belt.drive.running, at: 0.1, is: {"==": true}}
      - {name: the belt runs at 500 s, slot: belt.drive.running, at: 500, is: {"==": true}}
      - {name: the belt runs at the end, slot: belt.drive.running, is: {"==": true}}
      - {name: the belt never runs, slot: belt.drive.running, always: {"==": false}}
      - {name: nothing passes the gate, slot: gate.trigger.on_enter, always: {"==": false}}
    """


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_a_signal_during_planthub_test_judges_what_ran_and_writes_the_junit_file(write_scenario, tmp_path,
                                                                                 signum, status):
    """Interrupted at about 0.5 s of a 600 s run (paced to the wall clock), before the bottle reaches
    the gate at 2.9 s: a value at a time it reached is judged, and so is an `always` it broke; what
    the rest of the run could change is not judged, and says why."""
    path = write_scenario(INTERRUPTED)
    out, junit = tmp_path / "out", tmp_path / "report.xml"
    with process("-m", "hub", "test", path, "--realtime", "1", "--out", out, "--junit", junit) as proc:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (
                (out / "recording.csv").is_file() and len((out / "recording.csv").read_text().splitlines()) > 2):
            time.sleep(0.05)   # rows are flushed every 0.5 s of wall time: the run is under way
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=60)
    name = signal.Signals(signum).name
    assert proc.returncode == status, stderr
    assert stderr == f"planthub: {name}: the run stops at the next communication point\n"
    lines = stdout.splitlines()
    t = re.fullmatch(rf"  stopped      interrupted by {name} at t = ([0-9.]+) s", lines[1]).group(1)
    assert 0.2 < float(t) < 2.9
    assert lines[0] == f"planthub test scene  ({path}, {t} s simulated)"
    when = f"not judged: the run was interrupted at t = {t} s"
    assert lines[2:5] == ["  ✓ the belt runs at 0.1 s — belt.drive.running was True at 0.1 s",
                          f"  ? the belt runs at 500 s — {when}, before 500 s",
                          f"  ? the belt runs at the end — {when} (so far: belt.drive.running was True at {t} s)"]
    assert lines[5].startswith("  ✗ the belt never runs — failed ") and "at 0 s it was True" in lines[5]
    assert lines[6:] == [f"  ? nothing passes the gate — {when} (so far: held)", "1 passed, 1 failed, 3 not judged"]
    assert json.loads((out / "summary.json").read_text())["ended"] == {
        "kind": "stopped", "reason": f"interrupted by {name} at t = {t} s"}
    suite = ElementTree.parse(junit).getroot().find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("skipped")) == ("6", "2", "3")
    cases = {c.get("name"): c for c in suite.findall("testcase")}
    assert cases["the run"].find("failure").get("message") == f"interrupted by {name} at t = {t} s"
    assert cases["the belt never runs"].find("failure") is not None
    assert cases["the belt runs at the end"].find("skipped").get("message") == (
        f"{when} (so far: belt.drive.running was True at {t} s)")
    assert [c.find("failure") is None and c.find("skipped") is None for c in cases.values()] == [
        True, False, False, False, False, False]
    assert ("ended", f"interrupted by {name} at t = {t} s") in [(p.get("name"), p.get("value"))
                                                                 for p in suite.find("properties")]


def test_describe_gives_each_parameters_form_and_an_example_that_works(write_scenario):
    proc = planthub("describe", "source")
    assert proc.returncode == 0
    lines = proc.stdout.splitlines()
    at = lines.index("  bottles        optional           the bottles in release order")
    form, example = lines[at + 1], lines[at + 2]
    assert form == (" " * 17 + "form: a list of one or more mappings "
                    "{id: a non-empty string (required); destination: a string}")
    assert example == " " * 17 + "e.g.  bottles: [{id: P1, destination: A}, {id: P2, destination: B}]"
    assert lines[lines.index("  count          optional           instead of `bottles`: how many to make") + 1] \
        == " " * 17 + "form: an integer ≥ 1"
    assert all(lines[i + 1].startswith(" " * 17 + "form: ") for i, line in enumerate(lines)
               if line.startswith("  ") and lines.index("parameters:") < i < lines.index("slots:")
               and not line.startswith(" " * 17))
    path = write_scenario(f"""
        planthub: 1
        objects:
          source: {{module: source, position: [0, 0, 0], {example.split("e.g.  ")[1]}}}
        """)
    checked = planthub("validate", path)
    assert checked.returncode == 0, checked.stderr


def test_junit_carries_timestamp_case_times_seed_overrides_and_the_runs_output(write_scenario, tmp_path):
    path = write_scenario(SENSOR_WITH_EXPECTATIONS)
    proc = planthub("test", path, "--junit", tmp_path / "report.xml", "--set", "run.seed=7",
                    "--set", "objects.belt.speed=0.5")
    assert proc.returncode == 1, proc.stderr
    suite = ElementTree.parse(tmp_path / "report.xml").getroot().find("testsuite")
    datetime.fromisoformat(suite.get("timestamp"))
    assert suite.get("hostname")
    properties = [(p.get("name"), p.get("value")) for p in suite.find("properties")]
    assert properties == [("scenario", str(path)), ("seed", "7"), ("set", "run.seed=7"),
                          ("set", "objects.belt.speed=0.5"),
                          ("ended", "reached its duration at t = 3.5 s (run.duration)")]
    cases = suite.findall("testcase")
    assert [c.get("name") for c in cases] == ["the bottle reaches the gate", "nothing passes the gate"]
    assert all(float(c.get("time")) >= 0 for c in cases)
    assert [c.find("failure") is not None for c in cases] == [False, True]
    output = suite.find("system-out").text
    assert output.startswith("planthub run scene  (")
    assert "    gate.trigger.on_enter     1×  first at 2.9200 s  (bottle)" in output


def test_test_takes_the_run_options_and_says_what_it_waits_for(tmp_path):
    endpoint = free_loopback_endpoint()
    scene = tmp_path / "joined.yaml"
    text = (ROOT / "scenarios" / "belt_ramp_participant.yaml").read_text()
    scene.write_text(text.replace("    command: [python, -m, modules.belt_drive_logic]\n", "    join_timeout: 60\n")
                     + "expect:\n  - {name: the belt stops at the barrier, slot: drive.logic.running, is: {'==': false}}\n")
    with process("-m", "hub", "test", scene, "--listen", endpoint) as hub:
        assert hub.stderr.readline() == f"planthub: run 'joined' on the bus (peer, {endpoint}): plant/joined/**\n"
        assert hub.stderr.readline() == "planthub: waiting for participant 'drive' to join (up to 60 s)\n"
        with process("-m", "modules.belt_drive_logic", "--run", "joined", "--name", "drive",
                     "--connect", endpoint) as participant:
            out, err = hub.communicate(timeout=120)
            assert output_of(participant)[0] == 0
    assert hub.returncode == 0, out + err
    assert out.splitlines()[-2:] == ["  ✓ the belt stops at the barrier — drive.logic.running was False at 6 s",
                                     "1 passed, 0 failed"]


SENSOR_WITH_EXPECTATIONS = """
    planthub: 1
    run: {duration: 3.5}
    objects:
      belt: {module: conveyor, position: [0, 0, 0], length: 2}
      bottle: {module: bottle, position: [0.04, 0, 0]}
      gate: {module: light_barrier, position: [1.5, 0, 0.05]}
    expect:
      - {name: the bottle reaches the gate, slot: gate.trigger.occupied, at: 3.0, is: {"==": true}}
      - {name: nothing passes the gate, slot: gate.trigger.on_enter, always: {"==": false}}
    """
