"""FMU: logic or a plant-side model in an FMI 2.0 or 3.0 FMU, stepped at every communication point.

Slot types by FMI type: Real, Float32/64 → real; Integer, Int8…64, UInt8…64, Enumeration → int
(its range checked on every write); Boolean → bool; String → string; Binary → string of hex;
an FMI 3 array → one slot per element (`u_0`, `A_0_1`); clocks and structural parameters are not
mapped (`planthub check-fmu` and `validate` list them, with the reason). `parameters` sets any
variable FMI lets a user set before initialisation — parameters, and inputs and other variables
with a start value — by name (an array also by its own name, as a list), checked against the
variable's type, min/max and enumeration items (an Enumeration also by an item's name).

Variables named in `events` become void slots: a void target sets the Boolean input true in
the steps a flow fed it (false otherwise); a Boolean output true makes the void source fire.
`map` renames variables to slot names. The FMU steps from t to t + h with the inputs it got at
t; its outputs appear at the next communication point. With `runs: child` the FMU runs in a
child process: same results, one pipe round trip per step, and a crash of the FMU's code
stops the run with a message naming it instead of taking the hub down. `step` gives the FMU
its own, longer communication step (a whole number of the scenario's): it then steps only on
its own grid, inputs sampled there and outputs held until its next point. With
`runs: bus` the hub starts `planthub serve-fmu` in a child process that serves the FMU
over the Zenoh bus in lockstep; with `launch: false` beside it, it waits (`join_timeout`) for one
started elsewhere, e.g. on another machine: `planthub serve-fmu FILE --run RUN --name OBJECT
--connect tcp/HUB:PORT`. Same results as in-process, bit for bit. On a bus with TLS the launched
process presents `tls: {certificate, key}`, or else the hub's own certificate, with a warning.

A co-simulation FMU steps itself; an FMI 3 one with event mode has its events handled as they come
(event mode, and a step it returns early from continued to the point). A model-exchange FMU (the
only interface it offers, or `interface: model-exchange`) is integrated by the hub from point to
point with its inputs held: `solver: cvode` (SUNDIALS CVODE from fmpy, variable step, state events
located; `tolerance`, `max_step`) or `euler` (fixed steps of `max_step`); a changed input is an
input event, and time, state and step events are handled in event mode as FMI prescribes.
"""
from __future__ import annotations

import re
import sys

from hub.bus.lockstep import RemoteSpec
from hub.bus.tls import LAUNCHED_SCHEMA, launched_problems
from hub.core.logic_spec import CO_SIMULATION, INTERFACES, MODEL_EXCHANGE, REPLACED, RUNS, SOLVERS, own_step_problems
from hub.core.module import Module
from hub.core.registry import did_you_mean
from hub.core.slots import SlotFamily, SlotType
from hub.logic.component import LogicComponent
from hub.logic.factory import SlavePlan, make_slave
from hub.logic.fmi import FmuError, inspect_fmu
from hub.logic.fmi_me import Integration
from hub.logic.fmi_variables import parameter_problems, parameter_values
from hub.logic.ports import fmu_ports

