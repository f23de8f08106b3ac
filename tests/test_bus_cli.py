"""The command line on the bus: a paced run an operator stops with `planthub send`, its replay, errors."""
import subprocess
import sys

import pytest

from hub.bus.session import free_loopback_endpoint

from .bus_support import process, same_files
from .fmus.fmu_support import build
from .helpers import ROOT


def planthub(*args, timeout=120):
    return subprocess.run([sys.executable, "-m", "hub", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=timeout)


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


def test_an_operator_stops_a_paced_run_and_the_replay_stops_at_the_same_tick(tmp_path):
    endpoint = free_loopback_endpoint()
    with process("-m", "hub", "run", "scenarios/belt_ramp_participant.yaml", "--realtime", "2",
                 "--listen", endpoint, "--out", tmp_path / "live") as run:
        # The hub may take seconds to start on a busy machine: the command waits for it up to 30 s.
        sent = planthub("send", "belt_ramp_participant", "stop", "--connect", endpoint, "--by", "test",
                        "--timeout", "30")
        out, err = run.communicate(timeout=60)
    assert sent.returncode == 0, sent.stderr
    assert sent.stdout.startswith("stop applied at tick ")
    tick = int(sent.stdout.split()[-1])
    assert run.returncode == 0, err
    assert f"  stopped      stopped by an operator at t = {tick / 150:.9g} s\n" in out
    assert "  pacing       paced at 2× real time, " in out
    assert f"planthub: run 'belt_ramp_participant' on the bus (peer, {endpoint})" in err

    replay = planthub("run", "scenarios/belt_ramp_participant.yaml", "--replay", tmp_path / "live",
                      "--out", tmp_path / "replay")
    assert replay.returncode == 0, replay.stderr
    assert same_files(tmp_path / "live", tmp_path / "replay", ("recording.csv", "events.csv", "commands.csv"))


def test_a_replay_does_not_overwrite_its_source(tmp_path):
    (tmp_path / "events.csv").write_text("time,tick,slot,detail\n")
    proc = planthub("run", "scenarios/stop_at_barrier.yaml", "--replay", tmp_path, "--out", tmp_path)
    assert proc.returncode == 2   # a usage error
    assert proc.stderr == f"planthub: --out {tmp_path} is the run being replayed; write the replay elsewhere\n"


def test_replaying_a_folder_that_is_no_run_is_named(tmp_path):
    proc = planthub("run", "scenarios/stop_at_barrier.yaml", "--replay", tmp_path / "nothing", "--out", tmp_path / "o")
    assert proc.returncode == 1
    assert proc.stderr == f"planthub: {tmp_path / 'nothing'}: not a run folder (no recording.csv or events.csv)\n"


def test_send_without_a_hub_says_so():
    endpoint = free_loopback_endpoint()
    proc = planthub("send", "nowhere", "stop", "--connect", endpoint, "--timeout", "0.5")
    assert proc.returncode == 1
    assert proc.stderr == f"planthub: run 'nowhere': no hub seen within 0.5 s ({endpoint})\n"


def test_serve_fmu_names_a_bad_file(tmp_path):
    proc = planthub("serve-fmu", tmp_path / "x.fmu", "--run", "r", "--name", "drive")
    assert proc.returncode == 1
    assert proc.stderr == f"planthub: {tmp_path / 'x.fmu'}: no such FMU file\n"


def test_realtime_needs_a_positive_factor():
    proc = planthub("run", "scenarios/stop_at_barrier.yaml", "--realtime", "0")
    assert proc.returncode == 2   # a usage error: argparse's, with the usage
    assert proc.stderr.endswith("planthub run: error: argument --realtime: needs a positive factor, got 0\n")


def test_an_instructor_sends_a_fault_and_the_replay_applies_it_again(tmp_path):
    endpoint = free_loopback_endpoint()
    with process("-m", "hub", "run", "scenarios/stop_at_barrier.yaml", "--realtime", "1",
                 "--listen", endpoint, "--out", tmp_path / "live") as run:
        sent = planthub("send", "stop_at_barrier", "fault", "belt.drive", "{name: slow, kind: belt_failure, speed: 0.5}",
                        "--connect", endpoint, "--by", "teacher")
        bad = planthub("send", "stop_at_barrier", "fault", "belt", "{name: x, kind: belt_failure}",
                       "--connect", endpoint)
        out, err = run.communicate(timeout=60)
    assert sent.returncode == 0, sent.stderr
    assert sent.stdout.startswith("fault belt.drive applied at tick ")
    assert bad.returncode == 1 and "fault x: name the component: belt.drive" in bad.stderr, bad.stderr
    assert run.returncode == 0, err
    replay = planthub("run", "scenarios/stop_at_barrier.yaml", "--replay", tmp_path / "live", "--out", tmp_path / "replay")
    assert replay.returncode == 0, replay.stderr
    assert same_files(tmp_path / "live", tmp_path / "replay", ("recording.csv", "events.csv", "commands.csv"))
