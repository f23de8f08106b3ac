"""FMU logic in the step loop: the belt-drive FMU drives a belt; bad FMUs are named clearly."""
import csv
import zipfile

import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.scenario.checker import load_scenario

from .fmus.fmu_support import build
from .foreign_fmus import build_python_fmu
from .helpers import ROOT, run_scenario

SCENARIO = ROOT / "scenarios" / "belt_ramp_fmu.yaml"
BUILT = ROOT / "build" / "fmus"


@pytest.fixture(scope="module")
def fmus():
    """The project's FMUs, brought up to date (free after `make fmus`)."""
    return build(BUILT)


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """The test-only `faulty` model (tests/fmu_models/faulty) built for FMI 2 and 3."""
    return build(tmp_path_factory.mktemp("faulty"), models_dir=ROOT / "tests" / "fmu_models")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_fmu_ramps_the_belt_and_its_output_lags_one_communication_step(fmus, tmp_path):
    """
        go ─► drive.logic.run ; setpoint ─► drive.logic.speed_setpoint ; drive.logic.speed ─► belt.drive.speed
        barrier.on_enter ─► stop ─► drive.logic.run (false)
    """
    run_scenario(SCENARIO, tmp_path)
    data = rows(tmp_path / "recording.csv")
    speed = [float(r["drive.logic.speed"]) for r in data]
    h = 0.02
    # Ramp 0.5 m/s² from t = 0: the output at point k is what the step ending there computed.
    assert speed[0] == 0.0 and speed[1] == pytest.approx(0.5 * h)
    assert speed[50] == 0.5   # 1.0 s: the setpoint is reached exactly, not one step late
    # The belt takes the FMU's speed at the point it is sensed; its own source shows it one point later.
    for k in range(1, 60):
        assert float(data[k + 1]["belt.drive.velocity"]) == speed[k]
    fired = next(k for k, r in enumerate(data) if r["barrier.trigger.on_enter"] == "1")
    assert speed[fired] == 0.5 and speed[fired + 1] == pytest.approx(0.5 - 0.5 * h)
    stopped = next(k for k in range(fired, len(speed)) if speed[k] == 0.0)
    assert (stopped - fired) * h == pytest.approx(1.0)
    assert data[stopped]["drive.logic.running"] == "0"
    assert abs(float(data[-1]["bottle.body.position.x"]) - float(data[-20]["bottle.body.position.x"])) < 1e-5


def test_fmi2_and_fmi3_builds_give_bit_identical_recordings(fmus, tmp_path):
    run_scenario(SCENARIO, tmp_path / "fmi2")
    run_scenario(SCENARIO, tmp_path / "fmi3", {"objects.drive.file": str(fmus / "belt_drive-fmi3.fmu")})
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "fmi2" / name).read_bytes() == (tmp_path / "fmi3" / name).read_bytes()


def scene(write_scenario, drive: str, flows: str = ""):
    return write_scenario(f"""
        planthub: 1
        objects:
          belt: {{module: conveyor, position: [0, 0, 0], length: 2}}
          drive: {{module: fmu, {drive}}}
        flows: [{flows}]
        """)


def problems(path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p) for p in info.value.problems]


def test_missing_file_not_a_zip_and_no_description(fmus, write_scenario, tmp_path):
    (tmp_path / "text.fmu").write_text("not a zip")
    with zipfile.ZipFile(tmp_path / "empty.fmu", "w") as z:
        z.writestr("readme.txt", "nothing")
    for name, cause in [("nope.fmu", "no such FMU file"),
                        ("text.fmu", "not an FMU (an FMU is a zip archive)"),
                        ("empty.fmu", "no modelDescription.xml in the archive")]:
        path = scene(write_scenario, f"file: {name}")
        assert problems(path) == [f"{path}:4: objects.drive.file: {tmp_path / name}: {cause}"]


def rewrite(source, target, edit_xml=None, drop=None):
    """Copy an FMU, editing its modelDescription.xml and dropping archive members."""
    with zipfile.ZipFile(source) as src, zipfile.ZipFile(target, "w") as dst:
        for item in src.infolist():
            if drop and drop(item.filename):
                continue
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml" and edit_xml:
                data = edit_xml(data.decode()).encode()
            dst.writestr(item, data)


