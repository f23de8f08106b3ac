"""`planthub campaign` on real Dask clusters on loopback: the embedded LocalCluster with two workers, a scheduler and a worker started with Dask's own command line, a worker killed mid-case, a scheduler lost mid-case, a case that hangs, Ctrl-C and SIGTERM.

    campaign ──► LocalCluster (127.0.0.1) ──► worker ──► planthub test (a child per case)
             └─► dask scheduler ◄── dask worker      (--scheduler tcp://127.0.0.1:PORT)

Every case is the belt_bottle_sensor scene, short; a "long" case stands still on a stopped belt.
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from xml.etree import ElementTree

import psutil
import pytest

from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "belt_bottle_sensor.yaml"
LIMIT = 120   # s: the longest any campaign here may take before the test stops it and fails

# speed 0.3 m/s: the bottle is at x = 0.47 m after 1.5 s, short of 0.6 (failed); 0.5 m/s: 0.76 m (passed).
# A vec3 compares as a list, x first.
SPEEDS = """\
    planthub: 1
    name: speeds
    scenarios: [SCENARIO]
    matrix:
      objects.belt.speed: [0.3, 0.5]
      run.duration: [1.5]
    seeds: 2
    expect:
      - {name: far, slot: bottle.body.position, is: {">": [0.6, -1, -1]}}
    time_limit: 60
    """
LONG_SECONDS = 300   # s simulated of a bottle standing on a stopped belt: ~1.5 s of wall time here


def write(folder: Path, text: str, name: str = "campaign.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text).replace("SCENARIO", str(SCENARIO)))
    return path


def long_case(folder: Path, time_limit: float, count: int = 1, duration: float = LONG_SECONDS) -> Path:
    return write(folder, f"""\
        planthub: 1
        name: long
        scenarios: [SCENARIO]
        matrix:
          objects.belt.speed: [0]
          run.duration: [{duration}]
        seeds: {count}
        time_limit: {time_limit}
        """)


def start(args: list[str], cwd: Path, name: str, env: dict | None = None) -> subprocess.Popen:
    """A process in a session of its own (so a test can stop all it started), its output in cwd/NAME.log."""
    with open(cwd / f"{name}.log", "w") as log:   # the child has its own copy of the file
        return subprocess.Popen(args, cwd=cwd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                                stdin=subprocess.DEVNULL, env={**os.environ, **(env or {})})


def until(done, what: str, limit: float = 30) -> None:
    """Wait for `done()` up to `limit` s; the test fails saying `what` did not happen otherwise."""
    deadline = time.monotonic() + limit
    while not done():
        if time.monotonic() > deadline:
            pytest.fail(f"{what} did not happen within {limit:g} s")
        time.sleep(0.1)


DASK = str(Path(sys.executable).with_name("dask"))


def scheduler(folder: Path) -> tuple[subprocess.Popen, str]:
    """`dask scheduler` on 127.0.0.1 (a failed task not run again, as the embedded cluster does) and its address."""
    file = folder / "scheduler.json"
    process = start([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
                     str(file)], folder, "scheduler", env={"DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0"})
    try:
        until(file.is_file, f"the scheduler writing {file} (its log: {folder / 'scheduler.log'})")
        address = json.loads(file.read_text())["address"]
    except BaseException:
        stop(process)
        raise
    assert address.startswith("tcp://127.0.0.1:")
    return process, address


def worker(folder: Path, address: str) -> subprocess.Popen:
    """`dask worker` of one thread on 127.0.0.1, once it has joined the scheduler at `address`."""
    process = start([DASK, "worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--no-dashboard"], folder,
                    "worker")
    log = folder / "worker.log"
    try:
        until(lambda: "Registered to" in log.read_text(), f"the worker joining {address} (its log: {log})")
    except BaseException:
        stop(process)
        raise
    return process


def stop(process: subprocess.Popen) -> None:
    """The process's whole session ended: SIGTERM, then SIGKILL."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            return
        try:
            process.wait(timeout=10)
            return
        except subprocess.TimeoutExpired:
            continue


