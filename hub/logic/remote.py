"""Logic a participant serves over the bus: the slave side of the lockstep (hub/bus/lockstep.py)."""
from __future__ import annotations

from hub.bus.lockstep import Lockstep, RemoteSpec
from hub.core.errors import CheckpointError, SimulationError
from hub.logic.participant_state import pack_state, read_state


class RemoteSlave:
    """A logic slave (hub.core.slave) whose logic a participant serves over the bus.

    `step` only sends the step message; `outputs` waits for the answer. FmuLogic asks for the
    outputs at the next communication point, so participants compute while the hub goes on, and
    in parallel with each other.
    """

    on_bus = True

    def __init__(self, spec: RemoteSpec, rate: int):
        self.spec = spec
        self.rate = rate
        self.instance = spec.name
        self.link: Lockstep | None = None
        self.peer = None   # its state in the link, set when the link starts
        self.sent = 0            # step messages sent; the next step's number
        self._inputs = None

    def set_inputs(self, values: list) -> None:
        self._inputs = values

    def step(self, t: float, h: float) -> None:
        # FmuLogic passes t = tick / rate and h = ticks / rate: rounding recovers the integers exactly.
        rate = self.rate
        self._require().send_step(self, round(t * rate), round(h * rate), t, h, self._inputs)

    def outputs(self) -> list:
        return self._require().collect(self)

    def save(self) -> bytes:
        """The participant's state (asked over the bus) with the inputs and outputs of its last step."""
        if self.link is None:
            raise CheckpointError(f"{self.spec.label} cannot save its state: it is not linked to a running lockstep")
        state = self.link.save(self)   # the last step's outputs are collected first
        return pack_state(self.spec, self._inputs, self.peer.result, state)

    def restore(self, state: bytes) -> None:
        """Hand the participant back a state (from this transport or the in-process one): read here
        first, so a state that does not fit never reaches the participant."""
        if self.link is None:
            raise CheckpointError(f"{self.spec.label} cannot restore its state: it is not linked to a running "
                                  f"lockstep")
        inputs, outputs, own = read_state(self.spec, state, self.spec.label)
        self.link.restore(self, own, outputs)
        self._inputs = inputs

    def _require(self) -> Lockstep:
        if self.link is None:
            raise SimulationError(f"{self.spec.label} is served over the bus, "
                                  f"but the run has not started its lockstep (use Master.run)")
        return self.link

    def close(self) -> None:
        if self.link is not None:
            self.link.release(self)