def test_fmi1_and_missing_binary(fmus, write_scenario, tmp_path):
    fmi2 = fmus / "belt_drive-fmi2.fmu"
    rewrite(fmi2, tmp_path / "nobin.fmu", drop=lambda name: name.startswith("binaries/"))
    rewrite(fmi2, tmp_path / "v1.fmu", edit_xml=lambda x: x.replace('fmiVersion="2.0"', 'fmiVersion="1.0"'))
    found = {}
    for name in ("nobin.fmu", "v1.fmu"):
        found[name] = problems(scene(write_scenario, f"file: {name}", ""))[0].split(": objects.drive.file: ")[1]
    assert found["nobin.fmu"] == (f"{tmp_path / 'nobin.fmu'}: no binary for this platform "
                                  f"(binaries/linux64/belt_drive.so); the FMU has: none")
    assert found["v1.fmu"] == (f"{tmp_path / 'v1.fmu'}: FMI 1.0 is not supported "
                               f"(planthub loads FMI 2.0 and 3.0 FMUs, co-simulation or model exchange)")


def test_unknown_parameter_event_and_type_mismatch(fmus, write_scenario):
    drive = f"file: {fmus / 'belt_drive-fmi2.fmu'}, parameters: {{rampe: 1, }}, events: [speed]"
    path = scene(write_scenario, drive)
    assert problems(path) == [
        f"{path}:4: objects.drive.parameters.rampe: belt_drive-fmi2.fmu has no variable 'rampe' that can be set "
        f"(did you mean 'ramp'?)",
        f"{path}:4: objects.drive.events[0]: speed is Real; only a Boolean can be an event",
    ]
    path = scene(write_scenario, f"file: {fmus / 'belt_drive-fmi2.fmu'}", "{from: drive.logic.speed, to: belt.drive.run}")
    assert problems(path) == [f"{path}:5: flows[0]: type mismatch: drive.logic.speed is real but belt.drive.run is bool"]


def test_map_names_a_variable_the_fmu_lacks(fmus, write_scenario):
    path = scene(write_scenario, f"file: {fmus / 'belt_drive-fmi2.fmu'}, map: {{sped: belt_speed}}")
    assert problems(path) == [f"{path}:4: objects.drive.map.sped: belt_drive-fmi2.fmu has no input or output "
                              f"'sped' (did you mean 'speed'?)"]


def test_map_renames_slots(fmus, write_scenario):
    path = scene(write_scenario, f"file: {fmus / 'belt_drive-fmi2.fmu'}, map: {{speed: belt_speed}}",
                 "{from: drive.logic.belt_speed, to: belt.drive.speed}")
    assert [str(f.source) for f in load_scenario(path).flows] == ["drive.logic.belt_speed"]


def test_parameter_of_the_wrong_type(fmus, write_scenario):
    path = scene(write_scenario, f"file: {fmus / 'belt_drive-fmi2.fmu'}, parameters: {{ramp: fast}}")
    assert problems(path) == [f"{path}:4: objects.drive.parameters.ramp: ramp is Real: expected a finite number, "
                              f"got 'fast'"]


