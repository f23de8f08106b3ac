"""The checked scenario: run settings, objects, flows, recorded slots, expectations, faults and exercise — everything the plant builder needs, nothing left to validate."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from hub.bus.settings import BusSettings
from hub.core.flow import Condition, Mode
from hub.core.module import Module
from hub.core.slots import SlotRef, SlotType
from hub.scenario.expectations import Expectation


@dataclass(frozen=True)
class RunSettings:
    physics_rate: int        # ticks per second
    substeps: int            # physics ticks per communication step
    end_tick: int            # a whole number of communication steps
    seed: int
    event_driven: bool = False   # a trigger event ends the communication step at its tick
    master: str = "jacobi"       # or "gauss-seidel": how logic components step (hub/run/algorithms.py)
    jam_after: float = 5.0       # s a bottle stands still on a running belt, not held at a gate, to be jammed (modules/plant/jams.py)
    sleep_after: float = 0.05    # s a bottle stands still where nothing drives it before it rests (hub/physics/rest.py); 0: never
    orders: int | None = None    # the run ends once the sinks took this many bottles (modules/plant/orders.py); None: at its duration
    bus: BusSettings | None = None   # None: no `run.bus` section
    max_speed: float | None = None   # run.watch.max_speed, m/s; None: from the fastest belt (hub/physics/watch.py)
    on_violation: str = "stop"       # run.watch.on_violation: "stop" the run, or "remove" the body and log it
    record_bodies: int = 0           # ticks between two points of the body recording (hub/view/bodies_file.py); 0: none
    solver_iterations: int | None = None   # the engine's constraint solver iterations; None: PhysicsWorld.SOLVER_ITERATIONS
    integrator: str = "exact"        # belt fields: "exact" update, or the paper's "explicit" law (hub/physics/fields.py)

    @property
    def dt(self) -> float:
        return 1.0 / self.physics_rate


@dataclass(frozen=True)
class ObjectSpec:
    name: str
    module: type[Module]
    module_name: str
    params: dict             # with defaults filled in
    logic: dict | None = None   # `fmu` module parameters of the attached state logic
    logic_module: type[Module] | None = None   # the module that builds it (`fmu`)


@dataclass(frozen=True)
class FlowSpec:
    source: SlotRef
    target: SlotRef
    type: SlotType
    condition: Condition
    mode: Mode
    rearm: SlotRef | None
    line: int | None


@dataclass(frozen=True)
class Scenario:
    """A checked scenario: everything the plant builder needs, nothing left to validate."""

    path: Path
    name: str
    description: str
    run: RunSettings
    objects: tuple[ObjectSpec, ...]
    flows: tuple[FlowSpec, ...]
    record: tuple[tuple[SlotRef, SlotType], ...]
    expect: tuple[Expectation, ...]
    order: tuple[tuple[str, object], ...]   # evaluation order of flows and feedthrough components
    faults: tuple = ()        # hub/scenario/faults.py FaultSpec: faults on a schedule
    exercise: object = None   # hub/scenario/exercise.py Exercise: the task, goals and score; None: no exercise

    @property
    def is_plant(self) -> bool:
        return is_plant(self.objects)


def is_plant(objects) -> bool:
    """A scenario is a plant when one of its objects is an end of the material flow (Module.PLANT)."""
    return any(obj.module.PLANT for obj in objects)
