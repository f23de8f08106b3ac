"""SSP: a controller delivered as an SSP (System Structure and Parameterization 1.0), its FMUs wired as its SSD says.

Slot types by the connector's type (or, where the SSD gives none, the connected FMU variable's):
Real → real; Integer, Enumeration → int; Boolean → bool; String, Binary → string. An input slot
starts at the start value of the first FMU input it feeds.

Each FMU component of the SSD's system is one FMU instance; each connection either wires two of
them or a system connector to a component's variable. They run as one slave in the hub's process
(hub/logic/ssp_slave.py), stepped as `run.master: jacobi` steps separate `fmu` objects: every
component steps from t with the others' outputs of t, so the SSP gives the recording of the same
FMUs placed as `fmu` objects and wired by hand with flows, bit for bit. A non-finite real passed
from one FMU to another stops the run naming it, as it would entering a flow (`on_bad_value`
applies to the system's outputs only). `run.master: gauss-seidel`
is refused: under it the hand-wired FMUs would hand fresh values over within a step, in an order
the scenario's flows decide, which one object cannot reproduce faithfully for every wiring.

Start values: the SSD's parameter bindings (.ssv files in the archive, or inline), a component's
own first and the system's after them (named `component.variable`, after a binding's prefix); then
the scenario's `parameters`, keyed `component.variable`, each checked against the variable's type,
range and items like an `fmu` object's. A LinearTransformation on a connection between reals
scales the value (factor · x + offset). Nested systems, components that are not FMUs, signal
dictionaries, parameter mappings, mapping transformations and unit conversions are refused by name.
The FMUs are extracted to the run's scratch folder, never next to the scenario.

Why a module and not a scenario that expands the SSP into `fmu` objects and flows: its slots
must be `object.logic.<connector>`, one SSD connector may feed several FMUs and a connection may
carry a transformation, none of which plain objects and flows express without helper objects the
user never wrote; and errors in the SSP are named at the object's `file:` line either way.
"""
from __future__ import annotations

from hub.core.logic_spec import CO_SIMULATION
from hub.core.module import Module
from hub.core.slots import Slot, SlotFamily
from hub.logic.component import LogicComponent
from hub.logic.ssp import SspError, override_problems, read_ssp, start_values
from hub.logic.ssp_slave import SspSlave


class Ssp(Module):
    """A controller from an SSP: its system's input connectors are target slots, its output connectors sources."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "file": {"type": "string", "x-path": True, "description": "the .ssp, relative to the scenario file"},
            "parameters": {"type": "object", "default": {},
                           "description": "start values over the SSP's own, keyed component.variable"},
            "step_timeout": {"type": "number", "exclusiveMinimum": 0, "default": 10,
                             "description": "s one FMU's step may take before the hub ends the run naming it"},
            "on_bad_value": {"enum": ["stop", "hold"], "default": "stop",
                             "description": "a non-finite real from the system: stop the run, or hold the last "
                                            "good value (logged)"},
        },
        "required": ["file"],
        "additionalProperties": False,
    }
    COMPONENTS = {"logic": LogicComponent}
    SLOT_FAMILIES = {"logic": (
        SlotFamily.target("<input>", "the connector's", "each input connector of the system, passed to the FMU "
                                                        "inputs it is connected to"),
        SlotFamily.source("<output>", "the connector's", "each output connector of the system, from the FMU output "
                                                         "connected to it; active every step"))}

    @classmethod
    def check(cls, params):
        try:
            system = read_ssp(params["file"])
        except SspError as exc:
            return [(("file",), problem) for problem in exc.problems]
        return [(("parameters", key), message) for key, message in override_problems(system, params["parameters"])]

    @classmethod
    def check_run(cls, params, run):
        system = read_ssp(params["file"])
        problems = []
        if run.master != "jacobi":
            problems.append((("file",), f"{system.path.name} runs its FMUs as run.master: jacobi does; under "
                                        f"{run.master} the FMUs must be separate `fmu` objects wired by flows"))
        if run.event_driven:
            problems += [(("file",), f"{system.path.name}: component {p.name!r} ({p.fmu.path.name}) cannot handle "
                                     f"variable communication steps, which run.event_driven needs")
                         for p in system.parts if p.fmu.kind == CO_SIMULATION and not p.fmu.variable_steps]
        return problems

    @classmethod
    def slots(cls, params):
        try:
            system = read_ssp(params["file"])
        except (KeyError, SspError):
            return {"logic": ()}   # check() names what is wrong
        return {"logic": tuple(Slot.target(p.name, p.type.value) for p in system.inputs)
                + tuple(Slot.source(p.name, p.type.value) for p in system.outputs)}

    @classmethod
    def build(cls, name, params, world):
        system = read_ssp(params["file"])
        starts = start_values(system, params["parameters"])
        inputs, outputs = [p.name for p in system.inputs], [p.name for p in system.outputs]
        first = {}
        for link in system.links:   # an input slot starts where the first FMU input it feeds does
            if link.start[0] is None and link.start[1] not in first:
                component, variable = link.end
                value = starts[component].get(variable, system.part(component).fmu.variables[variable].start)
                if value is not None:
                    first[link.start[1]] = value
        slave = SspSlave(system, name, inputs, outputs, starts, float(params["step_timeout"]))
        slots = cls.slots(params)["logic"]
        return {"logic": LogicComponent(name, "logic", slots, slave, [(n, False) for n in inputs],
                                        [(n, False) for n in outputs], world.rate, None,
                                        params["on_bad_value"], first)}
