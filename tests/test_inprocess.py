"""A Python participant in the hub's process (`python: [...]`, `runs: hub`): the same run,
bit for bit, as the same logic launched as a process on the bus; its faults named as over the bus."""
import pytest

from hub.core.errors import PlanthubError, SimulationError

from .helpers import ROOT, run_scenario

SCENARIO = ROOT / "scenarios" / "belt_ramp_participant.yaml"
LAUNCHED = "command: [python, -m, modules.belt_drive_logic]"


def variant(tmp_path, how: str, name: str):
    text = SCENARIO.read_text()
    assert LAUNCHED in text
    path = tmp_path / f"{name}.yaml"
    path.write_text(text.replace(LAUNCHED, how))
    return path


def test_in_process_gives_the_recording_of_the_launched_participant(tmp_path):
    # tests.participants.belt_drives `plain` is modules.belt_drive_logic's BeltDrive, with participant(argv)
    python = f"python: [tests.participants.belt_drives, plain]\n    cwd: {ROOT}"
    runs = {"command": LAUNCHED, "python": python, "in_process": python + "\n    runs: hub"}
    recordings = {}
    for name, how in runs.items():
        out = tmp_path / name
        run_scenario(variant(tmp_path, how, name), out)
        recordings[name] = (out / "recording.csv").read_bytes()
    assert recordings["in_process"] == recordings["command"] == recordings["python"]
    speeds = [line.split(",")[1] for line in recordings["in_process"].decode().splitlines()[1:]]
    assert "0.5" in speeds and speeds[-1] == "0.0"   # it ramped up, and the barrier stopped it


def scene(write_scenario, participant: str, extra: str = ""):
    return write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.05}}
        objects:
          drive:
            module: participant
            inputs: {{run: bool, speed_setpoint: real}}
            outputs: {{speed: real, running: bool}}
            parameters: {{fail_at: 0.5}}
            python: {participant}
            runs: hub
            cwd: {ROOT}
{extra}
        """)


def test_an_exception_in_its_step_stops_the_run_naming_it(write_scenario):
    with pytest.raises(SimulationError) as info:
        run_scenario(scene(write_scenario, "[tests.participants.belt_drives, fails]"))
    assert str(info.value).startswith(
        "participant 'drive' (in-process) failed in its step at t = 0.5 s: ZeroDivisionError: asked to fail at "
        "t = 0.5 s")


def test_an_output_of_the_wrong_type_is_named(write_scenario):
    with pytest.raises(SimulationError) as info:
        run_scenario(scene(write_scenario, "[tests.participants.belt_drives, ints]"))
    assert str(info.value).startswith(
        "participant 'drive' (in-process) gave a bad output in its step at t = 0 s: output 'running': "
        "expected a bool, got 0")


def test_a_module_that_does_not_import_is_named(write_scenario):
    with pytest.raises(SimulationError) as info:
        run_scenario(scene(write_scenario, "[tests.participants.no_such_thing]"))
    assert str(info.value) == ("participant 'drive' (in-process): cannot import Python module "
                               "'tests.participants.no_such_thing': No module named 'tests.participants.no_such_thing'")


def test_a_module_without_a_participant_function_is_named(write_scenario):
    with pytest.raises(SimulationError) as info:
        run_scenario(scene(write_scenario, "[tests.participants.echo]"))
    assert str(info.value) == ("participant 'drive' (in-process): module 'tests.participants.echo' has no "
                               "function participant(argv) that makes its logic")


def test_logic_that_does_not_fit_the_scenario_is_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 1.0, physics_rate: 100}
        objects:
          control:
            module: participant
            inputs: {r1_read: void, r1_destination: int}
            outputs: {sw1_work: void}
            python: [modules.plant_control, --lanes, A]
            runs: hub
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    assert str(info.value) == (
        "participant 'control' (in-process) does not fit the scenario: its input 'r1_destination' is string, "
        "the scenario's is int; its output 'sw1_base' (void) is not in the scenario (known: sw1_work)")


def test_python_and_command_together_are_refused(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 1.0, physics_rate: 100}
        objects:
          drive:
            module: participant
            inputs: {run: bool}
            python: [modules.belt_drive_logic]
            command: [python, -m, modules.belt_drive_logic]
        """)
    with pytest.raises(PlanthubError) as info:
        run_scenario(path)
    assert f"{path}:7: objects.drive.python: give `command` (any program) or `python` (a Python module), not both" \
        in str(info.value)


def test_runs_hub_without_a_python_module_is_refused(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 1.0, physics_rate: 100}
        objects:
          drive:
            module: participant
            inputs: {run: bool}
            runs: hub
        """)
    with pytest.raises(PlanthubError) as info:
        run_scenario(path)
    assert "objects.drive.runs: only a Python participant (`python: [MODULE, ...]`) runs in the hub" \
        in str(info.value)


def test_in_process_is_gone_and_says_what_to_write(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          a: {module: participant, python: [modules.belt_drive_logic], in_process: true}
          b: {module: participant, python: [modules.belt_drive_logic], in_process: false}
          c: {module: participant, python: [modules.belt_drive_logic], runs: child}
        """)
    with pytest.raises(PlanthubError) as info:
        run_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:3: objects.a.in_process: in_process is gone: write `runs: hub` instead",
        f"{path}:4: objects.b.in_process: in_process is gone: write `runs: bus` instead",
        f"{path}:5: objects.c.runs: a participant runs on the bus, or with `python` in the hub (runs: hub); "
        f"a child process over a pipe is for an FMU"]


def test_arguments_the_module_rejects_are_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 1.0, physics_rate: 100}
        objects:
          control:
            module: participant
            inputs: {r1_read: void, r1_destination: string}
            outputs: {sw1_work: void, sw1_base: void}
            python: [modules.plant_control]
            runs: hub
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    assert str(info.value) == ("participant 'control' (in-process): modules.plant_control.participant([]) "
                               "rejected its arguments (exit status 2)")
