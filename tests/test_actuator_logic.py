"""Actuators with their state logic attached (`logic:`): the default nets, and replacements
built by other tools or for FMI 3.0 that must give the same recording."""
import csv
import os
import subprocess
import sys

import pytest

from hub.core.errors import ScenarioError
from hub.core.logic_spec import LogicSpec
from hub.core.registry import Registry
from hub.scenario.checker import load_scenario
from modules import CATALOGUE
from modules.conveyor import Conveyor

from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario

SWITCH = ROOT / "scenarios" / "switch_logic.yaml"


@pytest.fixture(scope="module")
def fmus():
    return build(ROOT / "build" / "fmus")


def export_net(out, net_file):
    """A net run by the Petri reference interpreter inside a PythonFMU export: a third-party FMU."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "fmus")}
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f",
                    str(ROOT / "tests" / "fmu_models" / "python" / "petri_net_py.py"), "-d", str(out),
                    str(ROOT / "fmus" / "petri"), str(ROOT / "fmus" / "nets" / net_file),
                    str(ROOT / "schemas")], check=True, capture_output=True, env=env)
    return out / "petri_net_py.fmu"


@pytest.fixture(scope="module")
def python_net(tmp_path_factory):
    return export_net(tmp_path_factory.mktemp("python_switch"), "track_switch.pnml")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_the_switch_net_diverts_one_bottle_and_lets_the_other_pass(fmus, tmp_path):
    """
        clocks ─► sw.logic.MoveToWorkingPos_put / MoveToBasePos_put ; sw.logic.WorkingPos_marked ─► sw.blade.working
    """
    run_scenario(SWITCH, tmp_path)
    last = rows(tmp_path / "recording.csv")[-1]
    assert last["main_end.count.total"] == "1" and last["branch_end.count.total"] == "1"
    events = [(e["slot"], e["detail"]) for e in rows(tmp_path / "events.csv")]
    assert ("sw.logic.WorkingPosStartAnim_got", "") in events and ("sw.logic.BasePosStartAnim_got", "") in events


@pytest.mark.parametrize("replacement", ["fmi3", "pythonfmu"])
def test_replaced_switch_logic_gives_a_bit_identical_recording(fmus, python_net, tmp_path, replacement):
    file = fmus / "track_switch-fmi3.fmu" if replacement == "fmi3" else python_net
    run_scenario(SWITCH, tmp_path / "default")
    run_scenario(SWITCH, tmp_path / replacement, {"objects.sw.logic": {"file": str(file)}})
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "default" / name).read_bytes() == (tmp_path / replacement / name).read_bytes()


def test_belt_logic_stops_the_belt_on_a_command(fmus, write_scenario, tmp_path):
    path = write_scenario("""
        planthub: 1
        run: {duration: 3, communication_step: 0.02}
        objects:
          belt: {module: conveyor, position: [0, 0, 0], length: 2.0, logic: default}
          bottle: {module: bottle, position: [0.04, 0, 0]}
          barrier: {module: light_barrier, position: [1.0, 0, 0.05]}
        flows:
          - {from: barrier.trigger.on_enter, to: belt.logic.Stop_put}
        record: [belt.drive.running, belt.logic.Running_marked, barrier.trigger.on_enter]
        """)
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert data[0]["belt.logic.Running_marked"] == "1"     # starts as the belt's `running` says
    fired = next(i for i, r in enumerate(data) if r["barrier.trigger.on_enter"] == "1")
    assert data[fired + 1]["belt.logic.Running_marked"] == "0"
    assert data[fired + 2]["belt.drive.running"] == "0"
    assert all(r["belt.drive.running"] == "0" for r in data[fired + 2:])


def problems(path, registry=None):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, registry=registry)
    return [str(p) for p in info.value.problems]


def test_logic_on_a_module_without_one_and_bad_logic_options(fmus, write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          bottle: {module: bottle, position: [0, 0, 0], logic: default}
          belt: {module: conveyor, position: [0, 0, 0], length: 1, logic: {fil: x.fmu}}
          other: {module: conveyor, position: [0, 1, 0], length: 1, logic: {file: nope.fmu}}
          third: {module: conveyor, position: [0, 2, 0], length: 1, logic: true}
        """)
    assert problems(path) == [
        f"{path}:3: objects.bottle.logic: module 'bottle' has no state logic to attach",
        f"{path}:4: objects.belt.logic.fil: unknown key 'fil' (did you mean 'file'?)",
        f"{path}:5: objects.other.logic.file: {path.parent / 'nope.fmu'}: no such FMU file",
        f"{path}:6: objects.third.logic: expected `default` or a mapping of file, parameters, map, runs, "
        f"step, on_bad_value, on_fault, step_timeout, interface, solver, max_step, tolerance, got True",
    ]