@pytest.mark.parametrize("version", [2, 3])
def test_failing_do_step_names_instance_function_time_and_log(faulty, write_scenario, tmp_path, version):
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.1}}
        objects:
          counter: {{module: fmu, file: {faulty / f'faulty-fmi{version}.fmu'}}}
          fail: {{module: constant, type: bool, value: true}}
          other: {{module: fmu, file: {faulty / f'faulty-fmi{version}.fmu'}}}
        record: [counter.logic.steps]
        """)
    # `counter` gets fail = true at once; `other`, a second instance of the same FMU, keeps counting
    # and must not swallow the failing instance's log lines.
    text = path.read_text() + "flows:\n  - {from: fail.value.out, to: counter.logic.fail, when: target}\n"
    path.write_text(text)
    out = tmp_path / "out"
    with pytest.raises(SimulationError) as info:
        run_scenario(path, out)
    message = str(info.value)
    assert message.startswith(f"FMU instance 'counter' (faulty-fmi{version}.fmu) at t = 0 s: "
                              f"fmi{version}DoStep returned error\n  FMU log:\n")
    assert "faulty: asked to fail at t = 0 s after 0 steps" in message
    # What was recorded before the failure is on disk.
    assert rows(out / "recording.csv")[0]["counter.logic.steps"] == "0"


def check_fmu(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "hub", "check-fmu", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT)


def test_check_fmu_accepts_a_fitting_replacement(fmus):
    proc = check_fmu(fmus / "belt_drive-fmi3.fmu", "--like", fmus / "belt_drive-fmi2.fmu")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "  target slots  run (bool, start false), speed_setpoint (real, start 0)\n" in proc.stdout
    assert "  settable      ramp (real, start 0, 0 … ∞)\n" in proc.stdout
    assert proc.stdout.endswith(f"  ✓ passes fmpy's validation; fits in place of {fmus / 'belt_drive-fmi2.fmu'}\n")


def test_check_fmu_lists_what_a_replacement_lacks(fmus):
    proc = check_fmu(fmus / "timer-fmi2.fmu", "--like", fmus / "belt_drive-fmi2.fmu")
    assert proc.returncode == 1
    assert "  ✗ missing input 'run' (bool)\n" in proc.stdout
    assert "  ✗ missing output 'speed' (real)\n" in proc.stdout
    assert "  ✗ no parameter 'ramp' (a scenario setting it would be rejected)\n" in proc.stdout


def test_check_fmu_names_an_unusable_file(tmp_path):
    (tmp_path / "x.fmu").write_text("plain text")
    proc = check_fmu(tmp_path / "x.fmu")
    assert proc.returncode == 1
    assert proc.stderr == f"planthub: {tmp_path / 'x.fmu'}: not an FMU (an FMU is a zip archive)\n"


def first_response(data, event_time):
    """Time at which the belt's speed command first reacts to the stop that the event caused."""
    return next(float(r["time"]) for r in data
                if float(r["time"]) > event_time and float(r["drive.logic.speed"]) < 0.5)


def test_event_driven_points_cut_the_sensor_to_actuator_latency(fmus, tmp_path):
    settings = {"run.communication_step": 0.2}
    run_scenario(SCENARIO, tmp_path / "fixed", settings)
    run_scenario(SCENARIO, tmp_path / "events", {**settings, "run.event_driven": True})
    fixed, events = rows(tmp_path / "fixed" / "recording.csv"), rows(tmp_path / "events" / "recording.csv")
    enter = [float(e["time"]) for e in rows(tmp_path / "events" / "events.csv") if e["slot"].endswith("on_enter")]
    assert len(enter) == 1
    # A communication point at the event's own tick, where the stop reaches the FMU's input.
    at_event = next(r for r in events if float(r["time"]) == enter[0])
    assert at_event["barrier.trigger.on_enter"] == "1"
    # The regular grid is kept around the extra point.
    assert {round(float(r["time"]), 9) for r in fixed} <= {round(float(r["time"]), 9) for r in events}
    latency_fixed = first_response(fixed, enter[0]) - enter[0]
    latency_events = first_response(events, enter[0]) - enter[0]
    # The step after the event lasts one tick: the FMU's answer reaches the belt one tick later.
    assert latency_events == pytest.approx(1 / 150)
    assert latency_fixed > 0.2


def test_event_driven_run_rejects_an_fmu_with_fixed_steps(fmus, write_scenario, tmp_path):
    rewrite(fmus / "belt_drive-fmi2.fmu", tmp_path / "fixed.fmu", edit_xml=lambda x: x.replace(
        'canHandleVariableCommunicationStepSize="true"', 'canHandleVariableCommunicationStepSize="false"'))
    path = write_scenario("""
        planthub: 1
        run: {event_driven: true}
        objects:
          drive: {module: fmu, file: fixed.fmu}
        """)
    assert problems(path) == [f"{path}:4: objects.drive.file: fixed.fmu cannot handle variable communication "
                              f"steps, which run.event_driven needs (canHandleVariableCommunicationStepSize); "
                              f"or give it its own fixed `step`"]


