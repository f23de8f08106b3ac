"""Builds a checked scenario into a running plant: physics world, objects, slot state and flows."""
from __future__ import annotations

from hub.core.component import Component
from hub.core.flow import Flow
from hub.core.module import DynamicObject
from hub.core.signals import Signals
from hub.core.slots import Direction, SlotRef
from hub.physics import PhysicsWorld
from hub.run.algorithms import GaussSeidel, Jacobi
from hub.scenario.checker import Scenario
from hub.scenario.expectations import Expectation


class Plant:
    """Everything one run needs, built in a fixed order so that two builds are identical."""

    #: hub/core/state.py: the world, the slots' values, the flows' arming and every component's own.
    STATE = ("world", "signals", "flows", "components")

    def __init__(self, scenario: Scenario, every_source: bool = False):
        self.scenario = scenario
        self.world = PhysicsWorld(scenario.run.physics_rate, sleep_after=scenario.run.sleep_after,
                                  solver_iterations=scenario.run.solver_iterations,
                                  integrator=scenario.run.integrator)
        self.world.seed = scenario.run.seed   # for modules that draw at build time (a source's destinations)
        self.world.watch.configure(scenario.run.max_speed, scenario.run.on_violation)
        try:
            self.objects: dict[str, DynamicObject] = {}
            self.components: list[Component] = []
            for spec in scenario.objects:
                self.world.scene.owner = spec.name   # what it builds is its own in the scene (hub/physics/scene.py)
                components = spec.module.build(spec.name, spec.params, self.world)
                if spec.logic is not None:
                    components["logic"] = spec.logic_module.build(spec.name, spec.logic, self.world)["logic"]
                self.objects[spec.name] = DynamicObject(spec.name, spec.module_name, components)
                self.components.extend(components.values())
            self.world.scene.owner = ""
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
            read |= {f.event for f in scenario.faults if f.event is not None}   # what starts a fault (hub/run/faults.py)
            read |= {ref for e in scenario.expect if isinstance(e, Expectation)
                     for ref in (e.slot, e.when, e.show) if ref is not None}
            # The one place that says which sources a component computes (Component.needed): those
            # a flow, the recording or an expectation reads, or every one (`every_source`, for the
            # Python API, which may read any slot), and those a live subscriber watches (`watch`).
            self._needed = {}
            for comp, local in zip(self.components, local_indices):
                if every_source:
                    needed = frozenset(s.name for s in comp.SLOTS if s.direction is Direction.SOURCE)
                else:
                    needed = frozenset(r.slot for r in read if (r.obj, r.component) == (comp.obj, comp.name))
                self._needed[id(comp)] = needed
                comp.bind(self.signals, local, needed)
            self.flows = [
                Flow(self.index[f.source], self.index[f.target], f.condition, f.mode,
                     self.index[f.rearm] if f.rearm else None)
                for f in scenario.flows
            ]
            by_key = {f"{c.obj}.{c.name}": c for c in self.components}
            self.logic = [c for c in self.components if type(c).step is not Component.step]
            between = self._between_logic(by_key) if scenario.run.master == "gauss-seidel" else {}
            self.plan = [
                self.flows[ref].runner(self.signals) if kind == "flow" else by_key[ref].react
                for kind, ref in scenario.order if not (kind == "flow" and ref in between)
            ]
            #: Co-simulation algorithm over the logic components (run.master): steps them over an interval.
            self.algorithm = (GaussSeidel(self.logic, list(between.values()), self.signals) if between
                              else Jacobi(self.logic))
            self.world.start()
        except BaseException:
            self.close()
            raise

    def watch(self, comp: Component, slots) -> None:
        """Let `comp` also compute the sources `slots` (names) while someone watches them live."""
        comp.needed = self._needed[id(comp)] | frozenset(slots)

    def _between_logic(self, by_key) -> dict[int, tuple]:
        """Flows from one logic component to another: flow index → (source comp, target comp, flow)."""
        logic = {id(c) for c in self.logic}
        out = {}
        for i, spec in enumerate(self.scenario.flows):
            a = by_key[f"{spec.source.obj}.{spec.source.component}"]
            b = by_key[f"{spec.target.obj}.{spec.target.component}"]
            if id(a) in logic and id(b) in logic:
                out[i] = (a, b, self.flows[i])
        return out

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