class Campaign:
    """`planthub campaign` as a child process; stopped whatever happens."""

    def __init__(self, folder: Path, file: Path, *options: str, env: dict | None = None):
        self.out, self.junit = folder / "out", folder / "campaign.xml"
        self.process = subprocess.Popen(
            [sys.executable, "-m", "hub", "campaign", str(file), "--out", str(self.out), "--junit", str(self.junit),
             *options], cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            start_new_session=True, stdin=subprocess.DEVNULL, env={**os.environ, **(env or {})})
        self.stdout = self.stderr = ""

    def wait(self) -> int:
        try:
            self.stdout, self.stderr = self.process.communicate(timeout=LIMIT)
        except subprocess.TimeoutExpired:
            stop(self.process)
            self.stdout, self.stderr = self.process.communicate(timeout=10)
            pytest.fail(f"the campaign took over {LIMIT} s:\n{self.stdout}\n{self.stderr}")
        finally:
            stop(self.process)   # what it left in its session (a LocalCluster's workers), if anything
        return self.process.returncode

    def results(self) -> dict:
        return json.loads((self.out / "campaign.json").read_text())

    def testcases(self) -> list[tuple[str, str]]:
        """(name, result) of every testcase of the JUnit file."""
        root = ElementTree.parse(self.junit).getroot()
        found = []
        for case in root.iter("testcase"):
            marks = [child.tag for child in case if child.tag in ("failure", "error", "skipped")]
            found.append((case.get("name"), marks[0] if marks else "passed"))
        return found


def case_child(out: Path, limit: float = 60):
    """The process running a case of the campaign writing to `out`, once it runs: the one holding
    the case's output.txt open (a fork of its worker's zygote has the zygote's command line)."""
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        for process in psutil.process_iter():
            try:
                files = [f.path for f in process.open_files()]
            except psutil.Error:   # another user's, or gone
                continue
            if any(f.startswith(str(out / "cases")) and f.endswith("/output.txt") for f in files):
                return process
        time.sleep(0.1)
    pytest.fail(f"no case of {out} started within {limit} s")


def forked_by_a_zygote(child) -> psutil.Process:
    """The Dask worker whose zygote forked `child` (each case is a fork of its worker's warm zygote)."""
    zygote = child.parent()
    assert zygote.cmdline()[1:] == ["-m", "hub.campaign.zygote"]
    return zygote.parent()


def running(out: Path) -> None:
    """Once the first case's run is under way (its recording begun, its signals handled)."""
    started = out / "cases" / "000-belt_bottle_sensor" / "recording.csv"
    until(started.is_file, f"the first case writing {started}")


def same_results(campaign: dict) -> list:
    """What must be equal for the same campaign on any number of workers (not where or how fast)."""
    return [(c["label"], c["verdict"], c["outcomes"], c["figures"], c["ended"]) for c in campaign["cases"]]


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    """The speeds campaign on the embedded LocalCluster with two workers."""
    folder = tmp_path_factory.mktemp("local")
    campaign = Campaign(folder, write(folder, SPEEDS), "--workers", "2")
    campaign.wait()
    return campaign


