"""`planthub run … --view`: the run starts its view beside it (`planthub view RUN --connect …` as a
child process), prints its address, the page's socket says hello for the run, and the view is gone
when the run ends — by itself, or killed with the hub; a view that cannot serve its page stops the
run before it starts.

    planthub run source_sink.yaml --realtime --view ──► planthub view source_sink --connect <the hub's endpoint> ◄── /ws ── client
"""
import os
import re
import signal
import socket
import time
from types import SimpleNamespace

import pytest

from hub.bus.session import free_loopback_endpoint
from hub.bus.settings import BusSettings
from hub.cli.run_view import RunView
from hub.core.errors import PlanthubError

from .helpers import ROOT
from .view_support import planthub, receive, talk, wait_for_url

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"
_LINE = re.compile(r"^planthub run: the view of run 'source_sink' at (http://127\.0\.0\.1:\d+/)  \(open it in a "
                   r"browser; pid (\d+), it ends with the run\)$", re.M)


def gone(pid: int, timeout: float = 15.0) -> bool:
    """Whether process `pid` has ended (a zombie nobody reaps counts as ended) within `timeout` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with open(f"/proc/{pid}/stat") as f:
                if f.read().rsplit(")", 1)[1].split()[0] == "Z":
                    return True
        except FileNotFoundError:
            return True
        time.sleep(0.1)
    return False


def started_view(started) -> tuple[str, int]:
    wait_for_url(started, 60)
    found = _LINE.search(started.out.read_text())
    assert found, started.output()
    return found.group(1), int(found.group(2))


@pytest.mark.slow
def test_the_run_serves_its_view_and_the_view_ends_with_the_run(tmp_path):
    with planthub(tmp_path, "hub", "run", SCENARIO, "--realtime", "--view", "--view-port", 0, "--out",
                  tmp_path / "run", "--set", "run.duration=6") as started:
        url, pid = started_view(started)
        hello = talk(url, receive)
        assert hello == {"type": "hello", "run": "source_sink", "control": True, "reason": "",
                         "viewer": hello["viewer"], "role": "instructor", "role_reason": ""} and hello["viewer"].startswith("view-")
        assert started.proc.wait(60) == 0, started.output()
    assert gone(pid), f"the view (pid {pid}) outlived its run"
    out, err = started.output()
    assert "planthub run source_sink" in out and "the hub of run 'source_sink' went away" not in err


def test_a_hub_killed_outright_takes_its_view_with_it(tmp_path):
    with planthub(tmp_path, "hub", "run", SCENARIO, "--realtime", "--view", "--view-port", 0,
                  "--set", "run.duration=120", "--out", tmp_path / "run") as started:
        url, pid = started_view(started)
        os.kill(started.proc.pid, signal.SIGKILL)
        started.proc.wait(30)
        assert gone(pid), f"the view (pid {pid}) outlived its hub, killed with SIGKILL"


def test_a_view_that_cannot_serve_stops_the_run_before_it_starts(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with planthub(tmp_path, "hub", "run", SCENARIO, "--view", "--view-port", port, "--out",
                      tmp_path / "run") as started:
            assert started.proc.wait(90) == 1
    out, err = started.output()
    assert f"planthub: cannot serve on 127.0.0.1:{port}: error while attempting to bind on address ('127.0.0.1', " \
           f"{port}): address already in use (another view? --port picks another)" in err
    assert "ended early" not in err
    assert err.rstrip().endswith("planthub: the run's view ended before it served its page (exit 1; its message "
                                 "above): the run was not started"), err
    assert "planthub run: note: --view without --realtime: the run goes as fast as it can, and its view ends " \
           "with it" in err


def test_a_view_that_serves_no_page_in_time_is_named_and_stopped():
    """A real view child that waits for a hub nobody runs: RunView gives up on it and ends it."""
    view = RunView("nobody_runs_this", port=0)
    try:
        view.start(SimpleNamespace(settings=BusSettings(), endpoints=(free_loopback_endpoint(),)))
        with pytest.raises(PlanthubError) as info:
            view.wait(timeout=6)   # by then the child has started and handles SIGTERM, even on a busy machine
        assert str(info.value) == "the run's view served no page within 6 s: the run was not started"
        assert view.process.poll() is None, "it still waits for the scene"
    finally:
        view.stop()
    assert view.process.returncode == 128 + signal.SIGTERM and gone(view.pid)
