"""External participants in lockstep: the same logic in-process, as an FMU served over the bus and
as a pure-Python participant gives the same recording, byte for byte; joining is checked and named."""
import pytest

from hub.bus.session import Bus, wait_until
from hub.bus.settings import BusSettings
from hub.core.errors import SimulationError
from hub.core.slots import SlotType

from .bus_support import BELT_FMU, BELT_PARTICIPANT, hub, output_of, process, same_files
from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario

BUILT = ROOT / "build" / "fmus"
FMU = BUILT / "belt_drive-fmi2.fmu"


@pytest.fixture(scope="module")
def fmus():
    return build(BUILT)


@pytest.fixture(scope="module")
def in_process(fmus, tmp_path_factory):
    """belt_ramp_fmu.yaml with the FMU in the hub: the reference recording."""
    out = tmp_path_factory.mktemp("in_process")
    run_scenario(BELT_FMU, out)
    return out


def test_an_fmu_served_over_the_bus_gives_the_in_process_recording(in_process, tmp_path):
    """
        drive.logic ══ bus ══ planthub serve-fmu belt_drive-fmi2.fmu   (a process the hub launches)
    """
    run_scenario(BELT_FMU, tmp_path, {"objects.drive.runs": "bus"})
    assert same_files(in_process, tmp_path)


def test_a_python_participant_gives_the_in_process_recording(in_process, tmp_path):
    """
        drive.logic ══ bus ══ python -m modules.belt_drive_logic      (hub.participant)
    """
    run_scenario(BELT_PARTICIPANT, tmp_path)
    assert same_files(in_process, tmp_path)
    speeds = {line.split(",")[1] for line in (tmp_path / "recording.csv").read_text().splitlines()[1:]}
    assert len(speeds) > 20   # the participant really stepped: the ramp passes many values


def test_an_fmu_joining_from_another_process_gives_the_same_recording(in_process, tmp_path):
    """The hub waits for `planthub serve-fmu … --connect ENDPOINT`, started by someone else."""
    with Bus(BusSettings()) as bus, hub(BELT_FMU, tmp_path, {"objects.drive.runs": "bus", "objects.drive.launch": False}, bus=bus) as master:
        with process("-m", "hub", "serve-fmu", FMU, "--run", "belt_ramp_fmu", "--name", "drive",
                     "--connect", bus.endpoints[0]) as proc:
            master.run()
            assert output_of(proc)[0] == 0   # it ended by itself when the run stopped
    assert same_files(in_process, tmp_path)


def two_drives(write_scenario, command_a, command_b, lease=1.0):
    """Two belts, each driven by its own participant process."""
    objects = "\n".join(f"""
          belt_{x}: {{module: conveyor, position: [0, {y}, 0], length: 2.5, speed: 0.0, k: 16}}
          drive_{x}:
            module: participant
            inputs: {{run: bool, speed_setpoint: real}}
            outputs: {{speed: real, running: bool}}
            parameters: {{ramp: {ramp}{extra}}}
            command: {command}
            cwd: {ROOT}""" for x, y, ramp, command, extra in (("a", 0, 0.5, command_a, ", odd: true"),
                                                                ("b", 1, 0.25, command_b, "")))
    return write_scenario(f"""
        planthub: 1
        name: two_drives
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.01, bus: {{lease: {lease}}}}}
        objects:{objects}
          go: {{module: constant, type: bool, value: true}}
          setpoint: {{module: constant, type: real, value: 0.5}}
        flows:
          - {{from: go.value.out, to: drive_a.logic.run, when: target, mode: singular}}
          - {{from: go.value.out, to: drive_b.logic.run, when: target, mode: singular}}
          - {{from: setpoint.value.out, to: drive_a.logic.speed_setpoint, when: target, mode: singular}}
          - {{from: setpoint.value.out, to: drive_b.logic.speed_setpoint, when: target, mode: singular}}
          - {{from: drive_a.logic.speed, to: belt_a.drive.speed}}
          - {{from: drive_b.logic.speed, to: belt_b.drive.speed}}
        record: [drive_a.logic.speed, drive_b.logic.speed]
        """)


PLAIN = "[python, -m, tests.participants.belt_drives, plain]"
SLOW = "[python, -m, tests.participants.belt_drives, slow]"


def test_arrival_order_does_not_matter(write_scenario, tmp_path):
    """
        drive_a (slow on odd steps) ══ bus ══╗
                                             hub: waits for both, files each answer under its sender
        drive_b (slow on even steps) ═ bus ══╝
    """
    run_scenario(two_drives(write_scenario, PLAIN, PLAIN), tmp_path / "plain")
    run_scenario(two_drives(write_scenario, SLOW, SLOW), tmp_path / "slow")
    assert same_files(tmp_path / "plain", tmp_path / "slow")
    last = (tmp_path / "slow" / "recording.csv").read_text().splitlines()[-1].split(",")
    # After 1 s, the ramp of 0.5 m/s² reached 0.5 m/s, the ramp of 0.25 m/s² half of it.
    assert float(last[1]) == 0.5 and float(last[2]) == pytest.approx(0.25)


