"""No wait without a limit: an FMU whose step never returns stops the run naming it — its worker
killed when it runs isolated, the hub's process ended by the watchdog when it runs in the hub —
with the recording complete and summary.json saying why; and children never outlive the hub."""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from xml.etree import ElementTree

import pytest

from .fmus.fmu_support import build
from .helpers import ROOT


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """The test-only `faulty` model: its step at `hang_at` never returns."""
    return build(tmp_path_factory.mktemp("faulty"), models_dir=ROOT / "tests" / "fmu_models")


def scene(tmp_path, fmu, extra):
    path = tmp_path / "scene.yaml"
    path.write_text(f"""planthub: 1
run: {{duration: 2.0, physics_rate: 100, communication_step: 0.1}}
objects:
  counter: {{module: fmu, file: {fmu}, parameters: {{hang_at: 4}}, step_timeout: 1.5{extra}}}
record: [counter.logic.steps]
""")
    return path


def rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.mark.parametrize("isolate", [True, False])
def test_a_hanging_fmu_stops_the_run_naming_it_with_its_files_complete(faulty, tmp_path, isolate):
    path = scene(tmp_path, faulty / "faulty-fmi2.fmu", ", runs: child" if isolate else "")
    out = tmp_path / "out"
    started = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "hub", "run", str(path), "--out", str(out)],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 1, proc.stderr
    assert time.monotonic() - started < 30
    if isolate:
        assert ("FMU instance 'counter' (faulty-fmi2.fmu) at t = 0.3 s: its step did not return within 1.5 s "
                "(step_timeout), so its worker process was killed") in proc.stderr
    else:
        assert ("FMU instance 'counter' (faulty-fmi2.fmu) at t = 0.3 s: its step has not returned for") in proc.stderr
        assert "an FMU in the hub's process cannot be interrupted, so planthub ends here" in proc.stderr
    recorded = rows(out / "recording.csv")
    assert [r["counter.logic.steps"] for r in recorded] == ["0", "1", "2", "3"]
    assert (out / "events.csv").read_text().startswith("time,tick,slot,detail")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulated"]["ticks"] == 30


