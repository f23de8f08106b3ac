"""The logic-slave contract: what every logic transport (in the hub, in a child process, in-process Python, over the bus) provides."""
from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class LogicSlave(Protocol):
    """One running piece of state logic, stepped by the master at communication points.

    Call order, the same for every transport (FMI's co-simulation order): after construction the
    slave is initialised at its start time and `outputs()` gives its initial outputs; then, for
    each of its communication steps from t to t + h, `set_inputs(values)` with the inputs of t
    (in the order the slave was made with), `step(t, h)`, and `outputs()` — the outputs at
    t + h, which a transport may compute in the meantime (a participant on the bus does). After
    the last step, `close()` once; it releases instances, processes and folders and never raises
    for a slave that already failed.

    `save()` gives the slave's whole state at the communication point it has reached (after its
    last `outputs()`) as bytes, and `restore(state)` puts such bytes back, into this slave or a
    new one made the same way: stepping on from there gives, bit for bit, what the slave that
    saved would have given (hub/core/state.py; an FMU through FMI's own FMU-state calls, a
    participant through the bus's save and restore messages, schemas/wire.md). A slave that
    cannot raises hub.core.errors.CheckpointError naming itself and why, never saving part of it.

    `instance` names the slave in messages. `on_bus` is true for a slave whose logic is served
    over the bus: the run links it to its lockstep before the first point.
    """

    instance: str
    on_bus: bool

    def set_inputs(self, values: list) -> None: ...

    def step(self, t: float, h: float) -> None: ...

    def outputs(self) -> list: ...

    def save(self) -> bytes: ...

    def restore(self, state: bytes) -> None: ...

    def close(self) -> None: ...