_SLOT_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class Fmu(Module):
    """Logic in an FMU (FMI 2.0 or 3.0 co-simulation): inputs are target slots, outputs sources."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "file": {"type": "string", "x-path": True, "description": "the .fmu, relative to the scenario file"},
            "parameters": {"type": "object", "default": {},
                           "description": "start values of the FMU's variables, by name: parameters, and inputs "
                                          "and other variables FMI lets a user set before initialisation"},
            "events": {"type": "array", "items": {"type": "string"}, "uniqueItems": True, "default": [],
                       "description": "Boolean inputs/outputs to expose as void (event) slots"},
            "map": {"type": "object", "additionalProperties": {"type": "string", "pattern": _SLOT_NAME.pattern},
                    "default": {}, "description": "variable name → slot name"},
            "step": {"type": "number", "exclusiveMinimum": 0,
                     "description": "the FMU's own communication step, s: a whole number of the scenario's; "
                                    "default: the scenario's"},
            "runs": {"enum": list(RUNS), "default": "hub",
                     "description": "where the FMU runs: hub — in the hub's process; child — in a child process "
                                    "over a pipe (a crash stops the run cleanly); bus — served over the bus by "
                                    "`planthub serve-fmu`"},
            "launch": {"type": "boolean",
                       "description": "with runs: bus — true (default): the hub starts `planthub serve-fmu`; "
                                      "false: one started elsewhere joins"},
            "step_timeout": {"type": "number", "exclusiveMinimum": 0, "default": 10,
                             "description": "s one step may take: past it the worker of an FMU in a child process "
                                            "is killed and an FMU in the hub ends the hub (a C call cannot be "
                                            "interrupted); either way the run stops naming it, with its files complete"},
            "on_fault": {"enum": ["stop", "restart"], "default": "stop",
                         "description": "with runs: child, a worker that crashes or hangs past step_timeout: stop "
                                        "the run (stop), or start a new one from the FMU's state at the last "
                                        "checkpoint, step it again to where the lost one was and go on "
                                        "(restart: the same results, named in the summary)"},
            "on_bad_value": {"enum": ["stop", "hold"], "default": "stop",
                             "description": "a non-finite real from the logic: stop the run, or hold the last good value (logged)"},
            "join_timeout": {"type": "number", "exclusiveMinimum": 0, "default": 10,
                             "description": "s to wait for the participant to join (and to rejoin in a paused run)"},
            "interface": {"enum": list(INTERFACES),
                          "description": "the FMU's interface to run (default: co-simulation where it offers it)"},
            "solver": {"enum": list(SOLVERS),
                       "description": "model exchange: cvode (variable step, default) or euler (fixed steps of max_step)"},
            "max_step": {"type": "number", "exclusiveMinimum": 0,
                         "description": "model exchange: the solver's longest internal step, s (cvode: unlimited)"},
            "tolerance": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1,
                          "description": "model exchange, cvode: the relative tolerance (default 1e-6)"},
            "tls": {**LAUNCHED_SCHEMA, "description": "with runs: bus, the certificate `planthub "
                                                      "serve-fmu` presents on the bus (without: the hub's own, "
                                                      "with a warning)"},
        },
        "required": ["file"],
        "additionalProperties": False,
        "x-replaced": {key: REPLACED[key] for key in ("isolate", "participant")},
    }
    COMPONENTS = {"logic": LogicComponent}
    SLOT_FAMILIES = {"logic": (
        SlotFamily.target("<input>", "the input's", "each FMU input variable; the FMU's start value until fed"),
        SlotFamily.source("<output>", "the output's", "each FMU output variable, active every step"))}

    @classmethod
    def check(cls, params):
        try:
            fmu = inspect_fmu(params["file"])
        except FmuError as exc:
            return [(("file",), str(exc))]
        problems = []
        if params.get("on_fault", "stop") == "restart" and params["runs"] != "child":
            problems.append((("on_fault",), f"on_fault: restart goes with runs: child (an FMU in a worker process "
                                            f"the hub can start again), not runs: {params['runs']}"))
        if "launch" in params and params["runs"] != "bus":
            problems.append((("launch",), f"launch goes with runs: bus (a process serving the FMU over the bus); "
                                          f"with runs: {params['runs']} the hub launches nothing"))
        elif "tls" in params and not cls.launched(params):
            problems.append((("tls",), "a certificate goes with runs: bus, a process the hub starts on the bus; "
                                       "one that joins (launch: false) presents its own (serve-fmu --tls-cert, "
                                       "--tls-key)"))
        kind = params.get("interface", fmu.kind)
        if kind not in fmu.interfaces:
            problems.append((("interface",), f"{fmu.path.name} offers no {kind} interface with a binary for this "
                                             f"platform (it offers: {', '.join(fmu.interfaces)})"))
        elif kind == CO_SIMULATION:
            problems += [((key,), f"{key} is for a model-exchange FMU, which the hub integrates; {fmu.path.name} "
                                  f"runs as co-simulation and steps itself")
                         for key in ("solver", "max_step", "tolerance") if key in params]
        elif params.get("solver") == "euler" and "max_step" not in params:
            problems.append((("solver",), "euler takes fixed steps: give their length as max_step"))
        if params["runs"] == "bus" and not cls.launched(params):
            # A joining serve-fmu integrates with its own command line's settings; the hub cannot set them.
            problems += [((key,), f"{key} is given to the joining process (`planthub serve-fmu --"
                                  f"{key.replace('_', '-')} …`): with launch: false the hub cannot set it")
                         for key in ("interface", "solver", "max_step", "tolerance") if key in params]
        variables = fmu.variables
        ports = {v.name for v in fmu.of("input") + fmu.of("output")}
        problems += [(("parameters", name), message) for name, message in
                     parameter_problems(fmu.path.name, variables, fmu.unmapped, params["parameters"])]
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
    def notes(cls, params):
        """What the hub can live with but a user should know: the FMU's variables without a slot."""
        try:
            fmu = inspect_fmu(params["file"])
        except FmuError:
            return []
        return [(("file",), f"{fmu.path.name}: {name} is not mapped: {why}") for name, why in fmu.unmapped]

    @classmethod
    def check_run(cls, params, run):
        fmu = inspect_fmu(params["file"])
        if (run.event_driven and params.get("interface", fmu.kind) == CO_SIMULATION and not fmu.variable_steps
                and "step" not in params):
            return [(("file",), f"{fmu.path.name} cannot handle variable communication steps, "
                                "which run.event_driven needs (canHandleVariableCommunicationStepSize); "
                                "or give it its own fixed `step`")]
        found = own_step_problems(params, run)
        if "tls" in params:
            found += [(("tls",) + place, message) for place, message in launched_problems(params["tls"], run.bus)]
        return found

    @classmethod
    def slots(cls, params):
        if "file" not in params:
            return {"logic": ()}
        return {"logic": tuple(s for s, _ in fmu_ports(inspect_fmu(params["file"]), params.get("events", ()), params.get("map", {})))}

    @classmethod
    def launched(cls, params) -> bool:
        """Whether the hub starts the process that serves this FMU over the bus."""
        return params["runs"] == "bus" and params.get("launch", True)

    @classmethod
    def serve_command(cls, params) -> list[str]:
        """The command that serves this FMU over the bus (the object's name and the bus come from
        the environment the hub sets; by hand, add --run, --name and --connect)."""
        command = [sys.executable, "-m", "hub", "serve-fmu", params["file"]]
        for name in params.get("events", ()):
            command += ["--event", name]
        for variable, slot in params.get("map", {}).items():
            command += ["--map", f"{variable}={slot}"]
        integration = cls.integration(params)
        if integration.interface == MODEL_EXCHANGE:
            command += ["--interface", MODEL_EXCHANGE, "--solver", integration.solver,
                        "--tolerance", repr(integration.tolerance)]
            if integration.max_step is not None:
                command += ["--max-step", repr(integration.max_step)]
        return command

    @classmethod
    def integration(cls, params) -> Integration:
        """The interface the object runs and, for model exchange, its solver."""
        return Integration(params.get("interface", inspect_fmu(params["file"]).kind),
                           params.get("solver", Integration.solver), params.get("max_step"),
                           params.get("tolerance", Integration.tolerance))

    @classmethod
    def build(cls, name, params, world):
        fmu = inspect_fmu(params["file"])
        ports = fmu_ports(fmu, params["events"], params["map"])
        inputs = [(s, v) for s, v in ports if fmu.variables[v].causality == "input"]
        outputs = [(s, v) for s, v in ports if fmu.variables[v].causality == "output"]
        parameters = parameter_values(fmu.variables, params["parameters"])
        # An input no flow feeds keeps the FMU's start value (or the scenario's, from `parameters`):
        # its slot starts there, and the hub writes it back unchanged until a flow changes it.
        starts = {s.name: parameters.get(v, fmu.variables[v].start) for s, v in inputs
                  if s.type is not SlotType.VOID and parameters.get(v, fmu.variables[v].start) is not None}
        launch = cls.launched(params)
        own = (params["tls"]["certificate"], params["tls"]["key"]) if "tls" in params else None
        spec = RemoteSpec(name, tuple((s.name, s.type) for s, _ in inputs), tuple((s.name, s.type) for s, _ in outputs),
                          parameters, tuple(cls.serve_command(params)) if launch else None,
                          None, float(params["join_timeout"]), f"FMU {fmu.path.name}", tls=own)
        variables = (tuple(v for _, v in inputs), tuple(v for _, v in outputs))
        slave = make_slave(SlavePlan(params["runs"], spec, fmu=fmu, variables=variables,
                                     step_timeout=float(params["step_timeout"]), integration=cls.integration(params),
                                     on_fault=params.get("on_fault", "stop")),
                           world.rate)
        as_pairs = lambda pairs: [(s.name, s.type is SlotType.VOID) for s, _ in pairs]
        every = round(params["step"] * world.rate) if "step" in params else None
        return {"logic": LogicComponent(name, "logic", tuple(s for s, _ in ports), slave,
                                        as_pairs(inputs), as_pairs(outputs), world.rate, every,
                                        params["on_bad_value"], starts)}
