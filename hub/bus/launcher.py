"""Participant processes the hub starts: started with the bus coordinates, always stopped, never left behind."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from hub.core import scratch
from hub.core.errors import SimulationError
from hub.core.lifetime import guarded


class Launched:
    """One child process serving a participant. Its output goes to a log file whose last lines
    explain a failure; `stop` ends it in every case (asked, then SIGTERM, then SIGKILL)."""

    def __init__(self, name: str, command: list[str], cwd: str | None, env: dict[str, str]):
        self.name = name
        self.command = [sys.executable if i == 0 and part == "python" else part for i, part in enumerate(command)]
        program = self.command[0]
        if shutil.which(program, path=None if os.sep not in program else "") is None and not (
                os.sep in program and os.access(Path(cwd or ".") / program, os.X_OK)):
            # Checked here: the guard that starts it would only fail in the child, with a traceback.
            raise SimulationError(f"participant {name!r}: cannot start {' '.join(command)!r}: No such file or directory")
        # In the hub's scratch folder, as is whatever the process puts in PLANTHUB_SCRATCH: swept by
        # the next run if the hub is killed before it removes them.
        handle, path = tempfile.mkstemp(prefix=f"{name}-", suffix=".log", dir=scratch.folder())
        self.log = Path(path)
        try:
            with os.fdopen(handle, "wb") as out:
                # guarded: the kernel kills it if the hub dies without stopping it (kill -9)
                self.process = subprocess.Popen(
                    guarded(self.command), cwd=cwd, stdin=subprocess.DEVNULL,
                    env={**os.environ, **env, scratch.ENVIRONMENT: str(scratch.folder())},
                    stdout=out, stderr=subprocess.STDOUT,
                    # Its own process group, so a Ctrl-C at the hub's terminal is the hub's to handle;
                    # but the hub's session: with autogroup scheduling (Linux) a new session would make
                    # it a scheduling group of its own, and a lockstep round trip then waits longer
                    # for the CPU at every hand-over between the hub and its participants.
                    process_group=0)
        except OSError as exc:
            self.log.unlink(missing_ok=True)
            raise SimulationError(f"participant {name!r}: cannot start {' '.join(command)!r}: "
                                  f"{exc.strerror or exc}") from None

    @property
    def pid(self) -> int:
        return self.process.pid

    def poll(self, wait: float = 0.0) -> int | None:
        """The exit code once the process ended (negative: killed by that signal), else None."""
        try:
            return self.process.wait(timeout=wait) if wait > 0 else self.process.poll()
        except subprocess.TimeoutExpired:
            return None

    def how_it_ended(self, code: int) -> str:
        if code < 0:
            try:
                return f"was killed by {signal.Signals(-code).name}"
            except ValueError:
                return f"was killed by signal {-code}"
        return f"exited with code {code}"

    def tail(self, lines: int = 12) -> str:
        try:
            text = self.log.read_text(errors="replace").rstrip().splitlines()[-lines:]
        except OSError:
            return ""
        return "\n".join(f"    {line}" for line in text)

    def stop(self, grace: float = 3.0, keep: Path | None = None, as_name: str | None = None) -> list[str]:
        """Wait `grace` s for the process to end by itself (it was told the run stopped), then make it.
        With no grace (a lost participant: maybe frozen, where SIGTERM would wait) it is killed at once.
        Its output is kept as `keep`/NAME.log (`as_name`.log if given) when it said anything; the lines
        it said are returned."""
        try:
            if grace <= 0 and self.poll() is None:
                self.process.kill()
                self.process.wait(5.0)
            elif self.poll(grace) is None:
                self.process.terminate()
                if self.poll(2.0) is None:
                    self.process.kill()
                    self.process.wait(5.0)
        finally:
            said = self._keep(keep, as_name or self.name)
            self.log.unlink(missing_ok=True)
        return said

    def _keep(self, folder: Path | None, name: str) -> list[str]:
        try:
            text = self.log.read_text(errors="replace")
            if folder is not None and text.strip():
                (folder / f"{name}.log").write_text(text)
        except OSError:
            return []
        return text.rstrip().splitlines()
