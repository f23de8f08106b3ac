"""An FMU in a child process: a crash of the FMU's code stops the run with a message, not the hub."""
from __future__ import annotations

import multiprocessing
import os
import signal
from dataclasses import dataclass

from hub.core import scratch
from hub.core.errors import CheckpointError, SimulationError
from hub.core.lifetime import die_with_parent
from hub.logic.fmi import FmuInterface
from hub.logic.fmi_me import Integration, open_fmu

#: s an isolated FMU's step may take before its worker is killed (the fmu module's `step_timeout`)
STEP_TIMEOUT = 10.0
#: s its worker may take to start, instantiate and initialise the FMU
START_TIMEOUT = 30.0
#: each message's call, in the message of a worker killed for not answering in time
_WHAT = {"step": "its step", "outputs": "its start", "save": "saving its state", "restore": "restoring its state"}


@dataclass(frozen=True)
class Restart:
    """An isolated FMU restarted (`on_fault: restart`): before the step at `time` s, from its state
    at `since` s and `steps` steps stepped again, after `cause`."""

    instance: str
    time: float
    since: float
    steps: int
    cause: str

    def line(self) -> str:
        return (f"FMU instance {self.instance!r} at t = {self.time:.9g} s, from its state at t = {self.since:.9g} s "
                f"and {self.steps} steps again")


class IsolatedFmu:
    """A logic slave (hub.core.slave) over a pipe to a child process that runs the FMU.

    Each communication step costs one round trip: inputs and the step go out in one message,
    the new outputs come back in the answer. If the child dies (a segfault in the FMU, a kill),
    the next call raises a SimulationError naming the instance and the signal, and everything
    the hub recorded so far stays on disk.

    With `restart` (the fmu module's `on_fault: restart`), a step whose worker died or hung is
    not the end: a new worker is started, given the FMU's state at the last checkpoint (`save`,
    or a `restore`; without one, the state a new worker starts in), and stepped again through
    every step since with the inputs each had, then through the step that failed. An FMU is
    deterministic, so it is where the lost one was, and the run goes on as if nothing happened,
    bit for bit; `restarts` names each (the run's summary lists them). A step that fails again
    after a restart stops the run, naming both causes; an error the FMU reports itself is no
    crash, and stops the run as without `restart`.
    """

    on_bus = False

    def __init__(self, interface: FmuInterface, instance: str, inputs: list[str], outputs: list[str],
                 parameters: dict, start_time: float = 0.0, step_timeout: float = STEP_TIMEOUT,
                 integration: Integration | None = None, restart: bool = False):
        self.interface = interface
        self.instance = instance
        self.time = start_time
        self.step_timeout = step_timeout
        self.restart = restart
        self.restarts: list[Restart] = []
        self._worker = (interface, instance, inputs, outputs, parameters, start_time, integration)
        self._pending = None
        self._start()
        # Where a restart begins: the state at the last checkpoint (None: a new worker's own), its
        # time and outputs, and the steps since (inputs, t, h).
        self._mark: tuple[bytes | None, float, list] = (None, self.time, self._latest)
        self._since: list[tuple[list, float, float]] = []

    def _start(self) -> None:
        interface, instance, inputs, outputs, parameters, start_time, integration = self._worker
        context = multiprocessing.get_context("spawn")   # no fork of a process that holds pybullet
        self._conn, child = context.Pipe()
        self._process = context.Process(
            target=_serve, args=(child, interface, instance, inputs, outputs, parameters, start_time, os.getpid(),
                                 str(scratch.folder()), integration),
            name=f"planthub-fmu-{instance}", daemon=True)
        self._process.start()
        child.close()
        self._lost = False   # the worker died or was killed for hanging
        # Starting includes the FMU's instantiation and initialisation: a longer limit than one step.
        self._latest = self._ask(("outputs",), max(self.step_timeout, START_TIMEOUT))

    def _ask(self, message, limit: float | None = None):
        limit = self.step_timeout if limit is None else limit
        try:
            self._conn.send(message)
            if not self._conn.poll(limit):   # no wait without a limit: a hung FMU is killed
                self._process.kill()
                self._process.join(5)
                self._lost = True
                what = _WHAT[message[0]]
                raise SimulationError(
                    f"FMU instance {self.instance!r} ({self.interface.path.name}) at t = {self.time:.9g} s: "
                    f"{what} did not return within {limit:g} s (step_timeout), so its worker process was killed; "
                    f"the run stops here, the recording so far is kept")
            kind, payload = self._conn.recv()
        except (EOFError, BrokenPipeError, ConnectionResetError):
            self._lost = True
            raise SimulationError(self._died()) from None
        if kind == "error":
            raise SimulationError(payload)
        if kind == "checkpoint":
            raise CheckpointError(payload)
        return payload

    def _died(self) -> str:
        self._process.join(timeout=5)
        code = self._process.exitcode
        if code is not None and code < 0:
            how = f"was killed by {signal.Signals(-code).name}"
        else:
            how = f"exited with code {code}"
        return (f"FMU instance {self.instance!r} ({self.interface.path.name}) at t = {self.time:.9g} s: "
                f"its worker process {how}; the run stops here, the recording so far is kept")

    def set_inputs(self, values: list) -> None:
        self._pending = list(values)

    def step(self, t: float, h: float) -> None:
        self.time = t
        message = ("step", self._pending, t, h)
        try:
            self._latest = self._ask(message)
        except SimulationError as exc:
            if not (self.restart and self._lost):
                raise
            self._restart(t, str(exc))
            try:
                self._latest = self._ask(message)
            except SimulationError as again:
                raise SimulationError(f"{again} (restarted once at this step: {exc})") from None
        if self.restart:
            self._since.append((self._pending, t, h))
        self.time = t + h

    def _restart(self, t: float, cause: str) -> None:
        """A new worker where the lost one was before step `t`: the state at the mark, then the steps since."""
        self.close()
        state, since, _ = self._mark
        self._start()
        if state is not None:
            self._ask(("restore", state))
        for values, at, h in self._since:
            self._ask(("step", values, at, h))
        self.restarts.append(Restart(self.instance, t, since, len(self._since), cause))

    def outputs(self) -> list:
        return self._latest

    def save(self) -> bytes:
        """The child's FmuSlave.save bytes, so a state saved here restores in the hub's process and back."""
        state = self._ask(("save",))
        self._mark, self._since = (state, self.time, self._latest), []
        return state

    def restore(self, state: bytes) -> None:
        self.time, self._latest = self._ask(("restore", bytes(state)))
        self._mark, self._since = (bytes(state), self.time, self._latest), []

    def close(self) -> None:
        if self._process.is_alive():
            try:
                self._conn.send(("close",))
            except (BrokenPipeError, OSError):
                pass
            self._process.join(timeout=5)
        if self._process.is_alive():
            self._process.kill()
            self._process.join()
        self._conn.close()


