"""A Python participant run inside the hub's process: the same logic as over the bus, without the bus.

A Python participant module (one that `hub.participant.serve`s its logic) names a function
`participant(argv) -> Participant` that makes the logic from its command-line arguments. The
`participant` module runs it either as its own process on the bus (`python -m MODULE ARGS…`)
or here, stepped like an FMU: the same inputs at t, the same `step(t, h)`, the same outputs at
t + h. Every slot type crosses the wire exactly (float64, int64, UTF-8), so both ways give
bit-identical runs (tests/test_inprocess.py); in-process saves the round trip per step.
"""
from __future__ import annotations

import importlib
import traceback

from hub.bus import wire
from hub.bus.lockstep import RemoteSpec, misfit
from hub.core.errors import CheckpointError, PlanthubError, SimulationError
from hub.core.slots import SlotType
from hub.logic.participant_state import pack_state, read_state

FACTORY = "participant"


def make_logic(module: str, argv: list[str], where: str):
    """Import `module` and make its logic with `participant(argv)`; errors name `where`."""
    try:
        code = importlib.import_module(module)
    except ImportError as exc:
        raise SimulationError(f"{where}: cannot import Python module {module!r}: {exc}") from exc
    factory = getattr(code, FACTORY, None)
    if not callable(factory):
        raise SimulationError(f"{where}: module {module!r} has no function {FACTORY}(argv) that makes its logic")
    try:
        return factory(list(argv))
    except SystemExit as exc:   # argparse rejected the arguments (it has printed why)
        raise SimulationError(f"{where}: {module}.{FACTORY}({list(argv)}) rejected its arguments "
                              f"(exit status {exc.code})") from exc


class InProcessSlave:
    """A logic slave (hub.core.slave) over a Participant object in the hub's own process."""

    on_bus = False

    def __init__(self, spec: RemoteSpec, logic, time: float = 0.0):
        self.spec = spec
        self.instance = spec.name
        self.logic = logic
        where = f"{spec.label} (in-process)"
        try:
            inputs, outputs = logic.interface()
        except PlanthubError as exc:
            raise SimulationError(f"{where}: {exc}") from exc
        problems = misfit(spec, inputs, outputs)
        if problems:
            raise SimulationError(f"{where} does not fit the scenario: " + "; ".join(problems))
        # Inputs are set by name; outputs come back in the logic's order, as the bus maps them by name.
        self._in_names = [name for name, _ in spec.inputs]
        out_position = {name: i for i, (name, _) in enumerate(outputs)}
        self._out_order = [out_position[name] for name, _ in spec.outputs]
        # At every step each output is made canonical by the wire's reader of its type, which passes
        # a value of that very type as it is; any other value goes the whole way below, which names it.
        self._readers = [(_reader(name, kind), i) for (name, kind), i in zip(spec.outputs, self._out_order)]
        self._values: list = []
        self._guard(lambda: logic.begin(dict(spec.parameters), time), "at its start")
        self._latest = self._canonical(self._guard(logic.current_outputs, "at its start"), "at its start")

    def _guard(self, call, what: str):
        try:
            return call()
        except Exception as exc:
            detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
            raise SimulationError(f"{self.spec.label} (in-process) failed {what}: {detail}") from exc

    def _canonical(self, values: list, when: str) -> list:
        """In the scenario's order, each checked and made canonical as the bus would (wire.from_wire)."""
        try:
            return [read(values[i]) for read, i in self._readers]
        except (wire.WireError, TypeError):
            pass   # the whole way, for the message
        try:
            return [wire.from_wire(kind, wire.to_wire(kind, values[i]), f"output {name!r}")
                    for (name, kind), i in zip(self.spec.outputs, self._out_order)]
        except (wire.WireError, TypeError) as exc:
            raise SimulationError(f"{self.spec.label} (in-process) gave a bad output {when}: {exc}") from exc

    def set_inputs(self, values: list) -> None:
        self._values = values

    def step(self, t: float, h: float) -> None:
        logic, values = self.logic, self._values
        for name, value in zip(self._in_names, values):
            setattr(logic, name, value)

        def advance():
            logic.step(t, h)
            return logic.current_outputs()
        when = f"in its step at t = {t:.6g} s"
        self._latest = self._canonical(self._guard(advance, when), when)

    def outputs(self) -> list:
        return self._latest

    def save(self) -> bytes:
        """The Participant's own save_state, with the inputs and outputs of its last step: the bytes
        a participant on the bus gives (hub/logic/participant_state.py)."""
        state = self._checkpoint(self.logic.save_state, "save")
        if not isinstance(state, (bytes, bytearray)):
            raise CheckpointError(f"{self.spec.label} (in-process) cannot save its state: save_state gave "
                                  f"{type(state).__name__}, not bytes")
        return pack_state(self.spec, self._values, self._latest, bytes(state))

    def restore(self, state: bytes) -> None:
        """Put back a state saved here or over the bus; the outputs of its last step are again what
        `outputs()` gives, its inputs those `set_inputs` gave."""
        where = f"{self.spec.label} (in-process)"
        inputs, outputs, own = read_state(self.spec, state, where)
        self._checkpoint(lambda: self.logic.restore_state(own), "restore")
        self._latest, self._values = outputs, inputs

    def _checkpoint(self, call, op: str):
        try:
            return call()
        except Exception as exc:   # a participant's own save or restore may raise anything
            detail = str(exc) if isinstance(exc, PlanthubError) else \
                "".join(traceback.format_exception_only(type(exc), exc)).strip()
            raise CheckpointError(f"{self.spec.label} (in-process) could not {op} its state: {detail}") from exc

    def close(self) -> None:
        self.logic.close()


def _reader(name: str, kind: SlotType):
    """value → canonical value of the output `name`, as from_wire(to_wire(value)) makes it."""
    if kind in (SlotType.VEC3, SlotType.QUAT):   # to_wire makes a list of any sequence first
        return lambda value: wire.from_wire(kind, wire.to_wire(kind, value), f"output {name!r}")
    return wire.reader(kind)
