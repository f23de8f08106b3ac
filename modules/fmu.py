"""FMU: logic in an FMI 2.0 or 3.0 co-simulation FMU, stepped at every communication point.

| slot           | type        | dir    | meaning                                                  |
|----------------|-------------|--------|----------------------------------------------------------|
| logic.<input>  | the input's | target | each FMU input variable (Real, Integer, Boolean, String) |
| logic.<output> | the output's| source | each FMU output variable, active every step              |

Variables named in `events` become void slots: a void target sets the Boolean input true in
the steps a flow fed it (false otherwise); a Boolean output true makes the void source fire.
`map` renames variables to slot names. The FMU steps from t to t + h with the inputs it got at
t; its outputs appear at the next communication point. With `isolate: true` the FMU runs in a
child process: same results, one pipe round trip per step, and a crash of the FMU's code
stops the run with a message naming it instead of taking the hub down. `step` gives the FMU
its own, longer communication step (a whole number of the scenario's): it then steps only on
its own grid, inputs sampled there and outputs held until its next point. With
`participant: launch` the hub starts `planthub serve-fmu` in a child process that serves the FMU
over the Zenoh bus in lockstep; with `participant: join` it waits (`join_timeout`) for one
started elsewhere, e.g. on another machine: `planthub serve-fmu FILE --run RUN --name OBJECT
--connect tcp/HUB:PORT`. Same results as in-process, bit for bit.
"""
from __future__ import annotations

import re
import sys

from hub.component import Component
from hub.fmu import FmuError, FmuSlave, inspect_fmu
from hub.fmu_process import IsolatedFmu
from hub.lockstep import RemoteSlave, RemoteSpec
from hub.logic import own_step_problems
from hub.module import Module
from hub.registry import did_you_mean
from hub.slots import Slot, SlotType

_SLOT_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class FmuLogic(Component):
    """Steps its FMU over the master's communication steps, or over its own longer `every` ticks.

    Jacobi in both cases: the FMU steps from t with the inputs it got at t, and its new outputs
    are held back until the point at t + h, so the result does not depend on when the master
    calls it in between. They are fetched only there (`slave.outputs()`), so logic served by a
    participant computes while the hub goes on: the step is sent in `step`, collected in `sense`.
    """

    def __init__(self, obj, name, slots, slave, inputs, outputs, rate: int, every: int | None):
        super().__init__(obj, name)
        self.SLOTS = slots
        self.slave = slave
        self.inputs = inputs      # [(slot name, is event)] in the FMU's input order
        self.outputs = outputs    # [(slot name, is event)] in the FMU's output order
        self.rate = rate
        self.every = every        # own step in ticks, or None: every master step
        self.latest = None        # outputs in use; fetched at the first point
        self.ready_at = None      # the tick at which the last step's outputs are due
        self._reads = ()          # (slot number, is event) per input, in the FMU's order
        self._writes = ()         # (slot number, is event) per output

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        # Slot numbers resolved once: sense and step run at every point for every logic object.
        self._reads = tuple((index[slot], event) for slot, event in self.inputs)
        self._writes = tuple((index[slot], event) for slot, event in self.outputs)

    def sense(self, tick):
        if self.latest is None or (self.ready_at is not None and tick >= self.ready_at):
            self.latest, self.ready_at = self.slave.outputs(), None
        signals = self.signals
        values, active = signals.values, signals.active
        for (i, event), value in zip(self._writes, self.latest):   # Signals.emit, inlined
            if not event:
                if value is not None:
                    values[i] = value
                active[i] = True
            elif value:
                active[i] = True

    def step(self, tick, ticks):
        if self.every is not None:
            if tick % self.every:
                return   # between two of its own points: it already stepped over this interval
            ticks = self.every
        signals = self.signals
        updated, values = signals.updated, signals.values
        self.slave.set_inputs([updated[i] if event else values[i] for i, event in self._reads])
        self.slave.step(tick / self.rate, ticks / self.rate)
        self.ready_at = tick + ticks

    def emit_ready(self, tick):
        if self.ready_at != tick:
            return False   # stepping on its own grid: its outputs belong to a later point
        self.latest, self.ready_at = self.slave.outputs(), None
        self.sense(tick)
        return True

    def close(self):
        self.slave.close()