def probe(interface: FmuInterface) -> str | None:
    """Load the FMU's binary in a child process, instantiate and initialise it with its start
    values, and free it: None if that works, else why not (check-fmu's "cannot load"). In a child,
    so an FMU that crashes or hangs (START_TIMEOUT) is a finding, not the end of the checker."""
    try:
        IsolatedFmu(interface, "check-fmu", [], [], {}).close()
    except SimulationError as exc:
        return str(exc)
    return None


def _serve(conn, interface, instance, inputs, outputs, parameters, start_time, parent, folder, integration) -> None:
    """The child: owns one FMU instance and answers the parent's messages until told to close."""
    die_with_parent(parent)   # a hub killed with SIGKILL takes its FMU workers along
    scratch.adopt(folder)     # and its extracted FMU lies in the hub's folder, which the next run sweeps
    try:
        slave = open_fmu(interface, instance, inputs, outputs, parameters, start_time, integration=integration)
    except SimulationError as exc:
        conn.recv()
        conn.send(("error", str(exc)))
        return
    try:
        while True:
            message = conn.recv()
            if message[0] == "close":
                break
            try:
                if message[0] == "save":
                    conn.send(("ok", slave.save()))
                    continue
                if message[0] == "restore":
                    slave.restore(message[1])
                    conn.send(("ok", (slave.time, slave.outputs())))
                    continue
                if message[0] == "step":
                    _, values, t, h = message
                    slave.set_inputs(values)
                    slave.step(t, h)
                conn.send(("ok", slave.outputs()))
            except CheckpointError as exc:   # the parent raises the same kind
                conn.send(("checkpoint", str(exc)))
            except SimulationError as exc:
                conn.send(("error", str(exc)))
    except EOFError:
        pass   # the parent went away
    finally:
        slave.close()
