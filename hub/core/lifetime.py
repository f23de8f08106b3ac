"""Children never outlive the hub: on Linux a child asks the kernel to kill it when its parent dies (PR_SET_PDEATHSIG), so a hub killed with SIGKILL leaves no participant or FMU worker behind."""
from __future__ import annotations

import ctypes
import os
import signal
import sys

_PR_SET_PDEATHSIG = 1


def die_with_parent(parent: int | None = None) -> None:
    """Ask to be killed (SIGKILL) when the process that started this one ends. If it already
    ended — `parent` is the pid it had — exit at once. Does nothing where prctl is missing."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        return
    if parent is not None and os.getppid() != parent:
        os._exit(1)


#: Runs a command so that it dies with the hub: sets the parent-death signal, then becomes the
#: command (exec), so the command's pid, output and exit code are its own. Costs one Python start.
_TRAMPOLINE = ("import os, sys; from hub.core.lifetime import die_with_parent; "
               "die_with_parent(int(sys.argv[1])); os.execvp(sys.argv[2], sys.argv[2:])")


def guarded(command: list[str]) -> list[str]:
    """`command` wrapped so that the process it starts is killed when this process dies."""
    return [sys.executable, "-c", _TRAMPOLINE, str(os.getpid()), *command]