class Fmu(Module):
    """Logic in an FMU (FMI 2.0 or 3.0 co-simulation): inputs are target slots, outputs sources."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "file": {"type": "string", "x-path": True, "description": "the .fmu, relative to the scenario file"},
            "parameters": {"type": "object", "default": {},
                           "description": "values of the FMU's parameters, by variable name"},
            "events": {"type": "array", "items": {"type": "string"}, "uniqueItems": True, "default": [],
                       "description": "Boolean inputs/outputs to expose as void (event) slots"},
            "map": {"type": "object", "additionalProperties": {"type": "string", "pattern": _SLOT_NAME.pattern},
                    "default": {}, "description": "variable name → slot name"},
            "step": {"type": "number", "exclusiveMinimum": 0,
                     "description": "the FMU's own communication step, s: a whole number of the scenario's; "
                                    "default: the scenario's"},
            "isolate": {"type": "boolean", "default": False,
                        "description": "run the FMU in a child process: a crash stops the run cleanly"},
            "participant": {"enum": ["launch", "join"],
                            "description": "serve the FMU over the bus: launch — the hub starts `planthub serve-fmu`; "
                                           "join — one started elsewhere joins (default: in the hub)"},
            "join_timeout": {"type": "number", "exclusiveMinimum": 0, "default": 10,
                             "description": "s to wait for the participant to join (and to rejoin in a paused run)"},
        },
        "required": ["file"],
        "additionalProperties": False,
    }
    COMPONENTS = {"logic": FmuLogic}

    @classmethod
    def check(cls, params):
        try:
            fmu = inspect_fmu(params["file"])
        except FmuError as exc:
            return [(("file",), str(exc))]
        problems = []
        if params["isolate"] and "participant" in params:
            problems.append((("isolate",), "isolate and participant exclude each other: a child process over a "
                                           "pipe, or a participant over the bus"))
        variables = fmu.variables
        ports = {v.name for v in fmu.of("input") + fmu.of("output")}
        tunable = {v.name: v for v in fmu.of("parameter")}
        for name, value in params["parameters"].items():
            if name not in tunable:
                problems.append((("parameters", name), f"{fmu.path.name} has no parameter {name!r}"
                                 f"{did_you_mean(name, tunable)}"))
                continue
            try:
                tunable[name].type.coerce(value)
            except ValueError as exc:
                problems.append((("parameters", name), f"{name} is {tunable[name].fmi_type}: {exc}"))
        for i, name in enumerate(params["events"]):
            if name not in ports:
                problems.append((("events", i), f"{fmu.path.name} has no input or output {name!r}"
                                 f"{did_you_mean(name, ports)}"))
            elif variables[name].type is not SlotType.BOOL:
                problems.append((("events", i), f"{name} is {variables[name].fmi_type}; only a Boolean can be an event"))
        for name in params["map"]:
            if name not in ports:
                problems.append((("map", name), f"{fmu.path.name} has no input or output {name!r}"
                                 f"{did_you_mean(name, ports)}"))
        for v in fmu.of("input") + fmu.of("output"):
            slot = params["map"].get(v.name, v.name)
            if not _SLOT_NAME.match(slot):
                problems.append((("map",), f"variable {v.name!r} needs a slot name: add `{v.name}: some_name` to map"))
        return problems

    @classmethod
    def check_run(cls, params, run):
        fmu = inspect_fmu(params["file"])
        if run.event_driven and not fmu.variable_steps and "step" not in params:
            return [(("file",), f"{fmu.path.name} cannot handle variable communication steps, "
                                "which run.event_driven needs (canHandleVariableCommunicationStepSize); "
                                "or give it its own fixed `step`")]
        return own_step_problems(params, run)

    @classmethod
    def slots(cls, params):
        if "file" not in params:
            return {"logic": ()}
        return {"logic": tuple(s for s, _ in cls._ports(params, inspect_fmu(params["file"])))}

    @classmethod
    def _ports(cls, params, fmu):
        """(slot, variable name) for every input then every output, in the FMU's order."""
        out = []
        events, names = set(params.get("events", ())), params.get("map", {})
        for causality, make in (("input", Slot.target), ("output", Slot.source)):
            for v in fmu.of(causality):
                kind = "void" if v.name in events else v.type.value
                out.append((make(names.get(v.name, v.name), kind, v.description), v.name))
        return out

    @classmethod
    def serve_command(cls, params) -> list[str]:
        """The command that serves this FMU over the bus (the object's name and the bus come from
        the environment the hub sets; by hand, add --run, --name and --connect)."""
        command = [sys.executable, "-m", "hub", "serve-fmu", params["file"]]
        for name in params.get("events", ()):
            command += ["--event", name]
        for variable, slot in params.get("map", {}).items():
            command += ["--map", f"{variable}={slot}"]
        return command

    @classmethod
    def _remote(cls, name, params, fmu, inputs, outputs, parameters) -> RemoteSpec:
        return RemoteSpec(name, tuple((s.name, s.type) for s, _ in inputs), tuple((s.name, s.type) for s, _ in outputs),
                          parameters, tuple(cls.serve_command(params)) if params["participant"] == "launch" else None,
                          None, float(params["join_timeout"]), f"FMU {fmu.path.name}")

    @classmethod
    def build(cls, name, params, world):
        fmu = inspect_fmu(params["file"])
        ports = cls._ports(params, fmu)
        inputs = [(s, v) for s, v in ports if fmu.variables[v].causality == "input"]
        outputs = [(s, v) for s, v in ports if fmu.variables[v].causality == "output"]
        parameters = {k: fmu.variables[k].type.coerce(v) for k, v in params["parameters"].items()}
        if "participant" in params:
            slave = RemoteSlave(cls._remote(name, params, fmu, inputs, outputs, parameters), world.rate)
        else:
            runner = IsolatedFmu if params["isolate"] else FmuSlave
            slave = runner(fmu, name, [v for _, v in inputs], [v for _, v in outputs], parameters)
        as_pairs = lambda pairs: [(s.name, s.type is SlotType.VOID) for s, _ in pairs]
        every = round(params["step"] * world.rate) if "step" in params else None
        return {"logic": FmuLogic(name, "logic", tuple(s for s, _ in ports), slave,
                                  as_pairs(inputs), as_pairs(outputs), world.rate, every)}
