"""A worker's warm start: one process per worker that has imported the hub and run a moment of the campaign's scenario, forking a child per case.

A case's child started afresh pays, before its run begins, Python's start, the hub's imports,
numba's compiled loops loaded from its cache and the jsonschema checker built: about a second
of a bottling-plant case's 5 s. The zygote pays them once: it imports the hub, runs the first
case's scenario for WARM_SECONDS (`planthub run`, output thrown away), removes that run's
scratch folder, and only then serves. Each case is `os.fork()` of it — a process of its own
still, in a session of its own, with the zygote's warm memory — that returns from `serve()` into
this file's `__main__` and becomes `planthub test ARGS`, as `python -m hub` would, and ends as an
interpreter ends — its threads joined, atexit's handlers run, its streams flushed, its exit status
the same — except that it does not tear down the zygote's modules one by one (`_end`; a bottling
plant's are many, and their teardown writes nothing of the case's). It dies with the zygote
(Linux's parent-death signal), and the zygote with its worker: it reads requests on its stdin and
exits at end of file, so a worker that dies takes its zygote, and so its cases, with it.

Not multiprocessing's forkserver: its children first rerun the parent's main module (Dask's
worker, a benchmark's script), it has no hook for the warm-up run, and they end by os._exit with
no atexit (the hub's scratch folder, its bus sessions).

The protocol is a JSON object a line: to the zygote {"warm": ARGS} once, then {"id": N, "args":
ARGS, "output": PATH}; from it {"ready": true|false, "why": …}, {"id": N, "pid": P} and
{"pid": P, "code": C} (C as subprocess's returncode: negative for a signal).
"""
from __future__ import annotations

import atexit
import ctypes
import json
import os
import runpy
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time

WARM_SECONDS = 0.2   # s of the scenario the zygote runs to warm up: enough for every compiled loop's first call
WARM_LIMIT = 60.0    # s a worker waits for its zygote to be ready before it starts its cases afresh
FORK_LIMIT = 10.0    # s a worker waits for its zygote to fork a case
QUIET = 2.0          # s the zygote waits after its warm-up for the run's helper threads to end
#: threads a warm-up may leave because a forked child starts its own: the FMU watchdog
#: (hub/logic/watchdog.py, which registers what a child does after a fork)
_RESTARTED = {"planthub-watchdog"}


# ---- the worker's side ---------------------------------------------------------------------------