def test_a_participant_that_never_joins_is_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        name: lonely
        run: {duration: 0.1, bus: {}}
        objects:
          drive: {module: participant, outputs: {speed: real}, join_timeout: 0.3}
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    message = str(info.value)
    assert message.startswith("participant 'drive' did not join within 0.3 s: start it with the run name "
                              "'lonely' and the hub's endpoint (tcp/127.0.0.1:")


def test_a_command_that_fails_before_joining_shows_its_output(write_scenario):
    path = write_scenario("""
        planthub: 1
        run: {duration: 0.1}
        objects:
          drive:
            module: participant
            outputs: {speed: real}
            command: [python, -c, "import sys; print('no licence for this PLC'); sys.exit(3)"]
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    assert str(info.value) == ("participant 'drive': its process exited with code 3 before it could join\n"
                               "  its output ends with:\n    no licence for this PLC")


def test_a_missing_program_is_named(write_scenario):
    path = write_scenario("""
        planthub: 1
        objects:
          drive: {module: participant, outputs: {speed: real}, command: [no-such-plc-program, --fast]}
        """)
    with pytest.raises(SimulationError, match=r"^participant 'drive': cannot start 'no-such-plc-program --fast': "
                                              r"No such file or directory$"):
        run_scenario(path)


def test_a_participant_that_does_not_fit_the_scenario_is_refused_with_every_difference(write_scenario):
    path = write_scenario(f"""
        planthub: 1
        objects:
          drive:
            module: participant
            inputs: {{run: bool, speed_setpoint: int}}
            outputs: {{speed: real, runing: bool}}
            command: [python, -m, modules.belt_drive_logic]
            cwd: {ROOT}
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    assert str(info.value) == (
        "participant 'drive' does not fit the scenario: its input 'speed_setpoint' is real, the scenario's is "
        "int; it lacks output 'runing' (bool); its output 'running' (bool) is not in the scenario "
        "(did you mean 'runing'?)")


def test_a_participant_under_an_unknown_name_is_refused(write_scenario):
    path = write_scenario("""
        planthub: 1
        name: line
        run: {duration: 0.1}
        objects:
          drive: {module: participant, inputs: {run: bool, speed_setpoint: real},
                  outputs: {speed: real, running: bool}, join_timeout: 1}
        """)
    with Bus(BusSettings()) as bus, hub(path, bus=bus) as master:
        with process("-m", "modules.belt_drive_logic", "--run", "line", "--name", "driev",
                     "--connect", bus.endpoints[0], "--join-timeout", "5") as proc:
            with pytest.raises(SimulationError, match=r"^participant 'drive' did not join within 1 s"):
                master.run()
            code, _, err = output_of(proc)
    assert code == 1
    assert err == ("planthub participant 'driev': the hub refused me: run 'line' has no participant 'driev' "
                   "(did you mean 'drive'?)\n")


def test_a_participant_written_from_the_wire_document_alone_fits(in_process, tmp_path):
    """tests/participants/from_the_doc.py: literal keys and msgpack, its own order of inputs and outputs."""
    run_scenario(BELT_PARTICIPANT, tmp_path,
                 {"objects.drive.command": ["python", "-m", "tests.participants.from_the_doc"],
                  "objects.drive.cwd": str(ROOT)})
    assert same_files(in_process, tmp_path)


@pytest.mark.parametrize("how", ["launched", "joined"])
def test_every_control_message_of_a_run_follows_the_wire_schema(tmp_path, how):
    """A tap on plant/<run>/@cosim/** sees hello, welcome, steps, outputs and states (the hub runs as a
    Zenoh router and the others as its clients, so it forwards what participants send); each is checked
    against schemas/wire.schema.json. The participant is launched (its messages sealed with its token)
    or joins by itself (sealed with the key agreed in its hello and welcome, which carry `key`)."""
    import contextlib
    import json

    import jsonschema

    from hub.bus import wire
    from hub.bus.session import Inbox

    schema = json.loads((ROOT / "schemas" / "wire.schema.json").read_text())
    scene = json.loads((ROOT / "schemas" / "scene.schema.json").read_text())   # what views read
    path = BELT_PARTICIPANT
    if how == "joined":
        path = tmp_path / "belt_ramp_participant.yaml"
        path.write_text(BELT_PARTICIPANT.read_text().replace("    command: [python, -m, modules.belt_drive_logic]\n", ""))
    seen = Inbox()
    with Bus(BusSettings(mode="router")) as bus, \
            hub(path, tmp_path / "out", {"run.duration": 0.2, "objects.drive.join_timeout": 20}, bus=bus) as master:
        with Bus(BusSettings(mode="client", connect=bus.endpoints)) as tap:
            tap.subscribe("plant/belt_ramp_participant/@cosim/**", seen.put)
            assert wait_until(lambda: bus.publisher("plant/belt_ramp_participant/@cosim/probe", "x").matching, 5)
            with (process("-m", "modules.belt_drive_logic", "--run", "belt_ramp_participant", "--name", "drive",
                          "--mode", "client", "--connect", bus.endpoints[0]) if how == "joined"
                  else contextlib.nullcontext()) as proc:
                master.run()
                if proc is not None:
                    assert output_of(proc)[0] == 0
            key = master.link.lockstep.peers["drive"].key
            messages = []
            while (message := seen.get(1.0)) is not None:
                messages.append(message)
    assert len(key) == 32
    kinds = {}
    for message in messages:
        kind = message.key.rsplit("/", 1)[-1]
        if kind == "probe":
            continue
        assert message.encoding == "application/msgpack", message.key
        definition = {"result": "command_result"}.get(kind, kind)
        payload = message.payload
        if kind in ("step", "output"):   # sealed (schemas/wire.md): with the token's key or the agreed one
            payload = wire.unseal(key, payload)
        if kind in ("bodies", "events", "figures"):   # the view's messages (schemas/scene.schema.json)
            jsonschema.Draft202012Validator({**scene, "$ref": f"#/$defs/{kind}_message"}).validate(wire.unpack(payload))
        else:
            jsonschema.Draft202012Validator({**schema, "$ref": f"#/$defs/{definition}"}).validate(wire.unpack(payload))
        if kind in ("hello", "welcome"):   # JSON Schema has no type for bytes: `key` is 32 of them, or absent
            body = wire.unpack(payload)
            assert ("key" in body) == (how == "joined") and ("token" in body) == (kind == "hello" and how == "launched")
            assert "key" not in body or type(body["key"]) is bytes and len(body["key"]) == 32
        kinds[kind] = kinds.get(kind, 0) + 1
    assert kinds["step"] == kinds["output"] - 1 == 10   # 0.2 s of 20 ms steps; the initial outputs
    assert {"hello", "welcome", "state", "bodies", "figures"} <= set(kinds)


def test_a_served_fmu_announces_the_fmu_module_slots_with_events_and_renames(fmus):
    from hub.logic.served import FmuParticipant
    from modules.fmu import Fmu

    params = Fmu.with_defaults({"file": str(FMU), "events": ["run"], "map": {"speed": "belt_speed"},
                                "runs": "bus"})
    inputs, outputs = FmuParticipant(str(FMU), ["run"], {"speed": "belt_speed"}).interface()
    assert [(s.name, s.type) for s in Fmu.slots(params)["logic"]] == inputs + outputs
    assert ("run", SlotType.VOID) in inputs and ("belt_speed", SlotType.REAL) in outputs
    assert Fmu.serve_command(params)[3:] == ["serve-fmu", str(FMU), "--event", "run", "--map", "speed=belt_speed"]


def test_the_keys_runs_replaced_name_the_value_to_write(fmus, write_scenario):
    from hub.core.errors import ScenarioError
    from hub.scenario.checker import load_scenario

    path = write_scenario(f"""
        planthub: 1
        objects:
          a: {{module: fmu, file: {FMU}, isolate: true}}
          b: {{module: fmu, file: {FMU}, isolate: false}}
          c: {{module: fmu, file: {FMU}, participant: launch}}
          d: {{module: fmu, file: {FMU}, participant: join}}
          e: {{module: fmu, file: {FMU}, runs: child, launch: false}}
          f: {{module: conveyor, position: [0, 0, 0], length: 1, logic: {{isolate: true}}}}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:3: objects.a.isolate: isolate is gone: write `runs: child` instead",
        f"{path}:4: objects.b.isolate: isolate is gone: write `runs: hub` instead",
        f"{path}:5: objects.c.participant: participant is gone: write `runs: bus` instead",
        f"{path}:6: objects.d.participant: participant is gone: write `runs: bus` with `launch: false` instead",
        f"{path}:7: objects.e.launch: launch goes with runs: bus (a process serving the FMU over the bus); "
        f"with runs: child the hub launches nothing",
        f"{path}:8: objects.f.logic.isolate: isolate is gone: write `runs: child` instead"]


@pytest.mark.parametrize("settings", [{"objects.drive.step": 0.1}, {"run.event_driven": True}],
                         ids=["own longer step", "event-driven points"])
def test_a_participant_matches_the_fmu_with_its_own_step_and_with_event_driven_points(fmus, settings, tmp_path):
    run_scenario(BELT_FMU, tmp_path / "fmu", settings)
    run_scenario(BELT_PARTICIPANT, tmp_path / "participant", settings)
    assert same_files(tmp_path / "fmu", tmp_path / "participant")