def test_a_local_cluster_with_two_workers_runs_every_case(local):
    assert local.process.returncode == 1, local.stderr   # the cases at 0.3 m/s fail their expectation
    found = local.results()
    assert "a LocalCluster on 127.0.0.1: 2 workers" in found["cluster"]
    assert found["passed"] is False and found["ended"] == "every case ran"
    assert found["counts"] == {"failed": 2, "passed": 2}
    cases = found["cases"]
    assert [c["verdict"] for c in cases] == ["failed", "failed", "passed", "passed"]
    assert [c["parameters"] for c in cases][:2] == [{"objects.belt.speed": 0.3, "run.duration": 1.5, "run.seed": 0},
                                                    {"objects.belt.speed": 0.3, "run.duration": 1.5, "run.seed": 1}]
    assert cases[0]["reason"].startswith("far: bottle.body.position was (0.47")
    for case in cases:
        assert case["figures"]["simulated_s"] == 1.5 and case["attempts"] == 1
        assert (local.out / case["folder"] / "summary.json").is_file()
        assert (local.out / case["folder"] / "recording.csv").is_file()
    label = "belt_bottle_sensor[objects.belt.speed=0.3, run.duration=1.5, run.seed=0]"
    assert local.testcases() == [(f"far [{label}]", "failure"), (f"far [{label.replace('seed=0', 'seed=1')}]", "failure"),
                                 (f"far [{label.replace('0.3', '0.5')}]", "passed"),
                                 (f"far [{label.replace('0.3', '0.5').replace('seed=0', 'seed=1')}]", "passed")]
    rows = (local.out / "cases.csv").read_text().splitlines()
    assert rows[0].startswith("case,scenario,objects.belt.speed,run.duration,run.seed,verdict,failed,wall_s,simulated_s")
    assert rows[1].startswith("0,belt_bottle_sensor,0.3,1.5,0,failed,1,") and len(rows) == 5
    assert "[4/4]" in local.stderr and "0 left" in local.stderr   # progress as the cases finished
    assert "4 cases: 2 failed, 2 passed; every case ran" in local.stdout


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """A scheduler and a worker started with Dask's own command line on 127.0.0.1; its address."""
    folder = tmp_path_factory.mktemp("dask")
    process, address = scheduler(folder)
    try:
        joined = worker(folder, address)   # the worker has joined: a campaign sees it from its start
        try:
            yield address
        finally:
            stop(joined)
    finally:
        stop(process)


def test_a_scheduler_without_workers_ends_the_campaign_not_run(tmp_path):
    from hub.campaign.cluster import Cluster
    from hub.campaign.plan import load_campaign
    from hub.campaign.runner import run_campaign

    process, address = scheduler(tmp_path)
    try:
        lines = []
        with Cluster(address) as cluster:
            outcome = run_campaign(load_campaign(write(tmp_path, SPEEDS)), tmp_path / "out", cluster,
                                   progress=lines.append, no_workers=1)
    finally:
        stop(process)
    assert not outcome.passed and outcome.interrupted is None
    assert outcome.ended == "no worker in the cluster for 1 s after 0 of 4 cases"
    assert [r["reason"] for r in outcome.records] == ["not run: no worker in the cluster for 1 s"] * 4
    assert lines == ["campaign: no worker in the cluster for 1 s: stopping the running cases (up to 25 s)"]


def test_a_scheduler_lost_mid_campaign_ends_it_with_its_files(tmp_path):
    process, address = scheduler(tmp_path)
    joined = None
    try:
        joined = worker(tmp_path, address)
        campaign = Campaign(tmp_path, long_case(tmp_path, time_limit=60, duration=100000),
                            "--scheduler", address, env={"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"})
        try:
            child = case_child(campaign.out)
            running(campaign.out)   # (the campaign looks at its cluster every second: it has seen the case handed out)
            os.killpg(process.pid, signal.SIGKILL)   # the scheduler dies, as a machine that goes away
        finally:
            code = campaign.wait()
        child.wait(timeout=30)   # the case, cut off from its campaign, stopped itself
    finally:
        for started in (joined, process):
            if started is not None:
                stop(started)
    assert code == 1, campaign.stderr
    assert "Traceback" not in campaign.stderr
    found = campaign.results()
    assert found["passed"] is False and found["interrupted"] is None
    assert found["broken"].startswith(f"scheduler {address} failed while "), found["broken"]
    (case,) = found["cases"]
    assert case["verdict"] == "stopped" and case["reason"] == f"stopped: {found['broken']}; its result did not come back"
    assert [result for _, result in campaign.testcases()] == ["error", "failure"]
    assert (campaign.out / "cases.csv").read_text().count("\n") == 2
    assert f"campaign: {found['broken']}: stopping the running cases" in campaign.stderr