class Zygote:
    """A worker's zygote: started with the args of a case to warm up with; `fork` gives a child
    with `pid`, `wait(timeout)` and `returncode`, like subprocess.Popen's."""

    def __init__(self, warm: list[str]):
        self.process = subprocess.Popen([sys.executable, "-m", "hub.campaign.zygote"], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        self._lock = threading.Lock()            # one request at a time on the pipe
        self._changed = threading.Condition()    # a message came
        self._started: dict[int, int] = {}       # request id → pid
        self._codes: dict[int, int] = {}         # pid → exit code
        self._ready: dict | None = None
        self._gone = False
        self._next = 0
        threading.Thread(target=self._read, name="planthub-zygote-reader", daemon=True).start()
        self._send({"warm": warm})

    def ready(self, limit: float = WARM_LIMIT) -> tuple[bool, str]:
        """Whether the zygote serves (and why not): waits up to `limit` s for its warm-up."""
        with self._changed:
            self._changed.wait_for(lambda: self._ready is not None or self._gone, timeout=limit)
            if self._ready is None:
                return False, "it did not warm up in time" if not self._gone else "it ended"
            return bool(self._ready.get("ready")), self._ready.get("why", "")

    def alive(self) -> bool:
        return not self._gone and self.process.poll() is None

    def fork(self, args: list[str], output: str) -> Forked:
        """A child running `planthub ARGS` with its output to `output`; raises OSError if the zygote
        cannot fork it."""
        with self._lock:
            self._next += 1
            ident = self._next
            self._send({"id": ident, "args": args, "output": output})
        with self._changed:
            if not self._changed.wait_for(lambda: ident in self._started or self._gone, timeout=FORK_LIMIT):
                raise OSError(f"the zygote did not fork the case within {FORK_LIMIT:g} s")
            if ident not in self._started:
                raise OSError("the zygote ended")
            pid = self._started.pop(ident)
        if pid <= 0:
            raise OSError("the zygote could not fork the case")
        return Forked(self, pid)

    def close(self) -> None:
        """End of its stdin: the zygote exits (and any child of it still running dies with it)."""
        try:
            self.process.stdin.close()
        except OSError:
            pass
        try:
            self.process.wait(timeout=FORK_LIMIT)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()

    def _send(self, message: dict) -> None:
        try:
            self.process.stdin.write(json.dumps(message).encode() + b"\n")
            self.process.stdin.flush()
        except (OSError, ValueError) as exc:   # the zygote is gone
            raise OSError(f"the zygote is gone: {exc}") from None

    def _read(self) -> None:
        for line in self.process.stdout:
            message = json.loads(line)
            with self._changed:
                if "ready" in message:
                    self._ready = message
                elif "id" in message:
                    self._started[message["id"]] = message["pid"]
                else:
                    self._codes[message["pid"]] = message["code"]
                self._changed.notify_all()
        with self._changed:
            self._gone = True
            self._changed.notify_all()


class Forked:
    """A case's child forked by a zygote, waited for as a subprocess.Popen is."""

    def __init__(self, zygote: Zygote, pid: int):
        self.zygote, self.pid, self.returncode = zygote, pid, None

    def wait(self, timeout: float | None = None) -> int:
        z = self.zygote
        with z._changed:
            if not z._changed.wait_for(lambda: self.pid in z._codes or z._gone, timeout=timeout):
                raise subprocess.TimeoutExpired(f"case {self.pid}", timeout)
            # a zygote that ended took its children with it (their parent-death signal)
            self.returncode = z._codes.pop(self.pid, -signal.SIGKILL)
        return self.returncode


_mine: Zygote | None = None
_refused: str | None = None   # why this process runs its cases afresh: its zygote would not serve
_start = threading.Lock()


def zygote_for(warm: list[str]) -> Zygote | None:
    """This process's zygote (a Dask worker's: one for all its cases), started and warmed with
    `warm` on first use; None if it cannot serve (its cases then start afresh)."""
    global _mine, _refused
    with _start:
        if _refused is not None:
            return None
        if _mine is None or not _mine.alive():
            _mine = Zygote(warm)
            ok, why = _mine.ready()
            if not ok:
                _mine.close()
                _mine, _refused = None, why or "it refused"
        return _mine


def close_zygote() -> None:
    global _mine
    with _start:
        if _mine is not None:
            _mine.close()
            _mine = None


# ---- the zygote's side ---------------------------------------------------------------------------

def _say(out: int, message: dict) -> None:
    os.write(out, json.dumps(message).encode() + b"\n")


def _planthub(args: list[str]) -> None:
    """`python -m hub ARGS` in this process (the command line is above the campaign: hub/README.md)."""
    sys.argv = ["planthub", *args]
    runpy.run_module("hub", run_name="__main__", alter_sys=True)


def _warm(args: list[str]) -> str:
    """Run the warm-up (`planthub ARGS` with its output thrown away); '' or why the zygote must not serve."""
    from hub.core import scratch

    with tempfile.TemporaryDirectory(prefix="planthub-zygote-") as folder:
        try:
            _planthub([*args, "--out", folder, "-q"])
        except (Exception, SystemExit):   # noqa: BLE001 — a warm-up that fails only warms less: the cases judge
            pass
    sys.stdout.flush()
    sys.stderr.flush()   # nothing of the zygote's buffers written again by its children
    scratch.remove()   # the warm-up's scratch folder: each case makes its own, and removes it
    deadline = time.monotonic() + QUIET
    while _unknown_threads() and time.monotonic() < deadline:
        time.sleep(0.02)
    if _unknown_threads():   # a fork copies one thread: another's locks would stay held forever
        return f"the warm-up left threads running ({', '.join(_unknown_threads())})"
    return ""


def _unknown_threads() -> list[str]:
    return [t.name for t in threading.enumerate() if t is not threading.main_thread() and t.name not in _RESTARTED]


def serve() -> dict | None:
    """The zygote's loop; returns only in a forked child, with its request."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # a terminal's Ctrl-C is the campaign's to handle
    requests, out = os.dup(0), os.dup(1)   # the pipes; 0 and 1 to /dev/null, for the warm-up's prints
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)
    os.close(null)
    children: dict[int, int] = {}   # pidfd → pid
    buffer = b""
    warmed = False
    zygote = os.getpid()
    while True:
        ready, _, _ = select.select([requests, *children], [], [])
        for fd in ready:
            if fd in children:
                pid = children.pop(fd)
                os.close(fd)
                _, status = os.waitpid(pid, 0)
                _say(out, {"pid": pid, "code": os.waitstatus_to_exitcode(status)})
                continue
            data = os.read(requests, 65536)
            if not data:   # the worker is gone, or done: so is the zygote, and its children with it
                return None
            buffer += data
            while b"\n" in buffer:
                line, buffer = buffer.split(b"\n", 1)
                request = json.loads(line)
                if not warmed:
                    warmed = True
                    why = _warm(request["warm"])
                    _say(out, {"ready": not why, "why": why})
                    if why:
                        return None
                    continue
                try:
                    pid = os.fork()
                except OSError:
                    _say(out, {"id": request["id"], "pid": -1})
                    continue
                if pid == 0:
                    for fd in (requests, out, *children):
                        os.close(fd)
                    _become_case(zygote, request["output"])
                    return request
                children[os.pidfd_open(pid)] = pid
                _say(out, {"id": request["id"], "pid": pid})


def _become_case(zygote: int, output: str) -> None:
    """In the forked child: a session of its own, death with the zygote, its output to `output`."""
    os.setsid()
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # PR_SET_PDEATHSIG
    if os.getppid() != zygote:   # the zygote ended before the line above
        os._exit(1)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    written = os.open(output, os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    os.dup2(written, 1)
    os.dup2(written, 2)
    os.close(written)


def _end(args: list[str]):
    """In the forked child: `planthub ARGS`, then the interpreter's end as `python -m hub` makes it
    — a status from SystemExit (a message printed: 1), sys.excepthook for an exception (1), death
    by SIGINT for an uncaught Ctrl-C — after the threads' exit hooks, the threads that are not
    daemons joined, atexit's handlers and the standard streams flushed; then os._exit, which skips
    only the modules' teardown."""
    code, interrupted = 0, False
    try:
        _planthub(args)
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            code = exc.code or 0
        else:
            print(exc.code, file=sys.stderr)
            code = 1
    except KeyboardInterrupt:
        sys.excepthook(*sys.exc_info())
        interrupted = True
    except BaseException:   # noqa: BLE001 — as the interpreter does with an uncaught exception
        sys.excepthook(*sys.exc_info())
        code = 1
    # CPython's own calls at its end, in its order: the threads' exit hooks (an idle executor's
    # workers end only by theirs) and every thread that is not a daemon joined, then atexit's.
    threading._shutdown()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    if interrupted:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.raise_signal(signal.SIGINT)
        code = 128 + signal.SIGINT   # CPython's own status where the signal did not end it
    os._exit(code)


if __name__ == "__main__":
    case = serve()
    if case is not None:
        _end(case["args"])
