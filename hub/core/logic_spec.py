"""State logic attached to an actuator: the module's default FMU, or a replacement, and its wiring."""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from hub.core.resources import BUILT_FMUS


@dataclass(frozen=True)
class LogicSpec:
    """What an actuator module declares about its state logic (its `LOGIC` attribute).

    The FMU runs as the object's `logic` component; `wiring` are flows inside the object
    ("logic.BasePos_got" → "blade.to_base"), added to the scenario's flows when a scenario
    attaches the logic with `logic: default` or `logic: {file: …}`.
    """

    model: str                                   # built by `make fmus`: build/fmus/<model>-fmi2.fmu
    events: tuple[str, ...] = ()                 # FMU Booleans used as events (void slots)
    wiring: tuple[tuple[str, str], ...] = ()     # (source, target) within the object
    #: FMU parameter defaults derived from the object's own parameters (e.g. the initial marking)
    parameters: Callable[[dict], dict] = field(default=lambda params: {})

    @property
    def default_file(self) -> Path:
        return BUILT_FMUS / f"{self.model}-fmi2.fmu"


#: The interfaces of an FMU planthub runs, in the order it prefers them, and the solvers it
#: integrates a model-exchange FMU with (hub/logic/fmi_me.py): named here, where the scenario's
#: options and the command line find them without loading fmpy.
CO_SIMULATION, MODEL_EXCHANGE = INTERFACES = ("co-simulation", "model-exchange")
SOLVERS = ("cvode", "euler")

#: Where an object's logic runs (`runs:`): `hub` — in the hub's process; `child` — in a child
#: process over a pipe; `bus` — in a participant process over the Zenoh bus. hub/logic/factory.py
#: makes the slave for each.
RUNS = ("hub", "child", "bus")

#: The keys `runs:` replaced, by value as written, with what to write instead ("*": any other
#: value): a module's schema names those it had in its `x-replaced`, and the scenario checker
#: says so at the old key's line.
REPLACED = {
    "isolate": {"true": "runs: child", "false": "runs: hub", "*": "runs: child` or `runs: hub"},
    "participant": {"launch": "runs: bus", "join": "runs: bus` with `launch: false", "*": "runs: bus"},
    "in_process": {"true": "runs: hub", "false": "runs: bus", "*": "runs: hub` or `runs: bus"},
}

# `logic:` in a scenario object is `default` (the module's own FMU) or these options, which
# may name a replacement `file` and take the `fmu` module's other options.
OPTIONS = {
    "type": "object",
    "properties": {
        "file": {"type": "string", "description": "a replacement FMU, relative to the scenario file"},
        "parameters": {"type": "object"},
        "map": {"type": "object", "additionalProperties": {"type": "string"}},
        "runs": {"enum": ["hub", "child"]},
        "step": {"type": "number", "exclusiveMinimum": 0},
        "on_bad_value": {"enum": ["stop", "hold"]},
        "on_fault": {"enum": ["stop", "restart"]},
        "step_timeout": {"type": "number", "exclusiveMinimum": 0},
        "interface": {"enum": list(INTERFACES)},
        "solver": {"enum": list(SOLVERS)},
        "max_step": {"type": "number", "exclusiveMinimum": 0},
        "tolerance": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1},
    },
    "additionalProperties": False,
    "x-replaced": {"isolate": REPLACED["isolate"]},
}


def fmu_parameters(spec: LogicSpec, value, base: Path, params: dict) -> dict:
    """The `fmu` module parameters for one attached logic (`value` is "default" or a mapping);
    `params` are the actuator object's own parameters."""
    options = {} if value == "default" else dict(value)
    file = options.pop("file", None)
    return {
        "file": str((base / file).resolve()) if file else str(spec.default_file),
        "parameters": {**spec.parameters(params), **options.pop("parameters", {})},
        "events": list(spec.events),
        **options,
    }


def own_step_problems(params: dict, run) -> list[tuple[tuple, str]]:
    """A logic component's own `step` must be a whole number of the scenario's communication steps."""
    if "step" not in params:
        return []
    every = params["step"] * run.physics_rate / run.substeps
    if round(every) < 1 or abs(every - round(every)) > 1e-9 * every:
        master = run.substeps / run.physics_rate
        return [(("step",), f"{params['step']} s is not a whole number of communication steps ({master:.6g} s)")]
    return []
