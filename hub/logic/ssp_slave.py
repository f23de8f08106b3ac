"""An SSP's FMUs run as one logic slave: its connections routed inside, its system connectors the slave's inputs and outputs."""
from __future__ import annotations

import msgpack

from hub.core.errors import CheckpointError, SimulationError
from hub.logic.fmi import FmuSlave
from hub.logic.fmi_me import open_fmu
from hub.logic.ssp import SspSystem
from hub.logic.watchdog import WATCHDOG

#: names the layout of `SspSlave.save`'s bytes
_STATE_FORMAT = "planthub.ssp-slave/1"


class SspSlave:
    """The components of an SSP system, each an FMU instance, stepped as the master's Jacobi steps
    separate `fmu` objects (hub/run/algorithms.py), so that an SSP and the same FMUs wired by
    hand with flows give the same recording, bit for bit.

    There a flow copies an FMU's output, as sensed at the point t, to another's input before
    either steps from t; here `step(t, h)` hands every component the outputs the others had at t
    (after initialisation, or their last step), then steps each from t to t + h. The system's
    inputs are those of the point t, as any slave's; its outputs are read after the step and seen
    at t + h. A LinearTransformation is applied where it stands; without one a value passes
    untouched (x · 1 + 0 would turn −0.0 into 0.0). A component input no connection feeds is not
    written, so it keeps its start value, as an `fmu` object's unfed input does.

    `inputs` and `outputs` are the system connectors in the slave's order (the object's slots).
    """

    on_bus = False

    def __init__(self, system: SspSystem, instance: str, inputs: list[str], outputs: list[str],
                 parameters: dict[str, dict], step_timeout: float = 10.0):
        self.instance = instance
        self.time = 0.0
        self._parts: list[FmuSlave] = []
        names = [p.name for p in system.parts]
        feeds = {link.end: link for link in system.links}
        fed = {name: [v for (c, v) in feeds if c == name] for name in names}
        read = {name: list(dict.fromkeys(link.start[1] for link in system.links if link.start[0] == name))
                for name in names}
        system_inputs = {name: k for k, name in enumerate(inputs)}

        def source(link):
            if link.start[0] is None:
                return None, system_inputs[link.start[1]], link.scale, str(link)
            return names.index(link.start[0]), read[link.start[0]].index(link.start[1]), link.scale, str(link)

        #: per component, (component or None for the system, position, scale, the connection) of each
        #: input it is fed. No LogicComponent sees a value passed inside, so its finiteness is checked
        #: here, after its transformation, as a flow's would be (hub/logic/component.py).
        self._routes = [[source(feeds[(name, v)]) for v in fed[name]] for name in names]
        self._out = [source(feeds[(None, o)]) for o in outputs]
        try:
            for part in system.parts:
                slave = open_fmu(part.fmu, f"{instance}.{part.name}", fed[part.name], read[part.name],
                                 parameters.get(part.name, {}), step_timeout=step_timeout)
                WATCHDOG.watch(slave)   # in the hub's process, as every FMU stepped here
                self._parts.append(slave)
            self._latest = [slave.outputs() for slave in self._parts]
        except BaseException:
            self.close()
            raise
        self._inputs: list = [None] * len(inputs)

    def set_inputs(self, values: list) -> None:
        self._inputs = values

    def _value(self, route):
        part, k, scale, _ = route
        value = self._inputs[k] if part is None else self._latest[part][k]
        return value if scale is None else value * scale[0] + scale[1]

    def step(self, t: float, h: float) -> None:
        self.time = t
        # Every input from the outputs of t before any component steps: the order cannot matter.
        for slave, routes in zip(self._parts, self._routes):
            if routes:
                values = [self._value(r) for r in routes]
                for value, route in zip(values, routes):
                    if isinstance(value, float) and value - value != 0.0:   # NaN or ±inf
                        raise SimulationError(
                            f"SSP instance {self.instance!r}: connection {route[3]} carries {value!r} at t = {t:.9g} s; "
                            f"a non-finite value is not passed on to an FMU, so the run stops here")
                slave.set_inputs(values)
        for slave in self._parts:
            slave.step(t, h)
        self._latest = [slave.outputs() for slave in self._parts]
        self.time = t + h

    def outputs(self) -> list:
        return [self._value(r) for r in self._out]

    def save(self) -> bytes:
        """Every component's own saved state (each an FmuSlave's bytes) with what this slave holds
        between steps: the system inputs of the last point and the outputs each component gave,
        which the next step routes. A component that cannot save makes the whole system refuse."""
        try:
            parts = [slave.save() for slave in self._parts]
        except CheckpointError as exc:
            raise CheckpointError(f"SSP instance {self.instance!r}: a component cannot save its state: "
                                  f"{exc}") from None
        return msgpack.packb({"format": _STATE_FORMAT, "parts": [s.instance for s in self._parts], "states": parts,
                              "inputs": self._inputs, "latest": self._latest, "time": self.time}, use_bin_type=True)

    def restore(self, state: bytes) -> None:
        where = f"SSP instance {self.instance!r}"
        try:
            saved = msgpack.unpackb(state, raw=False) if isinstance(state, (bytes, bytearray)) else None
        except Exception as exc:   # msgpack raises several types for bytes that are not its own
            raise CheckpointError(f"{where}: the saved state cannot be read ({type(exc).__name__}: {exc})") from None
        if not (isinstance(saved, dict) and saved.get("format") == _STATE_FORMAT):
            raise CheckpointError(f"{where}: the saved state is not an SSP slave's ({_STATE_FORMAT})")
        names = [s.instance for s in self._parts]
        # Components are named <instance>.<component>: a system restored under another object name still fits.
        own = [n.split(".", 1)[-1] for n in names]
        theirs = [str(n).split(".", 1)[-1] for n in saved.get("parts") or []]
        states, latest, inputs = saved.get("states"), saved.get("latest"), saved.get("inputs")
        if theirs != own or not isinstance(states, list) or len(states) != len(own) \
                or not isinstance(latest, list) or len(latest) != len(own) \
                or not isinstance(inputs, list) or len(inputs) != len(self._inputs) \
                or not isinstance(saved.get("time"), (int, float)):
            raise CheckpointError(f"{where}: the saved state is of a system with components {theirs}, this one has "
                                  f"{own} (or its inputs or time do not fit)")
        for slave, part in zip(self._parts, states):
            slave.restore(part)
        self._latest, self._inputs, self.time = latest, inputs, saved.get("time")

    def close(self) -> None:
        failure = None
        for slave in self._parts:
            try:
                slave.close()
            except Exception as exc:   # free every instance, then tell of the first that refused
                failure = failure or exc
        self._parts = []
        if failure is not None:
            raise SimulationError(f"SSP instance {self.instance!r}: closing failed: {failure}") from failure
