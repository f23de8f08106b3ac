"""The command line as a user meets it: exit codes, messages, outputs."""
import subprocess
import sys
from pathlib import Path

from .helpers import ROOT


def planthub(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_validate_ok():
    proc = planthub("validate", "scenarios/belt_bottle_sensor.yaml")
    assert proc.returncode == 0
    assert proc.stdout == ("scenarios/belt_bottle_sensor.yaml: ok — 3 objects, 0 flows, 3 recorded slots, "
                           "3.5 s at 150 Hz\n")


def test_validate_reports_problems_on_stderr_with_exit_code_2(write_scenario):
    path = write_scenario("planthub: 1\nobjects:\n  b: {module: botle, position: [0, 0, 0]}\n")
    proc = planthub("validate", path)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == (f"planthub: 1 problem in scenario:\n"
                           f"  - {path}:3: objects.b.module: unknown module 'botle' (did you mean 'bottle'?)\n")


def test_bad_set_option_is_named():
    proc = planthub("validate", "scenarios/belt_bottle_sensor.yaml", "--set", "run.physics_rate")
    assert proc.returncode == 2
    assert "--set: expected KEY=VALUE, got 'run.physics_rate'" in proc.stderr


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
    assert "| drive.speed           | real | target |" in conveyor.stdout   # the module's slot table


def test_describe_unknown_module_suggests():
    proc = planthub("describe", "convayor")
    assert proc.returncode == 2
    assert proc.stderr == "planthub: unknown module 'convayor' (did you mean 'conveyor'?)\n"


def test_console_script_is_installed():
    script = Path(sys.executable).parent / "planthub"   # installed beside the interpreter by make
    proc = subprocess.run([str(script), "describe", "bottle"], capture_output=True, text=True)
    assert proc.returncode == 0 and "tag.id" in proc.stdout
