"""Helpers for bus tests: runs with a Master that is always closed, processes that are always stopped."""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from pathlib import Path

from hub.bus.commands import Commands, load_commands
from hub.run.master import Master
from hub.run.plant import Plant
from hub.run.recorder import Recorder
from hub.scenario.checker import load_scenario

from .helpers import ROOT

BELT_FMU = ROOT / "scenarios" / "belt_ramp_fmu.yaml"
BELT_PARTICIPANT = ROOT / "scenarios" / "belt_ramp_participant.yaml"


@contextlib.contextmanager
def hub(path, out: Path | None = None, overrides: dict | None = None, replay: Path | None = None,
        **master_options):
    """A built plant and its Master, for runs in pieces (`master.run(until_tick=…)`); closed after.
    With `replay`, the operator commands recorded in that run folder are applied again."""
    scenario = load_scenario(path, overrides)
    with Plant(scenario) as plant:
        columns = [(ref, kind, plant.index[ref]) for ref, kind in scenario.record]
        recorder = Recorder(columns, scenario.run.physics_rate, out)
        if replay is not None:
            master_options["commands"] = Commands(plant, recorder, load_commands(replay, plant))
        master = Master(plant, recorder, **master_options)
        try:
            yield master
        finally:
            try:
                master.close()
            finally:
                recorder.close()


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
