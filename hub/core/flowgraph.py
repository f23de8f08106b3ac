"""Orders flows and feedthrough components so each step evaluates in one pass; finds zero-delay loops."""
from __future__ import annotations

import heapq
from dataclasses import dataclass


@dataclass(frozen=True)
class FlowEdge:
    """What the graph needs of a flow: the slot addresses it reads and writes."""

    source: str
    target: str
    rearm: str | None = None


@dataclass(frozen=True)
class Feedthrough:
    """A component whose target slots reach its source slots within the same step."""

    key: str
    targets: frozenset[str]
    sources: frozenset[str]


@dataclass(frozen=True)
class Plan:
    """Evaluation order: ("flow", index) and ("component", key) items; `loops` lists flow-index cycles."""

    order: tuple[tuple[str, object], ...]
    loops: tuple[tuple[int, ...], ...]


def plan(flows: list[FlowEdge], feedthrough: list[Feedthrough]) -> Plan:
    """Topologically order the flows and feedthrough components; report every zero-delay loop.

    Ties are broken by declaration order (components first, then flows in file order), so the
    order, and with it every result, is the same in every run.
    """
    nodes = [("component", f.key) for f in feedthrough] + [("flow", i) for i in range(len(flows))]
    rank = {node: n for n, node in enumerate(nodes)}
    writes_into = {}   # target slot of a feedthrough component -> component node
    reads_from = {}    # source slot of a feedthrough component -> component node
    for f in feedthrough:
        for slot in f.targets:
            writes_into[slot] = ("component", f.key)
        for slot in f.sources:
            reads_from[slot] = ("component", f.key)
    successors = {node: [] for node in nodes}
    for i, flow in enumerate(flows):
        node = ("flow", i)
        if flow.target in writes_into:
            successors[node].append(writes_into[flow.target])
        for slot in (flow.source, flow.rearm):
            if slot in reads_from:
                successors[reads_from[slot]].append(node)
    indegree = {node: 0 for node in nodes}
    predecessors = {node: [] for node in nodes}
    for node, succ in successors.items():
        for s in succ:
            indegree[s] += 1
            predecessors[s].append(node)

    ready = [rank[n] for n in nodes if indegree[n] == 0]
    heapq.heapify(ready)
    order = []
    while ready:
        node = nodes[heapq.heappop(ready)]
        order.append(node)
        for s in successors[node]:
            indegree[s] -= 1
            if indegree[s] == 0:
                heapq.heappush(ready, rank[s])
    remaining = {n for n in nodes if indegree[n] > 0}
    return Plan(tuple(order), _loops(remaining, predecessors, rank))


def _loops(remaining, predecessors, rank) -> tuple[tuple[int, ...], ...]:
    """One cycle per strongly knotted group of what could not be ordered, as flow indices."""
    loops = []
    reported = set()
    for start in sorted(remaining, key=rank.get):
        if start in reported:
            continue
        # Every unordered node has an unordered predecessor: walking back must close a cycle.
        path, seen, node = [], {}, start
        while node not in seen and node not in reported:
            seen[node] = len(path)
            path.append(node)
            node = min((p for p in predecessors[node] if p in remaining), key=rank.get)
        if node in reported:
            reported.update(path)
            continue
        cycle = list(reversed(path[seen[node]:]))
        reported.update(path)
        flows = [n[1] for n in cycle if n[0] == "flow"]
        first = flows.index(min(flows))
        loops.append(tuple(flows[first:] + flows[:first]))
    return tuple(loops)
