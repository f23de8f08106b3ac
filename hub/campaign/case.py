"""One case of a campaign run as a `planthub test` (or `run`) child process, on whatever machine runs it: the verdict, the outcomes and the figures, as plain data.

The child is the hub's own command line, so a case is exactly what a user reruns by hand
(`command` in campaign.json). On Linux it is forked by its worker's zygote (hub/campaign/zygote.py),
which has imported the hub and warmed up once for all the worker's cases; elsewhere it is a fresh
Python. It runs in a session of its own: the campaign, not a terminal's Ctrl-C, decides when it
stops — SIGTERM first, so the run writes its files and summary so far, SIGKILL after GRACE. It
also dies with its worker (Linux's parent-death signal: set on a zygote's fork, which dies with the
zygote, which ends with its worker; on a fresh child by this file run as `python -m
hub.campaign.case`): a worker that dies takes its case with it instead of leaving a run going on
nobody's behalf.
"""
from __future__ import annotations

import ctypes
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from xml.etree import ElementTree

from hub.campaign.zygote import WARM_SECONDS, Forked, zygote_for

GRACE = 10.0     # s a stopped case has to write its files before it is killed
POLL = 0.25      # s between looks at the child, the time limit and the campaign's stop
TAIL = 20        # lines of the child's output kept in a failed case's reason
OUTPUT = "output.txt"   # the child's output in its folder: there once the case began (removed before it is handed out)
#: s the campaign waits for its stopped cases: _stop's SIGTERM and SIGKILL waits after a last look,
#: and the results' way back from the workers
STOPPING = 2 * GRACE + POLL + 4.75
FRESH = "PLANTHUB_CAMPAIGN_FRESH"   # set to 1: every case a fresh Python (no zygote), as before the warm start

PASSED, FAILED, ERROR, TIMEOUT, CRASHED, STOPPED, LOST, NOT_RUN = (
    "passed", "failed", "error", "timeout", "crashed", "stopped", "lost", "not run")


def command(spec: dict) -> list[str]:
    """The child's command line (also what campaign.json shows to rerun a case by hand)."""
    return [sys.executable, "-m", "hub", *arguments(spec)]


def arguments(spec: dict) -> list[str]:
    """The child's arguments to `planthub`."""
    out = Path(spec["out"])
    line = ["test" if spec["judge"] else "run", spec["scenario"], "--out", str(out), "-q"]
    if spec["judge"]:
        line += ["--junit", str(out / "junit.xml")]
    line += _settings(spec["overrides"])
    if spec.get("resume"):
        line += ["--resume", spec["resume"]]
    return line


def _settings(overrides: dict) -> list[str]:
    line = []
    for key, value in overrides.items():
        line += ["--set", f"{key}={json.dumps(value)}"]   # JSON is YAML: --set reads it back as given
    return line


def warm_up(spec: dict) -> list[str]:
    """What a worker's zygote runs before it serves (its output thrown away): a moment of the case's
    scenario with its settings, so that the same modules, checks and compiled loops are warm."""
    return ["run", spec["scenario"], *_settings({**spec["overrides"], "run.duration": WARM_SECONDS})]


def run_case(spec: dict, stopped=lambda: False) -> dict:
    """Run one case to its end, its time limit or until `stopped()` says the campaign stops; never
    raises for anything the case did. `spec`: scenario, out, judge, overrides, resume, time_limit."""
    if stopped():   # handed to its worker as the campaign stopped
        return {"verdict": NOT_RUN, "reason": "not run: the campaign was interrupted", "exit_code": None,
                "wall_seconds": None, "host": socket.gethostname(), "outcomes": [], "figures": {}, "ended": ""}
    out = Path(spec["out"])
    out.mkdir(parents=True, exist_ok=True)
    for old in ("summary.json", "junit.xml"):   # a folder of an earlier campaign judges nothing here
        (out / old).unlink(missing_ok=True)
    started = time.monotonic()
    (out / OUTPUT).write_bytes(b"")
    child = _start(spec, out / OUTPUT)
    ended = None
    while True:
        try:
            code = child.wait(timeout=POLL)
            break
        except subprocess.TimeoutExpired:
            pass
        if ended is None and time.monotonic() - started > spec["time_limit"]:
            ended = TIMEOUT, f"exceeded its time limit of {spec['time_limit']:g} s and was stopped"
        elif ended is None and stopped():
            ended = STOPPED, "stopped: the campaign was interrupted"
        if ended is not None:
            code = _stop(child)
            break
    wall = time.monotonic() - started
    verdict, reason = ended if ended is not None else _judge(code, out)
    return {"verdict": verdict, "reason": reason, "exit_code": code, "wall_seconds": round(wall, 3),
            "host": socket.gethostname(), "outcomes": _outcomes(out / "junit.xml"),
            "figures": _figures(out / "summary.json"), "ended": _ended(out / "summary.json")}


