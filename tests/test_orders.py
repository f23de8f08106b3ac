"""`run.orders`: the plant runs until its sinks have taken a set number of bottles (the
duration stays the limit), from the command line and the Python API; bad settings are named."""
import pytest

from hub import Simulation

from .helpers import ROOT, planthub_run
from .test_plant_summary import taken
from .test_scenario_errors import problems

SOURCE_SINK = ROOT / "scenarios" / "source_sink.yaml"   # 6 bottles, all delivered by 6.5 s


def test_the_run_ends_at_the_point_its_last_order_is_delivered(tmp_path):
    stdout, summary = planthub_run(SOURCE_SINK, tmp_path, "run.orders=4")
    times = [t for t, _, _ in taken(tmp_path)]
    assert len(times) == summary["plant"]["delivered"] == 4
    # The event log reports a bottle taken at the point after the tick it entered the sink,
    # the point at which the run ends.
    assert summary["simulated"]["seconds"] == pytest.approx(times[-1]) and times[-1] < 6.5
    assert f"  ended        4 orders out at t = {times[-1]:.9g} s (run.orders)" in stdout.splitlines()


def test_orders_out_count_the_reject_lane_and_say_how_they_divide(write_scenario, tmp_path):
    """An order is out once its bottle left the line, at a lane's sink or a reject sink: two belts,
    one ending at a sink, one at a reject sink."""
    path = write_scenario("""
        planthub: 1
        run: {duration: 6.0, orders: 5}
        objects:
          lane: {module: conveyor, position: [0, 0, 0], length: 1.0}
          made: {module: source, position: [0.05, 0, 0], count: 3, prefix: G, interval: 0.5}
          sink: {module: sink, position: [0.95, 0, 0.05]}
          scrap: {module: conveyor, position: [0, 1, 0], length: 1.0}
          bad: {module: source, position: [0.05, 1, 0], count: 2, prefix: S, interval: 0.5}
          reject: {module: sink, position: [0.95, 1, 0.05], rejects: true}
        """)
    stdout, summary = planthub_run(path, tmp_path)
    assert summary["plant"]["delivered"] == 3 and len(summary["plant"]["rejected"]) == 2
    assert summary["orders"] == {"wanted": 5, "out": 5, "rejected": 2, "met": True}
    ended = [line for line in stdout.splitlines() if line.startswith("  ended")]
    assert ended[0].startswith("  ended        5 orders out (3 delivered, 2 rejected) at t = ")


def test_the_duration_stays_the_limit_and_the_api_stops_at_the_orders_too(tmp_path):
    with Simulation(SOURCE_SINK, {"run.orders": 6, "run.duration": 3.0}) as sim:
        result = sim.run()
        assert result.stopped_by == "" and sim.time == 3.0 and sim.summary().plant.delivered < 6
    with Simulation(SOURCE_SINK, {"run.orders": 2}) as sim:
        result = sim.run()
        assert sim.summary().plant.delivered == 2 and result.stopped_by.startswith("2 orders out at t = ")
        stopped = sim.time
        sim.run()                     # the run is over: nothing more happens
        assert sim.time == stopped and sim.summary().plant.delivered == 2


def test_orders_need_sinks_and_enough_bottles(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {orders: 3}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0}
          source: {module: source, position: [0.05, 0, 0], count: 2}
        """)
    assert problems(path)[0] == [
        f"{path}:2: run.orders: 3 orders, but no sink takes bottles out: add a `sink` object or leave out run.orders"]
    # Given with --set, the value is blamed there (hub/scenario/checker.py).
    assert problems(SOURCE_SINK, {"run.orders": 7})[0] == [
        "--set: run.orders: 7 orders, but the sources put out only 6 bottles"]
    assert problems(SOURCE_SINK, {"run.orders": 0})[0] == ["--set: run.orders: 0 is less than the minimum of 1"]


def test_orders_with_a_broken_source_report_the_source(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {orders: 3}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0}
          source: {module: source, position: [0.05, 0, 0], count: many}
          sink: {module: sink, position: [0.95, 0, 0.05]}
        """)
    assert problems(path)[0] == [f"{path}:5: objects.source.count: 'many' is not of type 'integer'"]

