"""A campaign worker's zygote (hub/campaign/zygote.py) forks a case that ends as `python -m hub` run
by hand ends: the same exit status and the same output for a command that passes, a scenario that
does not load and a usage error, Python's own end for whatever the command raised (atexit's handlers
run, buffered output written), and a run's files as the run by hand writes them — though the child
skips the interpreter's teardown of the zygote's modules."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from hub.campaign.zygote import Zygote

from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "belt_bottle_sensor.yaml"


@pytest.fixture(scope="module")
def zygote():
    warm = Zygote(["run", str(SCENARIO), "--set", "run.duration=0.1"])
    try:
        ok, why = warm.ready()
        assert ok, why
        yield warm
    finally:
        warm.close()


def forked(zygote, tmp_path, *args) -> tuple[int, str]:
    output = tmp_path / "forked.txt"
    output.write_bytes(b"")
    child = zygote.fork([str(a) for a in args], str(output))
    return child.wait(timeout=60), output.read_text()


def by_hand(tmp_path, *args) -> tuple[int, str]:
    done = subprocess.run([sys.executable, "-m", "hub", *map(str, args)], cwd=ROOT, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=60)
    return done.returncode, done.stdout


@pytest.mark.parametrize("args, code", [
    (["validate", SCENARIO], 0),
    (["validate", "no_such_scenario.yaml"], 3),
    (["run", SCENARIO, "--no-such-option"], 2),
    (["describe", "no_such_module"], 2),
], ids=["passes", "does-not-load", "usage-error", "unknown-module"])
def test_a_forked_case_ends_with_the_status_and_output_of_the_command_run_by_hand(zygote, tmp_path, args, code):
    status, said = forked(zygote, tmp_path, *args)
    assert (status, said) == by_hand(tmp_path, *args)
    assert status == code, said


@pytest.mark.parametrize("does, code", [
    ("raise ZeroDivisionError('bang')", 1),
    ("raise SystemExit('planthub: a message')", 1),
    ("raise SystemExit(7)", 7),
    ("raise KeyboardInterrupt()", -2),
    ("pool.submit(print, 'from the pool', end='').result()", 0),   # its idle worker ends by its exit hook
])
def test_the_end_of_a_forked_case_is_the_interpreters_for_whatever_the_command_did(tmp_path, does, code):
    """_end (what a forked child runs) against Python's own end of a program that does the same."""
    def ends(program: str) -> tuple[int, str]:
        buffered = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}   # stdout a buffer to flush
        done = subprocess.run([sys.executable, "-c", program], cwd=ROOT, capture_output=True, text=True, timeout=60,
                              env=buffered)
        return done.returncode, done.stdout, (done.stderr.strip().splitlines() or [""])[-1]

    flag = tmp_path / "atexit.txt"
    pool = "import concurrent.futures\npool = concurrent.futures.ThreadPoolExecutor(1)\n"
    mine = ends(pool + "import atexit, pathlib; from hub.campaign import zygote\n"
                f"atexit.register(pathlib.Path({str(flag)!r}).write_text, 'ran')\n"
                "print('said before', end='')\n"
                f"def command(args): {does}\n"
                "zygote._planthub = command\nzygote._end([])")
    python = ends(pool + f"print('said before', end='')\n{does}")
    assert mine == python and python[0] == code, (mine, python)
    assert flag.read_text() == "ran"   # atexit's handlers ran, and the buffered print reached stdout


def test_a_forked_run_writes_the_files_of_the_run_by_hand_before_it_ends(zygote, tmp_path):
    status, said = forked(zygote, tmp_path, "run", SCENARIO, "--out", tmp_path / "forked", "-q")
    assert status == 0, said
    assert by_hand(tmp_path, "run", SCENARIO, "--out", tmp_path / "by_hand", "-q")[0] == 0
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "forked" / name).read_bytes() == (tmp_path / "by_hand" / name).read_bytes()
    summary = json.loads((tmp_path / "forked" / "summary.json").read_text())
    assert summary["ended"]["kind"] == "duration"
