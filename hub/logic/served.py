"""An FMU served over the bus as a lockstep participant (`planthub serve-fmu FILE`)."""
from __future__ import annotations

from hub.bus import wire
from hub.bus.participant import Participant
from hub.logic.fmi import inspect_fmu
from hub.logic.fmi_me import Integration, open_fmu
from hub.logic.fmi_variables import parameter_values
from hub.logic.ports import fmu_ports


class FmuParticipant(Participant):
    """Steps one FMU instance with the inputs the hub sends; its slots are the `fmu` module's
    (variables in the FMU's order, `events` as void slots, `map` renaming), so the hub checks
    them against the scenario's object of the same name."""

    def __init__(self, file: str, events=(), rename: dict | None = None, instance: str = "fmu",
                 integration: Integration | None = None):
        self.fmu = inspect_fmu(file)
        self.integration = integration
        self.instance = instance
        ports = fmu_ports(self.fmu, events, rename)   # the `fmu` module's slot rules
        causality = lambda v: self.fmu.variables[v].causality
        self.ports_in = [(s.name, s.type, v) for s, v in ports if causality(v) == "input"]
        self.ports_out = [(s.name, s.type, v) for s, v in ports if causality(v) == "output"]
        self.slave = None

    def interface(self):
        return [(n, k) for n, k, _ in self.ports_in], [(n, k) for n, k, _ in self.ports_out]

    def begin(self, parameters: dict, time: float) -> None:
        values = parameter_values(self.fmu.variables, parameters)   # checked as the hub checked them
        self.slave = open_fmu(self.fmu, self.instance, [v for _, _, v in self.ports_in],
                              [v for _, _, v in self.ports_out], values, time, integration=self.integration)

    def advance(self, t: float, h: float, values: list) -> list:
        self.slave.set_inputs([wire.from_wire(k, x, f"input {n!r}") for (n, k, _), x in zip(self.ports_in, values)])
        self.slave.step(t, h)
        return self.current_outputs()

    def current_outputs(self) -> list:
        return [wire.to_wire(k, x) for (_, k, _), x in zip(self.ports_out, self.slave.outputs())]

    def save_state(self) -> bytes:
        """The FMU slave's own state (FMI's FMU state, serialized): its attributes are not the state."""
        return self.slave.save()

    def restore_state(self, data: bytes) -> None:
        self.slave.restore(data)

    def close(self) -> None:
        if self.slave is not None:
            self.slave.close()