@pytest.fixture(scope="module")
def python_fmu(tmp_path_factory):
    """tests/fmu_models/python/belt_drive_py.py exported by PythonFMU: an FMU another tool built."""
    return build_python_fmu(tmp_path_factory.mktemp("pythonfmu"))


def test_a_pythonfmu_export_replaces_the_c_fmu_bit_for_bit(fmus, python_fmu, tmp_path):
    run_scenario(SCENARIO, tmp_path / "c")
    run_scenario(SCENARIO, tmp_path / "python", {"objects.drive.file": str(python_fmu)})
    for name in ("recording.csv", "events.csv"):
        assert (tmp_path / "c" / name).read_bytes() == (tmp_path / "python" / name).read_bytes()
    speeds = {r["drive.logic.speed"] for r in rows(tmp_path / "python" / "recording.csv")}
    assert len(speeds) > 20   # the logic really ran: the ramp passes many values


def test_check_fmu_warns_of_what_fmpy_validation_finds_in_a_third_party_fmu(fmus, python_fmu):
    """PythonFMU leaves InitialUnknowns out of ModelStructure: a finding, and the hub runs the FMU
    correctly (the test above), so a warning and exit 0, not a failure."""
    proc = check_fmu(python_fmu, "--like", fmus / "belt_drive-fmi2.fmu")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "  target slots  run (bool, start false), speed_setpoint (real, start 0)\n" in proc.stdout
    assert "  ! validation: ModelStructure/InitialUnknowns does not contain the expected set of variables." \
        in proc.stdout
    assert proc.stdout.endswith(f"  ✓ usable, with 1 warning (above); fits in place of {fmus / 'belt_drive-fmi2.fmu'}\n")


def test_an_isolated_fmu_gives_the_same_recording(fmus, tmp_path):
    run_scenario(SCENARIO, tmp_path / "in")
    run_scenario(SCENARIO, tmp_path / "out", {"objects.drive.runs": "child"})
    assert (tmp_path / "in" / "recording.csv").read_bytes() == (tmp_path / "out" / "recording.csv").read_bytes()


def counter_scene(write_scenario, fmu, isolate, extra="", objects="", flows=""):
    return write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.1}}
        objects:
          counter: {{module: fmu, file: {fmu}, runs: {'child' if isolate else 'hub'}{extra}}}
          {objects}
        flows: [{flows}]
        record: [counter.logic.steps]
        """)


def test_a_crashing_fmu_in_a_child_process_stops_the_run_with_its_name(faulty, write_scenario, tmp_path):
    path = counter_scene(write_scenario, faulty / "faulty-fmi2.fmu", True, ", parameters: {crash_at: 4}")
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == ("FMU instance 'counter' (faulty-fmi2.fmu) at t = 0.3 s: its worker process was "
                               "killed by SIGSEGV; the run stops here, the recording so far is kept")
    recorded = [r["counter.logic.steps"] for r in rows(tmp_path / "out" / "recording.csv")]
    assert recorded == ["0", "1", "2", "3"]


def test_a_failing_isolated_fmu_reports_like_an_in_process_one(faulty, write_scenario, tmp_path):
    path = counter_scene(write_scenario, faulty / "faulty-fmi3.fmu", True,
                         objects="fail: {module: constant, type: bool, value: true}",
                         flows="{from: fail.value.out, to: counter.logic.fail, when: target}")
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value).startswith("FMU instance 'counter' (faulty-fmi3.fmu) at t = 0 s: "
                                      "fmi3DoStep returned error\n  FMU log:\n")


def test_an_fmu_with_its_own_step_samples_and_answers_on_its_grid(fmus, tmp_path):
    run_scenario(SCENARIO, tmp_path, {"objects.drive.step": 0.1})
    data = rows(tmp_path / "recording.csv")
    speed = [(round(float(r["time"]), 9), float(r["drive.logic.speed"])) for r in data]
    # While ramping up (0.5 m/s² over 0.1 s steps): 0.05 more at every 0.1 s, held in between.
    for t, v in speed:
        if t < 1.0:
            assert v == pytest.approx(0.05 * int(t / 0.1 + 1e-9)), t


def test_own_step_must_be_whole_master_steps(fmus, write_scenario):
    path = write_scenario(f"""
        planthub: 1
        run: {{physics_rate: 150, communication_step: 0.02}}
        objects:
          drive: {{module: fmu, file: {fmus / 'belt_drive-fmi2.fmu'}, step: 0.05}}
        """)
    assert problems(path) == [f"{path}:4: objects.drive.step: 0.05 s is not a whole number of "
                              f"communication steps (0.02 s)"]


@pytest.mark.parametrize("master, lag", [("jacobi", 1), ("gauss-seidel", 0)])
def test_gauss_seidel_hands_fresh_outputs_down_the_flow(fmus, write_scenario, tmp_path, master, lag):
    """
        a (ramp 0.5 m/s²).speed ──► b.speed_setpoint ; b (ramp 0: follows at once).speed
    Declared downstream first, so only the flow order can put `a` before `b`.
    """
    drive = fmus / "belt_drive-fmi2.fmu"
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.1, master: {master}}}
        objects:
          b: {{module: fmu, file: {drive}, parameters: {{ramp: 0.0}}}}
          a: {{module: fmu, file: {drive}, parameters: {{ramp: 0.5}}}}
          go: {{module: constant, type: bool, value: true}}
          full: {{module: constant, type: real, value: 0.5}}
        flows:
          - {{from: go.value.out, to: a.logic.run, when: target}}
          - {{from: go.value.out, to: b.logic.run, when: target}}
          - {{from: full.value.out, to: a.logic.speed_setpoint, when: target}}
          - {{from: a.logic.speed, to: b.logic.speed_setpoint}}
        record: [a.logic.speed, b.logic.speed]
        """)
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    a = [float(r["a.logic.speed"]) for r in data]
    b = [float(r["b.logic.speed"]) for r in data]
    assert a[3] == pytest.approx(0.15)
    for k in range(1 + lag, len(data)):
        assert b[k] == a[k - lag], (master, k)