def _start(spec: dict, output: Path) -> subprocess.Popen | Forked:
    """The case's child, its output appended to `output`: forked by this worker's zygote (warm), or
    a fresh Python where there is none (not Linux, PLANTHUB_CAMPAIGN_FRESH=1, or one that would not
    serve). Only the child holds `output` open (tests find a case's process by it)."""
    if sys.platform.startswith("linux") and hasattr(os, "pidfd_open") and os.environ.get(FRESH) != "1":
        zygote = zygote_for(warm_up(spec))
        if zygote is not None:
            try:
                return zygote.fork(arguments(spec), str(output))
            except OSError:   # the zygote is gone: this case starts afresh (the next one a new zygote)
                pass
    with open(output, "ab") as written:
        return subprocess.Popen([sys.executable, "-m", "hub.campaign.case", *command(spec)], stdout=written,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)


def _stop(child: subprocess.Popen | Forked) -> int:
    """SIGTERM to the child's session (the run ends at its next point, files written), SIGKILL
    after GRACE."""
    for sig, wait in ((signal.SIGTERM, GRACE), (signal.SIGKILL, GRACE)):
        try:
            os.killpg(child.pid, sig)
        except ProcessLookupError:   # a forked child before its setsid(): not a group yet
            try:
                os.kill(child.pid, sig)
            except ProcessLookupError:
                pass
        try:
            return child.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            continue
    return child.returncode if child.returncode is not None else -signal.SIGKILL


def _judge(code: int, out: Path) -> tuple[str, str]:
    if code == 0:
        return PASSED, ""
    if code < 0:
        return CRASHED, f"the run was killed by {signal.Signals(-code).name}{_tail(out)}"
    outcomes = _outcomes(out / "junit.xml")
    failed = [o for o in outcomes if o["result"] in ("failure", "error")]
    if code == 1 and failed:
        return FAILED, "; ".join(f"{o['name']}: {o['message']}" for o in failed)
    return ERROR, f"the run exited with {code}{_tail(out)}"


def _tail(out: Path) -> str:
    try:
        lines = (out / OUTPUT).read_text(errors="replace").strip().splitlines()
    except OSError:
        return ""
    return (":\n" + "\n".join(lines[-TAIL:])) if lines else ""


def _outcomes(path: Path) -> list[dict]:
    """The child's JUnit file read back: a dict per testcase — name, result (passed, failure,
    error, skipped) and message."""
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError):
        return []
    found = []
    for case in root.iter("testcase"):
        mark = next((child for child in case if child.tag in ("failure", "error", "skipped")), None)
        found.append({"name": case.get("name", ""), "result": "passed" if mark is None else mark.tag,
                      "message": "" if mark is None else mark.get("message", "")})
    return found


def _summary(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def _ended(path: Path) -> str:
    ended = _summary(path).get("ended") or {}
    return ended.get("reason", "") if isinstance(ended, dict) else ""


def _figures(path: Path) -> dict:
    """The run's figures from its summary.json: simulated time, events, and every number at the top
    of its sections (the plant's bottles in, delivered, …), named section.figure."""
    summary = _summary(path)
    if not summary:
        return {}
    found = {"simulated_s": summary.get("simulated", {}).get("seconds"),
             "events": sum(e.get("count", 0) for e in summary.get("events", {}).values())}
    for section, values in summary.items():
        if section in ("scenario", "file", "ended", "simulated", "wall", "events", "files") or not isinstance(values, dict):
            continue
        for key, value in values.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                found[f"{section}.{key}"] = value
    return found


def _exec_orphan_proof(argv: list[str]) -> None:
    """Become `argv`, set to receive SIGKILL when the thread that started this process ends."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # PR_SET_PDEATHSIG
        if os.getppid() == 1:   # the parent died before the line above: nobody waits for this run
            sys.exit(f"planthub campaign: the worker that started {' '.join(argv)} is gone")
    os.execv(argv[0], argv)


if __name__ == "__main__":
    _exec_orphan_proof(sys.argv[1:])