def test_a_case_forked_by_a_zygote_is_the_case_run_by_hand(local, tmp_path):
    """The warm start changes nothing of a case (the zygote ran the plant, pybullet and numba's
    loops before it forked): its command from campaign.json in a fresh Python gives the same
    outcomes, figures and recording."""
    from hub.campaign.case import _ended, _figures, _outcomes

    case = local.results()["cases"][0]
    folder, again = str(local.out / case["folder"]), str(tmp_path / "again")
    line = [part.replace(folder, again) for part in case["command"]]
    done = subprocess.run(line, capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == case["exit_code"] == 1, done.stderr
    assert _outcomes(tmp_path / "again" / "junit.xml") == case["outcomes"]
    assert _figures(tmp_path / "again" / "summary.json") == case["figures"]
    assert _ended(tmp_path / "again" / "summary.json") == case["ended"]
    assert (tmp_path / "again" / "recording.csv").read_bytes() == (local.out / case["folder"] / "recording.csv").read_bytes()


def test_a_campaign_on_a_scheduler_and_worker_of_dasks_command_line(dask_cluster, local, tmp_path):
    campaign = Campaign(tmp_path, write(tmp_path, SPEEDS), "--scheduler", dask_cluster)
    assert campaign.wait() == 1, campaign.stderr
    found = campaign.results()
    assert found["cluster"] == f"scheduler {dask_cluster}: 1 workers, 1 cases at once"
    # one worker here, two there: the same cases, verdicts and figures
    assert same_results(found) == same_results(local.results())
    assert campaign.testcases() == local.testcases()


def test_only_the_failed_cases_again(dask_cluster, local, tmp_path):
    campaign = Campaign(tmp_path, write(tmp_path, SPEEDS), "--scheduler", dask_cluster, "--only-failed", str(local.out))
    assert campaign.wait() == 1, campaign.stderr
    found = campaign.results()
    assert [c["label"] for c in found["cases"]] == [c["label"] for c in local.results()["cases"][:2]]
    assert [c["verdict"] for c in found["cases"]] == ["failed", "failed"]


def test_a_worker_killed_mid_case_has_its_case_run_again_elsewhere(tmp_path):
    campaign = Campaign(tmp_path, long_case(tmp_path, time_limit=60), "--workers", "2")
    try:
        child = case_child(campaign.out)
        worker = forked_by_a_zygote(child)
        zygote = child.parent()
        worker.kill()   # SIGKILL: the worker process, not its case
        child.wait(timeout=10)   # the case dies with it (zygote, then case: end of file, parent-death signal)
        zygote.wait(timeout=10)
    finally:
        code = campaign.wait()
    assert code == 0, campaign.stderr
    (case,) = campaign.results()["cases"]
    assert case["verdict"] == "passed" and case["attempts"] == 2
    assert case["reason"] == "run again after its worker died (attempt 2)"


def test_a_case_that_crashes_is_that_cases_failure_with_its_reason(tmp_path):
    campaign = Campaign(tmp_path, long_case(tmp_path, time_limit=60, count=2), "--workers", "1")
    try:
        case_child(campaign.out).kill()   # as a segfault in an FMU's code would end it, with nothing written
    finally:
        code = campaign.wait()
    assert code == 1, campaign.stderr
    crashed, other = campaign.results()["cases"]
    assert crashed["verdict"] == "crashed" and crashed["attempts"] == 1
    assert crashed["reason"].startswith("the run was killed by SIGKILL")
    assert other["verdict"] == "passed"   # the worker went on with the next case
    assert campaign.testcases()[0] == ("the run [belt_bottle_sensor[objects.belt.speed=0, run.duration=300, "
                                       "run.seed=0]]", "error")


def test_a_case_that_hangs_is_stopped_at_its_time_limit(tmp_path):
    # 6 s: the case's child has started its run by then even on a busy machine (it is stopped by
    # SIGTERM mid-run and writes its summary).
    campaign = Campaign(tmp_path, long_case(tmp_path, time_limit=6, duration=100000), "--workers", "1")
    assert campaign.wait() == 1, campaign.stderr
    found = campaign.results()
    (case,) = found["cases"]
    assert case["verdict"] == "timeout"
    assert case["reason"] == "exceeded its time limit of 6 s and was stopped"
    # stopped with SIGTERM, the run wrote its files and a summary saying why
    summary = json.loads((campaign.out / case["folder"] / "summary.json").read_text())
    assert "SIGTERM" in summary["ended"]["reason"]
    assert campaign.testcases() == [("the run [belt_bottle_sensor[objects.belt.speed=0, run.duration=100000, "
                                     "run.seed=0]]", "error")]


def test_ctrl_c_stops_the_campaign_and_keeps_what_finished(tmp_path):
    # Cases as fresh Pythons: a Ctrl-C during a worker's zygote warm-up was once lost under load (the
    # cases ran to their limits; hub/campaign/README.md, "Open"): this test is of the campaign's Ctrl-C itself.
    campaign = Campaign(tmp_path, long_case(tmp_path, time_limit=60, count=3, duration=100000), "--workers", "1",
                        env={"PLANTHUB_CAMPAIGN_FRESH": "1"})
    try:
        child = case_child(campaign.out)
        running(campaign.out)
        os.killpg(campaign.process.pid, signal.SIGINT)   # as a terminal's Ctrl-C: the campaign and its workers
    finally:
        code = campaign.wait()
    assert code == 130, campaign.stderr
    assert "Traceback" not in campaign.stderr   # the workers ignored the terminal's SIGINT: the campaign decided
    assert not child.is_running()
    found = campaign.results()
    assert found["passed"] is False and found["interrupted"] == "SIGINT"
    assert found["ended"] == "interrupted (SIGINT) after 0 of 3 cases"
    assert [c["verdict"] for c in found["cases"]] == ["stopped", "not run", "not run"]
    assert [result for _, result in campaign.testcases()] == ["error", "skipped", "skipped", "failure"]
    assert (campaign.out / found["cases"][0]["folder"] / "summary.json").is_file()


def test_every_case_branches_from_one_checkpoint(dask_cluster, tmp_path):
    subprocess.run([sys.executable, "-m", "hub", "run", str(SCENARIO), "--set", "run.duration=1", "--checkpoint-at",
                    "0.5", "--out", str(tmp_path / "warm"), "-q"], check=True, capture_output=True, timeout=60)
    campaign = Campaign(tmp_path, write(tmp_path, """\
        planthub: 1
        scenarios: [SCENARIO]
        matrix:
          run.duration: [1, 1.5]
        from: warm/checkpoints/75.ckpt
        """), "--scheduler", dask_cluster)
    assert campaign.wait() == 0, campaign.stderr
    cases = campaign.results()["cases"]
    assert [c["figures"]["simulated_s"] for c in cases] == [1.0, 1.5]
    assert all("--resume" in c["command"] for c in cases)
    # resumed at 0.5 s: the recording starts there
    first = (campaign.out / cases[0]["folder"] / "recording.csv").read_text().splitlines()[1]
    assert first.split(",")[0].startswith("0.5")


def test_a_scheduler_that_cannot_be_reached_fails_the_campaign_with_its_files(tmp_path):
    with socket.socket() as unused:   # a port on loopback that nothing listens on
        unused.bind(("127.0.0.1", 0))
        port = unused.getsockname()[1]
    campaign = Campaign(tmp_path, write(tmp_path, SPEEDS), "--scheduler", f"tcp://127.0.0.1:{port}",
                        env={"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "1s"})   # Dask's own setting
    assert campaign.wait() == 1
    assert f"planthub campaign: cannot reach scheduler tcp://127.0.0.1:{port}: Timed out" in campaign.stderr
    found = campaign.results()
    assert found["passed"] is False and found["ended"].startswith("not started: cannot reach scheduler")
    assert [c["verdict"] for c in found["cases"]] == ["not run"] * 4
    assert campaign.testcases()[-1] == ("the campaign", "failure")


def test_sigterm_while_the_cluster_is_reached_ends_the_campaign_with_its_files(tmp_path):
    with socket.socket() as silent:   # a "scheduler" that takes the connection and never answers
        silent.bind(("127.0.0.1", 0))
        silent.listen()
        silent.settimeout(60)
        campaign = Campaign(tmp_path, write(tmp_path, SPEEDS), "--scheduler", f"tcp://127.0.0.1:{silent.getsockname()[1]}")
        connection = None
        try:
            connection, _ = silent.accept()   # the campaign is waiting for its cluster now (kept open: still waiting)
            campaign.process.send_signal(signal.SIGTERM)
        finally:
            code = campaign.wait()
            if connection is not None:
                connection.close()
    assert code == 143, campaign.stderr
    assert "Traceback" not in campaign.stderr
    found = campaign.results()
    assert found["interrupted"] == "SIGTERM" and found["ended"] == "not started: interrupted (SIGTERM)"
    assert [c["verdict"] for c in found["cases"]] == ["not run"] * 4
    assert campaign.testcases()[-1] == ("the campaign", "failure")


def test_a_figure_plotted_against_a_parameter(local, tmp_path, capsys):
    from hub.cli.main import main

    out = tmp_path / "speeds.png"
    assert main(["plot", str(local.out), "simulated_s", "wall_s", "--against", "objects.belt.speed",
                 "--out", str(out)]) == 0
    assert capsys.readouterr().out.strip() == str(out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for argv, message in (
            (["simulated", "--against", "run.seed"], "simulated: no such figure in {out}/campaign.json (did you mean 'simulated_s'?); its figures: "
                            "events, simulated_s, wall_s"),
            (["simulated_s", "--against", "objects.belt.sped"],
             "--against objects.belt.sped: the campaign does not vary it (did you mean 'objects.belt.speed'?)"),
            (["simulated_s", "--against", "objects.belt.speed", "--out", str(tmp_path / "x.svg")],
             f"--out {tmp_path / 'x.svg'}: planthub plot writes a PNG, so name a .png file")):
        assert main(["plot", str(local.out), *argv]) == 2
        assert message.format(out=local.out) in capsys.readouterr().err
    assert main(["plot", str(local.out), "simulated_s"]) == 2
    assert (f"{local.out} holds a campaign: say which parameter goes along the x axis with --against KEY "
            "(objects.belt.speed, run.duration, run.seed)") in capsys.readouterr().err
    case = local.out / "cases" / "000-belt_bottle_sensor"
    assert main(["plot", str(case), "bottle.body.position", "--against", "run.seed"]) == 2
    assert f"--against run.seed: {case} is no campaign's folder (it has no campaign.json)" in capsys.readouterr().err


def test_a_case_started_afresh_without_a_zygote(tmp_path, monkeypatch):
    """PLANTHUB_CAMPAIGN_FRESH=1 (and a zygote that would not serve, or no Linux): a fresh Python
    per case, judged the same way."""
    from hub.campaign import zygote
    from hub.campaign.case import FRESH, run_case

    monkeypatch.setenv(FRESH, "1")
    found = run_case({"scenario": str(SCENARIO), "out": str(tmp_path / "case"), "judge": False,
                      "overrides": {"run.duration": 0.5}, "resume": None, "time_limit": 60})
    assert found["verdict"] == "passed" and found["figures"]["simulated_s"] == 0.5, found["reason"]
    assert zygote._mine is None   # no zygote was started in this process