class _Unbuilt(Conveyor):
    LOGIC = LogicSpec(model="not_built")


class _Miswired(Conveyor):
    LOGIC = LogicSpec(model="belt_run_stop", wiring=(("logic.Running_tokens", "drive.run"),))


def test_unbuilt_default_logic_and_wiring_that_does_not_fit(fmus, write_scenario):
    registry = Registry({**CATALOGUE, "unbuilt": f"{__name__}:_Unbuilt", "miswired": f"{__name__}:_Miswired"})
    path = write_scenario("""
        planthub: 1
        objects:
          a: {module: unbuilt, position: [0, 0, 0], length: 1, logic: default}
          b: {module: miswired, position: [0, 1, 0], length: 1, logic: default}
        """)
    built = ROOT / "build" / "fmus" / "not_built-fmi2.fmu"
    assert problems(path, registry) == [
        f"{path}:3: objects.a.logic: the default logic of 'unbuilt', {built}, is not built: run `make fmus`",
        f"{path}:4: objects.b.logic: the logic's wiring does not fit: b.logic.Running_tokens is int "
        f"but b.drive.run is bool",
    ]


SEPARATOR = ROOT / "scenarios" / "separator_logic.yaml"


def test_the_separator_net_lets_one_bottle_through_per_cycle_in_order(fmus, tmp_path):
    """
        B326/B327/B321 on_stay ─► sep.logic.*_put ; BasePos_marked ─► sep.bp.closed ; WorkingPos_marked ─► sep.wp.closed
    """
    from .plant_watch import run_watched

    _, _, watch = run_watched(SEPARATOR, tmp_path)
    watch.assert_sound()
    passed = [(float(e["time"]), e["detail"]) for e in rows(tmp_path / "events.csv") if e["slot"] == "out.trigger.on_enter"]
    assert [bottle for _, bottle in passed] == [f"B{n}" for n in range(1, 9)]
    gaps = [b - a for (a, _), (b, _) in zip(passed, passed[1:])]
    assert all(gap >= 0.9 for gap in gaps)     # one per cycle: release 0.4 s + rearm 0.6 s
    assert rows(tmp_path / "recording.csv")[-1]["sink.count.total"] == "8"


@pytest.mark.parametrize("replacement", ["fmi3", "pythonfmu"])
def test_replaced_separator_logic_gives_a_bit_identical_recording(fmus, tmp_path, replacement):
    if replacement == "fmi3":
        file = fmus / "separator-fmi3.fmu"
    else:
        file = export_net(tmp_path / "export", "separator.net.yaml")
    run_scenario(SEPARATOR, tmp_path / "default", {"run.duration": 4.0})
    run_scenario(SEPARATOR, tmp_path / replacement, {"run.duration": 4.0, "objects.sep.logic.file": str(file)})
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "default" / name).read_bytes() == (tmp_path / replacement / name).read_bytes()
    assert sum(1 for e in rows(tmp_path / replacement / "events.csv") if e["slot"] == "out.trigger.on_enter") >= 2


ROBOT = ROOT / "scenarios" / "robot_logic.yaml"


def test_the_robot_net_sequences_the_arm_for_each_released_bottle(fmus, tmp_path):
    """
        store.released ─► robot.logic.Request_put ; Picking/Carrying/Placing/Returning_got ─► robot.arm.*
    """
    from .plant_watch import run_watched

    _, _, watch = run_watched(ROBOT, tmp_path)
    watch.assert_sound()
    events = [(e["slot"], e["detail"]) for e in rows(tmp_path / "events.csv")]
    grips = [d for s, d in events if s == "robot.gripper.on_grip"]
    assert grips == ["S1", "S2"]
    phases = [s.split(".")[-1] for s, _ in events if s.startswith("robot.logic.")]
    assert phases == ["Picking_got", "Carrying_got", "Placing_got", "Returning_got"] * 2
    last = rows(tmp_path / "recording.csv")[-1]
    assert (last["sink.count.A"], last["sink.count.B"]) == ("1", "1")


def test_robot_logic_as_fmi3_gives_a_bit_identical_recording(fmus, tmp_path):
    run_scenario(ROBOT, tmp_path / "fmi2", {"run.duration": 6.0})
    run_scenario(ROBOT, tmp_path / "fmi3", {"run.duration": 6.0, "objects.robot.logic": {"file": str(fmus / "robot_arm-fmi3.fmu")}})
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "fmi2" / name).read_bytes() == (tmp_path / "fmi3" / name).read_bytes()
