"""The module contract: a plant element type that a scenario instantiates as a dynamic object."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hub.core.component import Component
from hub.core.logic_spec import LogicSpec
from hub.core.slots import Slot, SlotFamily


@dataclass
class DynamicObject:
    """One plant element instance (`belt3`, `bottle17`): a named container of components."""

    name: str
    module: str
    components: dict[str, Component]


class Module:
    """Base of element modules. A subclass declares:

    - `PARAMETERS`: a JSON Schema (an object schema) of its scenario parameters, with defaults;
    - `COMPONENTS`: component name → component class, whose `SLOTS` make the module's slot table;
    - `build(name, params, world)`: the components of one instance, with its physics created;
    - optionally `LOGIC`: its default state logic FMU and how it is wired to its components.
    """

    PARAMETERS: ClassVar[dict] = {"type": "object", "properties": {}}
    COMPONENTS: ClassVar[dict[str, type[Component]]] = {}
    #: The actuator's state logic (an FMU) that a scenario attaches with `logic:`; None: it has none.
    LOGIC: ClassVar[LogicSpec | None] = None
    #: An end of the material flow (a source, a sink): a scenario with one is a *plant*, which
    #: gets the plant's figures, `jams: none` expectations and `run.orders`. The one definition.
    PLANT: ClassVar[bool] = False
    #: Takes bottles out of the plant (a sink): what `run.orders` counts.
    TAKES_OUT: ClassVar[bool] = False
    #: Observers and stop conditions this module contributes to every run that holds one of its
    #: objects, as entry points "package.file:factory"; each distinct factory is called once per
    #: run with the built plant and returns an Observer, a StopCondition, both, or None
    #: (hub/core/observer.py).
    CONTRIBUTES: ClassVar[tuple[str, ...]] = ()
    #: Slots its parameters name or type, component → families (an FMU's `logic.<input>`, a
    #: constant's `value.out` of the `type` parameter): its reference lists a family in place of
    #: the slot of the same name that default parameters give, and the others after their
    #: component's slots.
    SLOT_FAMILIES: ClassVar[dict[str, tuple[SlotFamily, ...]]] = {}

    @classmethod
    def slots(cls, params: dict) -> dict[str, tuple[Slot, ...]]:
        """Component name → its slots, for checking a scenario without building anything."""
        return {name: comp.SLOTS for name, comp in cls.COMPONENTS.items()}

    @classmethod
    def reference_slots(cls) -> list[tuple[str, Slot | SlotFamily]]:
        """(component, slot or family), in the order the module's reference lists them."""
        slots = dict(cls.slots(cls.with_defaults({})))
        rows = []
        for component in {**slots, **cls.SLOT_FAMILIES}:
            families = {f.name: f for f in cls.SLOT_FAMILIES.get(component, ())}
            for slot in slots.get(component, ()):
                rows.append((component, families.pop(slot.name, slot)))
            rows += [(component, family) for family in families.values()]
        return rows

    @classmethod
    def members(cls, name: str, params: dict) -> dict[str, dict[str, tuple[Slot, ...]]]:
        """Objects an instance makes beside itself, addressable by their own names in `record:`,
        expectations and flows (a source's bottles, by id): member name → component name → slots.
        `build` returns their components too, with the member's name as their object."""
        return {}

    @classmethod
    def feedthrough(cls, params: dict) -> dict[str, tuple[tuple[str, str], ...]]:
        """Component name → its (target, source) pairs that pass within one step."""
        return {name: comp.FEEDTHROUGH for name, comp in cls.COMPONENTS.items() if comp.FEEDTHROUGH}

    @classmethod
    def check(cls, params: dict) -> list[tuple[tuple, str]]:
        """Problems the parameter schema cannot express, as (path within params, message)."""
        return []

    @classmethod
    def notes(cls, params: dict) -> list[tuple[tuple, str]]:
        """Findings a run can live with but a user should hear of at `validate` (path, message)."""
        return []

    @classmethod
    def check_run(cls, params: dict, run) -> list[tuple[tuple, str]]:
        """Problems of these parameters under the scenario's run settings (`RunSettings`)."""
        return []

    @classmethod
    def supply(cls, name: str, params: dict, seed: int) -> int:
        """Bottles an object of this module puts on the line over a run (a source's store)."""
        return 0

    @classmethod
    def with_defaults(cls, params: dict) -> dict:
        """The parameters with every default from `PARAMETERS` filled in."""
        out = {k: v["default"] for k, v in cls.PARAMETERS.get("properties", {}).items() if "default" in v}
        out.update(params)
        return out

    @classmethod
    def build(cls, name: str, params: dict, world) -> dict[str, Component]:
        raise NotImplementedError
