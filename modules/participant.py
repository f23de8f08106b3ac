"""Participant: logic served by another process over the Zenoh bus, stepped in lockstep.

The process (any language: schemas/wire.md; in Python: `hub.participant`) announces the same
inputs and outputs and gets `parameters` when the hub welcomes it. With `command` the hub starts
it (in `cwd`, default the scenario's folder; `python` is the hub's own interpreter) and stops it
at the end; without, it waits `join_timeout` s for one started elsewhere (`--run`, `--name`,
`--connect`). A Python participant can be named by its module instead: `python: [MODULE, ARGS…]`
launches `python -m MODULE ARGS…`. On a bus with TLS a launched process presents `tls: {certificate,
key}` (paths relative to the scenario file), or else the hub's own certificate, with a warning.
With `runs: hub` the hub makes the same logic with MODULE's `participant(ARGS)` and steps it in
its own process, without the bus (hub/logic/inprocess.py): the same results, bit for bit,
without the round trip. Like an FMU it steps from t to t + h with
the inputs of t, and its outputs appear at t + h; `step` gives it its own, longer step. A void
input is true in the steps a flow fed it; a void output true fires the event.
"""
from __future__ import annotations

from hub.bus.lockstep import RemoteSpec
from hub.bus.tls import LAUNCHED_SCHEMA, launched_problems
from hub.core.logic_spec import REPLACED, RUNS, own_step_problems
from hub.core.module import Module
from hub.core.slots import Slot, SlotFamily, SlotType
from hub.logic.component import LogicComponent
from hub.logic.factory import SlavePlan, make_slave

_NAME = "^[A-Za-z_][A-Za-z0-9_]*$"
_TYPES = [t.value for t in SlotType]


class ParticipantModule(Module):
    """Logic in a participant process on the bus: declared inputs and outputs, stepped in lockstep."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "inputs": {"type": "object", "propertyNames": {"pattern": _NAME}, "default": {},
                       "additionalProperties": {"enum": _TYPES}, "description": "input name → slot type (target slots)"},
            "outputs": {"type": "object", "propertyNames": {"pattern": _NAME}, "default": {},
                        "additionalProperties": {"enum": _TYPES}, "description": "output name → slot type (source slots)"},
            "parameters": {"type": "object", "default": {}, "description": "values sent to the participant when it joins"},
            "command": {"type": "array", "items": {"type": "string"}, "minItems": 1,
                        "description": "the hub starts this command (in cwd); without: it joins by itself"},
            "python": {"type": "array", "items": {"type": "string"}, "minItems": 1,
                       "description": "instead of `command`: a Python participant module and its arguments"},
            "runs": {"enum": list(RUNS), "default": "bus",
                     "description": "where the logic runs: bus — a participant process on the bus; hub — with "
                                    "`python`, the same logic inside the hub, without the bus"},
            "cwd": {"type": "string", "x-path": True, "default": ".",
                    "description": "folder the command runs in, relative to the scenario file"},
            "tls": LAUNCHED_SCHEMA,
            "on_bad_value": {"enum": ["stop", "hold"], "default": "stop",
                             "description": "a non-finite real from the logic: stop the run, or hold the last good value (logged)"},
            "join_timeout": {"type": "number", "exclusiveMinimum": 0, "default": 10,
                             "description": "s to wait for it to join (and to rejoin in a paused run)"},
            "step": {"type": "number", "exclusiveMinimum": 0,
                     "description": "its own communication step, s: a whole number of the scenario's"},
        },
        "additionalProperties": False,
        "x-replaced": {"in_process": REPLACED["in_process"]},
    }
    COMPONENTS = {"logic": LogicComponent}
    SLOT_FAMILIES = {"logic": (
        SlotFamily.target("<input>", "declared", "each entry of `inputs`, sent with every step"),
        SlotFamily.source("<output>", "declared", "each entry of `outputs`, from the step's answer"))}

    @classmethod
    def check(cls, params):
        both = sorted(set(params["inputs"]) & set(params["outputs"]))
        problems = [(("outputs", name), f"{name!r} is also an input: slot names must differ") for name in both]
        if "python" in params and "command" in params:
            problems.append((("python",), "give `command` (any program) or `python` (a Python module), not both"))
        if params["runs"] == "child":
            problems.append((("runs",), "a participant runs on the bus, or with `python` in the hub (runs: hub); "
                                        "a child process over a pipe is for an FMU"))
        if params["runs"] == "hub" and "python" not in params:
            problems.append((("runs",), "only a Python participant (`python: [MODULE, ...]`) runs in the hub"))
        if "tls" in params and params["runs"] == "hub":
            problems.append((("tls",), "a participant in the hub is not on the bus: it needs no certificate"))
        elif "tls" in params and "command" not in params and "python" not in params:
            problems.append((("tls",), "the hub launches no process here (no `command` or `python`): a participant "
                                       "that joins by itself presents its own certificate (--tls-cert, --tls-key)"))
        return problems

    @classmethod
    def check_run(cls, params, run):
        found = own_step_problems(params, run)
        if "tls" in params:
            found += [(("tls",) + place, message) for place, message in launched_problems(params["tls"], run.bus)]
        return found

    @classmethod
    def slots(cls, params):
        return {"logic": tuple(Slot.target(n, t) for n, t in params.get("inputs", {}).items())
                + tuple(Slot.source(n, t) for n, t in params.get("outputs", {}).items())}

    @classmethod
    def build(cls, name, params, world):
        inputs = tuple((n, SlotType(t)) for n, t in params["inputs"].items())
        outputs = tuple((n, SlotType(t)) for n, t in params["outputs"].items())
        command = tuple(params["command"]) if "command" in params else None
        if "python" in params:
            command = ("python", "-m", *params["python"])
        own = (params["tls"]["certificate"], params["tls"]["key"]) if "tls" in params else None
        spec = RemoteSpec(name, inputs, outputs, dict(params["parameters"]), command, params["cwd"],
                          float(params["join_timeout"]), tls=own)
        plan = SlavePlan(params["runs"], spec, python=tuple(params["python"]) if "python" in params else None)
        slave = make_slave(plan, world.rate)
        as_pairs = lambda pairs: [(n, k is SlotType.VOID) for n, k in pairs]
        every = round(params["step"] * world.rate) if "step" in params else None
        return {"logic": LogicComponent(name, "logic", cls.slots(params)["logic"], slave,
                                  as_pairs(inputs), as_pairs(outputs), world.rate, every,
                                  params["on_bad_value"])}

