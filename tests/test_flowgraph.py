"""Evaluation order of flows and feedthrough components, and zero-delay loop detection."""
from hub.core.flowgraph import Feedthrough, FlowEdge, plan


def connector(key):
    return Feedthrough(key, frozenset({f"{key}.in0", f"{key}.in1"}), frozenset({f"{key}.out"}))


def test_flows_follow_file_order_when_independent():
    flows = [FlowEdge("a.x.s", "b.x.t"), FlowEdge("c.x.s", "d.x.t")]
    assert plan(flows, []).order == (("flow", 0), ("flow", 1))


def test_a_connector_runs_after_the_flows_into_it_and_before_the_flows_out():
    flows = [FlowEdge("c.l.out", "belt.d.stop"), FlowEdge("s.t.on_enter", "c.l.in0")]
    result = plan(flows, [connector("c.l")])
    assert result.loops == ()
    assert result.order == (("flow", 1), ("component", "c.l"), ("flow", 0))


def test_rearm_from_a_connector_orders_the_flow_after_it():
    flows = [FlowEdge("a.x.s", "b.x.t", rearm="c.l.out"), FlowEdge("s.t.e", "c.l.in0")]
    order = plan(flows, [connector("c.l")]).order
    assert order.index(("component", "c.l")) < order.index(("flow", 0))


def test_two_connectors_in_a_ring_are_a_loop():
    flows = [
        FlowEdge("s.t.e", "c1.l.in0"),
        FlowEdge("c1.l.out", "c2.l.in0"),
        FlowEdge("c2.l.out", "c1.l.in1"),
    ]
    result = plan(flows, [connector("c1.l"), connector("c2.l")])
    assert result.loops == ((1, 2),)
    assert ("flow", 0) in result.order


def test_separate_loops_are_each_reported_once():
    flows = [
        FlowEdge("a.l.out", "a.l.in0"),
        FlowEdge("b.l.out", "c.l.in0"),
        FlowEdge("c.l.out", "b.l.in0"),
        FlowEdge("c.l.out", "x.y.z"),   # downstream of a loop, not part of one
    ]
    result = plan(flows, [connector("a.l"), connector("b.l"), connector("c.l")])
    assert sorted(result.loops) == [(0,), (1, 2)]


def test_a_component_without_feedthrough_breaks_the_loop():
    # belt.drive is not feedthrough: its source only changes after physics, so no loop.
    flows = [FlowEdge("belt.drive.running", "c.l.in0"), FlowEdge("c.l.out", "belt.drive.stop")]
    assert plan(flows, [connector("c.l")]).loops == ()
