"""Builds a checked scenario into a running plant: physics world, objects, slot state and flows."""
from __future__ import annotations

from .component import Component
from .flow import Flow
from .module import DynamicObject
from .physics import PhysicsWorld
from .scenario import Scenario
from .signals import Signals
from .slots import SlotRef


class Plant:
    """Everything one run needs, built in a fixed order so that two builds are identical."""

    def __init__(self, scenario: Scenario):
        self.scenario = scenario
        self.world = PhysicsWorld(scenario.run.physics_rate)
        self.world.seed = scenario.run.seed   # for modules that draw at build time (a source's destinations)
        try:
            self.objects: dict[str, DynamicObject] = {}
            self.components: list[Component] = []
            for spec in scenario.objects:
                components = spec.module.build(spec.name, spec.params, self.world)
                if spec.logic is not None:
                    components["logic"] = spec.logic_module.build(spec.name, spec.logic, self.world)["logic"]
                self.objects[spec.name] = DynamicObject(spec.name, spec.module_name, components)
                self.components.extend(components.values())
            slots, self.index, local_indices = [], {}, []
            for comp in self.components:
                local = {}
                for slot in comp.SLOTS:
                    local[slot.name] = self.index[SlotRef(comp.obj, comp.name, slot.name)] = len(slots)
                    slots.append(slot)
                local_indices.append(local)
            self.signals = Signals(slots)
            read = {f.source for f in scenario.flows} | {f.rearm for f in scenario.flows if f.rearm}
            read |= {ref for ref, _ in scenario.record}
            for comp, local in zip(self.components, local_indices):
                needed = frozenset(r.slot for r in read if (r.obj, r.component) == (comp.obj, comp.name))
                comp.bind(self.signals, local, needed)
            self.flows = [
                Flow(self.index[f.source], self.index[f.target], f.condition, f.mode,
                     self.index[f.rearm] if f.rearm else None)
                for f in scenario.flows
            ]
            by_key = {f"{c.obj}.{c.name}": c for c in self.components}
            self.plan = [
                (lambda flow=self.flows[ref]: flow.run(self.signals)) if kind == "flow" else by_key[ref].react
                for kind, ref in scenario.order
            ]
            self.world.start()
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        try:
            for comp in getattr(self, "components", []):
                comp.close()
        finally:
            self.world.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
