"""Co-simulation algorithms: how the logic components step over a communication step (Jacobi, Gauss-Seidel), chosen by `run.master`."""
from __future__ import annotations

import heapq

from hub.core.component import Component
from hub.core.flow import Flow


class Jacobi:
    """Every logic component steps from t with the inputs of the point at t; outputs are seen at
    the next point. The order of the steps cannot change a result."""

    def __init__(self, components: list[Component]):
        self.components = list(components)

    def step(self, start: int, ticks: int) -> None:
        for comp in self.components:
            comp.step(start, ticks)


class GaussSeidel:
    """Steps the logic components (FMUs) one after another over a communication step.

    A flow from one logic component's output to another's input is evaluated here, between
    the two steps, and not at the communication point: the downstream component steps from t
    with the upstream one's outputs at t + h. The order follows those flows; a ring of logic
    components is cut at its first member in declaration order (that one takes the last
    member's outputs from the step before, as Jacobi would). Components that cannot hand over
    outputs at once (no `emit_ready`, or stepping on their own grid) step as under Jacobi.
    """

    def __init__(self, components: list[Component], flows: list[tuple[object, object, Flow]], signals):
        self.signals = signals
        self.order = _order(components, [(a, b) for a, b, _ in flows])
        self.outgoing = {id(c): [flow for a, _, flow in flows if a is c] for c in components}

    def step(self, start: int, ticks: int) -> None:
        for comp in self.order:
            comp.step(start, ticks)
            flows = self.outgoing[id(comp)]
            if flows and comp.emit_ready(start + ticks):
                for flow in flows:
                    flow.run(self.signals)


def _order(components: list[Component], edges: list[tuple[Component, Component]]) -> list[Component]:
    """Topological order (ties and cycles resolved by declaration order)."""
    rank = {id(c): n for n, c in enumerate(components)}
    indegree = {id(c): 0 for c in components}
    successors = {id(c): [] for c in components}
    for a, b in edges:
        if a is not b:
            successors[id(a)].append(b)
            indegree[id(b)] += 1
    order, done = [], set()
    while len(order) < len(components):
        ready = [rank[id(c)] for c in components if id(c) not in done and indegree[id(c)] == 0]
        if not ready:   # a ring: cut it at its first member
            ready = [min(rank[id(c)] for c in components if id(c) not in done)]
        heapq.heapify(ready)
        comp = components[heapq.heappop(ready)]
        order.append(comp)
        done.add(id(comp))
        for b in successors[id(comp)]:
            indegree[id(b)] -= 1
    return order
