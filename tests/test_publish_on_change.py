"""Publish on change (`run.bus.publish: change`): a watched slot goes out only at the points where its
value differs from the last sample sent; an event whenever it fires; a viewer that asks for a rate
gets the current values at once. The runs go at the data plane's pace (tests/dataplane_support.py
EveryPoint), so every point is compared.

    belt_ramp_fmu:  drive.logic.speed  0 ─ramp─► 0.5 ── holds ── barrier ─ramp─► 0 ── holds
                    hub ── plant/belt_ramp_fmu/drive/logic/{speed,running} ──► viewer (only changes)
"""
import csv

import pytest

from hub.bus.session import Bus
from hub.bus.settings import BusSettings
from hub.live import Viewer

from .bus_support import BELT_FMU
from .dataplane_support import every_point, settle
from .fmus.fmu_support import build
from .helpers import ROOT

RUN = "belt_ramp_fmu"


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


@pytest.fixture
def bus():
    with Bus(BusSettings(publish="change")) as bus:
        yield bus


def recorded(path, column):
    """(tick, value) of every point of the recording (150 ticks per second)."""
    with open(path / "recording.csv", newline="") as f:
        return [(round(float(r["time"]) * 150), r[column]) for r in csv.DictReader(f)]


def changes(points):
    """The points whose value differs from the point before (and the first)."""
    return [p for n, p in enumerate(points) if n == 0 or p[1] != points[n - 1][1]]


def samples(viewer):
    """Every sample that arrives until none has come for a second (the run is over by then)."""
    out = []
    while (sample := viewer.next(1.0)) is not None:
        out.append(sample)
    return out


def test_a_slot_goes_out_only_when_its_value_changed_and_an_event_whenever_it_fires(bus, tmp_path):
    with every_point(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as viewer:
        master.start()
        viewer.watch("drive/logic/*")
        viewer.watch("barrier/trigger/on_enter")
        settle(master, lambda: len(master.dataplane.live) == 5)   # speed, running, run, speed_setpoint, on_enter
        master.run()
        got = samples(viewer)
        published = master.dataplane.samples
    speed = [(s.tick, s.value) for s in got if s.slot == "drive.logic.speed"]
    running = [(s.tick, s.value) for s in got if s.slot == "drive.logic.running"]
    speed_points = recorded(tmp_path, "drive.logic.speed")
    assert speed == [(tick, float(value)) for tick, value in changes(speed_points)]
    assert len(speed) < len(speed_points) - 100   # it holds 0.5 m/s, then 0, for well over 100 points
    assert running == [(tick, value == "1") for tick, value in changes(recorded(tmp_path, "drive.logic.running"))]
    assert [value for _, value in running] == [False, True, False]
    setpoint = [(s.tick, s.value) for s in got if s.slot == "drive.logic.speed_setpoint"]
    assert setpoint == [(0, 0.5)]   # an input, fed once at the start
    enter = [s for s in got if s.slot == "barrier.trigger.on_enter"]
    assert len(enter) == 1 and enter[0].value is None and enter[0].tick > 0
    assert published == len(got)


def test_a_viewer_that_asks_for_a_rate_gets_the_current_values_though_they_hold(bus, tmp_path):
    with every_point(BELT_FMU, tmp_path, bus=bus) as master, Viewer(RUN, bus.endpoints) as first, \
            Viewer(RUN, bus.endpoints) as second:
        master.start()
        first.watch("drive/logic/speed")
        settle(master, lambda: len(master.dataplane.live) == 1)
        master.run(until_tick=300)                   # t = 2 s: the belt runs at its 0.5 m/s
        second.watch("drive/logic/speed", period=0.02)
        settle(master, lambda: second.id in master.dataplane.requests)
        master.run(until_tick=330)                   # ten more points, the speed holding
        late = samples(second)
        early = samples(first)
    reached = next(tick for tick, value in recorded(tmp_path, "drive.logic.speed") if value == "0.5")
    assert [(s.tick, s.value) for s in late] == [(303, 0.5)]
    assert [(s.tick, s.value) for s in early if s.tick >= reached] == [(reached, 0.5), (303, 0.5)]


def test_the_bus_section_names_how_slots_are_published(write_scenario):
    from hub.core.errors import ScenarioError
    from hub.scenario.checker import load_scenario

    scene = """
        planthub: 1
        run: {{bus: {{publish: {how}}}}}
        objects:
          c: {{module: constant, type: real, value: 1}}
        """
    assert load_scenario(write_scenario(scene.format(how="change"))).run.bus.publish == "change"
    assert BusSettings().publish == "every"
    path = write_scenario(scene.format(how="sometimes"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:2: run.bus.publish: 'sometimes' is not one of ['every', 'change']"]
