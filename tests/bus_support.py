"""Helpers for bus tests: runs that are always closed, processes that are always stopped."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT

BELT_FMU = ROOT / "scenarios" / "belt_ramp_fmu.yaml"
BELT_PARTICIPANT = ROOT / "scenarios" / "belt_ramp_participant.yaml"


@contextlib.contextmanager
def hub(path, out: Path | None = None, overrides: dict | None = None, replay: Path | None = None, **options):
    """A run put together (hub.run.assembly.Run), for runs in pieces (`run.run(until_tick=…)`);
    closed after. With `replay`, the operator commands recorded in that run folder are applied again."""
    with Run(load_scenario(path, overrides), out=out, replay=replay, **options) as run:
        yield run


def same_files(a: Path, b: Path, names=("recording.csv", "events.csv")) -> bool:
    return all((a / n).read_bytes() == (b / n).read_bytes() for n in names)


@contextlib.contextmanager
def process(*args, env: dict | None = None):
    """A child process (python ARGS…), killed and reaped whatever happens; yields the Popen."""
    proc = subprocess.Popen([sys.executable, *map(str, args)], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, **(env or {})})
    try:
        yield proc
    finally:
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(proc.pid, signal.SIGCONT)
            proc.kill()
        proc.communicate(timeout=10)


def output_of(proc, timeout: float = 30) -> tuple[int, str, str]:
    out, err = proc.communicate(timeout=timeout)
    return proc.returncode, out, err


@contextlib.contextmanager
def resumed_at_exit(pid: int):
    """Make sure a process this test stopped (SIGSTOP) is continued and killed at the end."""
    try:
        yield
    finally:
        for sig in (signal.SIGCONT, signal.SIGKILL):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, sig)
