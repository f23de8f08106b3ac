"""The one place that picks a logic transport: an object's logic runs in the hub, in a child process or over the bus, as its scenario says."""
from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass
from pathlib import Path

from hub.bus.lockstep import RemoteSpec
from hub.core.errors import SimulationError
from hub.core.logic_spec import RUNS
from hub.core.slave import LogicSlave
from hub.logic.fmi import FmuInterface
from hub.logic.fmi_me import Integration, open_fmu
from hub.logic.inprocess import InProcessSlave, make_logic
from hub.logic.isolated import IsolatedFmu
from hub.logic.remote import RemoteSlave
from hub.logic.watchdog import WATCHDOG

#: Where logic runs, an object's `runs:` (hub/core/logic_spec.py).
TRANSPORTS = RUNS


@dataclass(frozen=True)
class SlavePlan:
    """What one logic object runs and where: an FMU (`fmu`, its input and output variables in
    slot order) or a Python participant module (`python`: module and arguments), and the
    interface the scenario expects of it (`remote`: name, typed inputs and outputs, parameters,
    the command that launches it, its folder and join time-out)."""

    transport: str
    remote: RemoteSpec
    fmu: FmuInterface | None = None
    variables: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())
    python: tuple[str, ...] | None = None
    step_timeout: float = 10.0   # s one step may take (a child is killed; the hub's own process is ended)
    integration: Integration | None = None   # an FMU's interface and, for model exchange, its solver
    on_fault: str = "stop"       # an FMU in a child process that crashes or hangs: stop the run, or restart it


def make_slave(plan: SlavePlan, rate: int) -> LogicSlave:
    """The slave for `plan` at the scenario's physics `rate` (ticks per second)."""
    if plan.transport not in TRANSPORTS:
        raise SimulationError(f"{plan.remote.label}: unknown transport {plan.transport!r} (known: {', '.join(TRANSPORTS)})")
    spec = plan.remote
    if plan.transport == "bus":
        return RemoteSlave(spec, rate)
    if plan.fmu is not None:
        inputs, outputs = plan.variables
        if plan.transport == "child":
            return IsolatedFmu(plan.fmu, spec.name, list(inputs), list(outputs), dict(spec.parameters),
                               step_timeout=plan.step_timeout, integration=plan.integration,
                               restart=plan.on_fault == "restart")
        slave = open_fmu(plan.fmu, spec.name, list(inputs), list(outputs), dict(spec.parameters),
                         step_timeout=plan.step_timeout, integration=plan.integration)
        WATCHDOG.watch(slave)   # in the hub's own process: a hang past step_timeout ends the process
        return slave
    if plan.python is not None and plan.transport == "hub":
        module, *argv = plan.python
        with _importable(spec.cwd or "."):
            logic = make_logic(module, argv, f"{spec.label} (in-process)")
        return InProcessSlave(spec, logic)
    raise SimulationError(f"{spec.label}: a Python participant runs in the hub or over the bus, not {plan.transport!r}")


@contextlib.contextmanager
def _importable(folder: str):
    """Modules in `folder` (where a launched participant would run) import, as they would there."""
    folder = str(Path(folder).resolve())
    added = folder not in sys.path
    if added:
        sys.path.insert(0, folder)
    try:
        yield
    finally:
        if added:
            sys.path.remove(folder)