def test_an_fmus_description_is_read_once_per_load(fmus, tmp_path, monkeypatch):
    """Checking, the slot table and the build share one reading of modelDescription.xml; an FMU
    rebuilt (here: touched with new content) between loads is read again."""
    import shutil

    from hub.logic import fmi
    from hub.run.plant import Plant

    shutil.copy(BUILT / "belt_drive-fmi2.fmu", tmp_path / "drive.fmu")
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENARIO.read_text().replace("../build/fmus/belt_drive-fmi2.fmu", "drive.fmu"))
    reads = []
    real = fmi.read_model_description
    monkeypatch.setattr(fmi, "read_model_description", lambda path, **kw: reads.append(path) or real(path, **kw))
    with Plant(load_scenario(scene)):
        pass
    assert len(reads) == 1
    with zipfile.ZipFile(tmp_path / "drive.fmu", "a") as archive:   # a new version of the file
        archive.writestr("documentation/note.txt", "rebuilt")
    load_scenario(scene)
    assert len(reads) == 2


def test_an_event_into_a_boolean_names_events_or_constant(fmus, write_scenario):
    """A void source into a Boolean target: an FMU's input is told to be listed in `events:`
    (by its variable's name, not its mapped slot's), any other target is told of `constant`."""
    path = write_scenario(f"""
        planthub: 1
        objects:
          belt: {{module: conveyor, position: [0, 0, 0], length: 2}}
          barrier: {{module: light_barrier, position: [1, 0, 0.05]}}
          drive: {{module: fmu, file: {fmus / 'belt_drive-fmi2.fmu'}, map: {{run: go}}}}
        flows:
          - {{from: barrier.trigger.on_enter, to: drive.logic.go}}
          - {{from: barrier.trigger.on_enter, to: belt.drive.run}}
        """)
    assert problems(path) == [
        f"{path}:7: flows[0]: type mismatch: barrier.trigger.on_enter is void but drive.logic.go is bool "
        f"(an FMU's Boolean is an event when listed in its `events:`: add 'run' to objects.drive.events)",
        f"{path}:8: flows[1]: type mismatch: barrier.trigger.on_enter is void but belt.drive.run is bool "
        f"(an event carries no value: a `constant` object's value.set turns it into one)",
    ]