def test_a_signal_that_finds_planthub_test_stuck_still_gives_the_verdicts_and_the_junit_file(faulty, tmp_path):
    """The FMU's step never returns, in the hub's own process, and its step_timeout is far off: the
    SIGINT is handled by the helper thread 3 s later (GRACE), which judges what the run reached
    before it ends the process with 130."""
    path = scene(tmp_path, faulty / "faulty-fmi2.fmu", "").read_text().replace("step_timeout: 1.5", "step_timeout: 60")
    (tmp_path / "scene.yaml").write_text(path + """expect:
  - {name: one step by 0.1 s, slot: counter.logic.steps, at: 0.1, is: {"==": 1}}
  - {name: twenty steps at the end, slot: counter.logic.steps, is: {"==": 20}}
""")
    out, junit = tmp_path / "out", tmp_path / "report.xml"
    hub = subprocess.Popen([sys.executable, "-m", "hub", "test", str(tmp_path / "scene.yaml"), "--out", str(out),
                            "--junit", str(junit)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        while not (out / "recording.csv").is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
        # The step at t = 0.3 s starts milliseconds after the file is made (three steps of a
        # counter) and spins for good: 3 s leave room for a machine busy with other tests.
        time.sleep(3.0)
        hub.send_signal(signal.SIGINT)
        stdout, stderr = hub.communicate(timeout=30)
    finally:
        if hub.poll() is None:
            hub.kill()
            hub.communicate(timeout=10)
    assert hub.returncode == 130, stderr
    reason = ("failed at t = 0.3 s: interrupted by SIGINT; the run did not reach its next communication point "
              "within 3 s (a step is stuck), so it ends here")
    assert stdout.splitlines()[1:] == [
        f"  failed       {reason}",
        "  ✓ one step by 0.1 s — counter.logic.steps was 1 at 0.1 s",
        "  ? twenty steps at the end — not judged: the run was interrupted at t = 0.3 s (so far: "
        "counter.logic.steps was 3 at 0.3 s)",
        "1 passed, 0 failed, 1 not judged"]
    suite = ElementTree.parse(junit).getroot().find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("skipped")) == ("3", "1", "1")
    run_case = [c for c in suite.findall("testcase") if c.get("name") == "the run"][0]
    assert run_case.find("failure").get("message") == reason
    assert json.loads((out / "summary.json").read_text())["ended"]["kind"] == "failed"


def test_a_launched_participant_dies_with_a_hub_killed_by_sigkill(tmp_path):
    """kill -9 of the hub: the kernel ends the participant it launched (no orphan 2 s later)."""
    scene_path = tmp_path / "long.yaml"
    scene_path.write_text((ROOT / "scenarios" / "belt_ramp_participant.yaml").read_text()
                          .replace("duration: 6.0", "duration: 600.0"))
    hub = subprocess.Popen([sys.executable, "-m", "hub", "run", str(scene_path), "--out", str(tmp_path / "out"),
                            "--realtime", "1"], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        child = None
        deadline = time.monotonic() + 30
        while child is None and time.monotonic() < deadline:
            time.sleep(0.2)
            found = subprocess.run(["pgrep", "-P", str(hub.pid)], capture_output=True, text=True).stdout.split()
            child = int(found[0]) if found else None
        assert child is not None, "the hub launched no participant"
        time.sleep(1.0)   # the participant is in its steps
        os.kill(hub.pid, signal.SIGKILL)
        hub.wait(10)
        time.sleep(2.0)
        alive = subprocess.run(["ps", "-o", "stat=", "-p", str(child)], capture_output=True, text=True).stdout.strip()
        assert alive in ("", "Z"), f"participant {child} outlived the hub ({alive})"
        # Its files were flushed at most 0.5 s of wall time before the kill: readable, header first.
        recorded = rows(tmp_path / "out" / "recording.csv")
        assert recorded and float(recorded[-1]["time"]) > 0.0
        assert (tmp_path / "out" / "events.csv").read_text().startswith("time,tick,slot,detail\n")
    finally:
        if hub.poll() is None:
            hub.kill()
            hub.wait(10)


def children_of(pid: int) -> list[int]:
    found = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [int(p) for p in found]


def alive(pid: int) -> bool:
    state = subprocess.run(["ps", "-o", "stat=", "-p", str(pid)], capture_output=True, text=True).stdout.strip()
    return state not in ("", "Z")


def test_the_temporary_files_of_a_hub_killed_by_sigkill_are_swept_by_the_next_run(tmp_path):
    """An isolated FMU's extracted files and a launched participant's log live in one folder named
    with the hub's pid. kill -9 leaves it (nothing runs at a SIGKILL) and no child alive; the next
    `planthub run` sees that process is gone and removes it, and its own folder at its normal end."""
    temporary = tmp_path / "tmp"   # the hubs' temporary folder (TMPDIR): this test's own
    temporary.mkdir()
    env = {**os.environ, "TMPDIR": str(temporary)}
    scene_path = tmp_path / "long.yaml"
    scene_path.write_text((ROOT / "scenarios" / "belt_ramp_participant.yaml").read_text()
                          .replace("duration: 6.0", "duration: 600.0")
                          .replace("  go:", f"  spare: {{module: fmu, file: '{ROOT}/build/fmus/belt_drive-fmi2.fmu', "
                                            f"runs: child}}\n  go:"))
    hub = subprocess.Popen([sys.executable, "-m", "hub", "run", str(scene_path), "--out", str(tmp_path / "out"),
                            "--realtime", "1"], cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 30
        folder, inside = None, []
        while time.monotonic() < deadline and not (
                any(n.startswith("drive-") and n.endswith(".log") for n in inside)
                and any(n.startswith("fmu-spare-") for n in inside) and len(children_of(hub.pid)) >= 2):
            time.sleep(0.2)
            folders = list(temporary.glob(f"planthub-{hub.pid}-*"))
            folder = folders[0] if folders else None
            inside = [p.name for p in folder.iterdir()] if folder is not None else []
        assert folder is not None and len(list(temporary.iterdir())) == 1, list(temporary.iterdir())
        assert any(n.startswith("fmu-spare-") for n in inside), inside   # the isolated worker's FMU
        assert any(n.startswith("drive-") and n.endswith(".log") for n in inside), inside   # the participant's log
        children = children_of(hub.pid)   # the participant and the FMU's worker
        time.sleep(1.0)   # both in their steps
        os.kill(hub.pid, signal.SIGKILL)
        hub.wait(10)
        killed = time.monotonic()
        assert folder.is_dir()   # kill -9: nothing of the hub ran
        time.sleep(max(0.0, killed + 2.0 - time.monotonic()))
        assert [c for c in children if alive(c)] == [], "children outlived the hub"
    finally:
        if hub.poll() is None:
            hub.kill()
            hub.wait(10)
        hub.stderr.close()
    after = subprocess.run([sys.executable, "-m", "hub", "run", "scenarios/stop_at_barrier.yaml", "--set",
                            "run.duration=0.1", "--out", str(tmp_path / "next")], cwd=ROOT, env=env,
                           capture_output=True, text=True, timeout=60)
    assert after.returncode == 0, after.stderr
    assert not folder.exists()
    assert list(temporary.iterdir()) == []   # nor is the next run's own folder left


def test_a_scratch_folder_is_swept_only_when_its_process_is_gone(tmp_path):
    """A live process keeps its folder; a dead pid, or a live pid that belongs to a later process
    than the one that made the folder (another start time), does not."""
    from hub.core import scratch

    sleeper = subprocess.Popen(["sleep", "30"])
    try:
        started = open(f"/proc/{sleeper.pid}/stat").read().rsplit(")", 1)[1].split()[19]
        gone = subprocess.Popen(["true"])
        gone.wait()
        folders = {"live": (sleeper.pid, started), "reused": (sleeper.pid, str(int(started) - 1)),
                   "dead": (gone.pid, "1")}
        made = {}
        for i, (what, (pid, start)) in enumerate(folders.items()):
            made[what] = tmp_path / f"planthub-{pid}-{what[:4]}000{i}"
            made[what].mkdir()
            (made[what] / "owner").write_text(f"{pid} {start}\n")
        (tmp_path / f"planthub-{gone.pid}-notmine1").write_text("a file, not a folder\n")
        removed = scratch.sweep(tmp_path)
    finally:
        sleeper.kill()
        sleeper.wait()
    assert sorted(removed) == sorted([made["reused"], made["dead"]])
    assert made["live"].is_dir() and (tmp_path / f"planthub-{gone.pid}-notmine1").is_file()


FORKED_HANG = """
import os, sys, time
from pathlib import Path
from types import SimpleNamespace
from hub.logic.watchdog import WATCHDOG

class Slave:                  # what the watchdog reads of an FMU slave (hub/logic/fmi.py)
    def __init__(self, since):
        self.busy_since, self.step_timeout, self.time, self.instance = since, 0.2, 1.0, "stuck"
        self.interface = SimpleNamespace(path=Path("stuck.fmu"))

slave = Slave

calm = slave(None)
WATCHDOG.watch(calm)          # the parent's watchdog thread runs
pid = os.fork()
if pid == 0:                  # a campaign's case forked from its zygote (hub/campaign/zygote.py)
    hung = slave(time.monotonic())
    WATCHDOG.watch(hung)
    time.sleep(5.0)
    os._exit(7)               # never reached when the child's own watchdog runs
_, status = os.waitpid(pid, 0)
print(os.waitstatus_to_exitcode(status))
"""


def test_a_forked_child_watches_its_own_fmus_for_hangs():
    """The watchdog's thread is not copied by a fork: a child forked after the parent started it
    starts its own, and a step hung in the child ends the child (exit 1), not the 5 s sleep (7)."""
    done = subprocess.run([sys.executable, "-c", FORKED_HANG], cwd=ROOT, capture_output=True, text=True, timeout=30)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "1", done.stderr
    assert "'stuck' (stuck.fmu)" in done.stderr and "has not returned for" in done.stderr
