"""A participant that dies, freezes or fails stops (or pauses) the run by the scenario's policy, with a
message naming it; every process the hub launched is gone afterwards. Never a hang.

    drive_a.logic ══ bus ══ planthub serve-fmu belt_drive-fmi2.fmu    (launched by the hub)
    drive_b.logic ══ bus ══ python -m modules.belt_drive_logic       (launched by the hub)
"""
import csv
import os
import signal

import pytest

from hub.bus.lockstep import pid_of
from hub.core.errors import SimulationError

from .bus_support import hub, resumed_at_exit
from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario

SCENARIO = ROOT / "scenarios" / "two_drives_distributed.yaml"
MID_RUN = 150   # tick 150 = 1 s: both belts are ramping; the next point is at 1.02 s


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


def slave(master, name):
    return next(c.slave for c in master.plant.components if c.obj == name)


def gone(pid) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    with open(f"/proc/{pid}/stat") as f:   # a zombie the hub has not reaped yet is gone as well
        return f.read().split(") ")[1].startswith("Z")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_killed_participant_stops_the_run_at_once_with_its_name(tmp_path):
    with hub(SCENARIO, tmp_path) as master:
        master.run(until_tick=MID_RUN)
        victim, other = pid_of(slave(master, "drive_b")), pid_of(slave(master, "drive_a"))
        os.kill(victim, signal.SIGKILL)
        with pytest.raises(SimulationError) as info:
            master.run()
        assert str(info.value) == ("participant 'drive_b' left the bus: its process was killed by SIGKILL "
                                   "(at t = 1.02 s); the run stops here, the recording so far is kept")
        assert gone(other)   # the FMU participant was told the run stopped, or stopped
    recorded = rows(tmp_path / "recording.csv")
    assert float(recorded[-1]["time"]) >= 1.0 and len(recorded) < 201


def test_a_killed_fmu_participant_is_named_with_its_fmu(tmp_path):
    with hub(SCENARIO, tmp_path) as master:
        master.run(until_tick=MID_RUN)
        os.kill(pid_of(slave(master, "drive_a")), signal.SIGKILL)
        with pytest.raises(SimulationError, match=r"^participant 'drive_a' \(FMU belt_drive-fmi2\.fmu\) left the "
                                                  r"bus: its process was killed by SIGKILL \(at t = 1\.02 s\)"):
            master.run()


def test_a_frozen_participant_is_lost_after_its_lease(tmp_path):
    with hub(SCENARIO, tmp_path, {"run.bus": {"lease": 0.3}}) as master:
        master.run(until_tick=MID_RUN)
        victim = pid_of(slave(master, "drive_b"))
        with resumed_at_exit(victim):
            os.kill(victim, signal.SIGSTOP)
            with pytest.raises(SimulationError) as info:
                master.run()
    # Whichever notices first, the missing answer or Zenoh's expired lease, the message says frozen.
    message = str(info.value)
    assert message.startswith("participant 'drive_b' ") and "frozen" in message
    assert message.endswith("; the run stops here, the recording so far is kept")


def test_with_the_pause_policy_a_killed_participant_is_relaunched_and_the_run_goes_on(tmp_path):
    with hub(SCENARIO, tmp_path, {"run.bus": {"on_loss": "pause"}}) as master:
        master.run(until_tick=MID_RUN)
        first = pid_of(slave(master, "drive_b"))
        os.kill(first, signal.SIGKILL)
        result = master.run()
        assert pid_of(slave(master, "drive_b")) is None   # closed: the relaunched one ended too
    assert result.ticks == 600 - MID_RUN
    notices = [(r["tick"], r["detail"]) for r in rows(tmp_path / "bus_log.csv")]
    assert notices == [
        ("153", "paused: participant 'drive_b' left the bus: its process was killed by SIGKILL (at t = 1.02 s); "
                "waiting up to 10 s for it to rejoin"),
        ("153", "resumed: participant 'drive_b' rejoined")]
    assert all(not r["slot"].startswith("@") for r in rows(tmp_path / "events.csv"))   # only the plant's
    assert len(rows(tmp_path / "recording.csv")) == 201


def test_a_participant_whose_step_raises_stops_the_run_with_its_error(write_scenario):
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.05}}
        objects:
          drive:
            module: participant
            inputs: {{run: bool, speed_setpoint: real}}
            outputs: {{speed: real, running: bool}}
            parameters: {{fail_at: 0.5}}
            command: [python, -m, tests.participants.belt_drives, fails]
            cwd: {ROOT}
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    first, *trace = str(info.value).splitlines()
    assert first == ("participant 'drive' failed in step 10: ZeroDivisionError: asked to fail at "
                     "t = 0.5 s (at t = 0.55 s); the run stops here, the recording so far is kept")
    assert trace[0] == "  its traceback:" and "belt_drives.py" in "\n".join(trace)   # where it failed
    assert trace[-1].strip() == 'raise ZeroDivisionError(f"asked to fail at t = {t:g} s")'



def test_an_output_of_the_wrong_type_is_named(write_scenario):
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.05}}
        objects:
          drive:
            module: participant
            inputs: {{run: bool, speed_setpoint: real}}
            outputs: {{speed: real, running: bool}}
            command: [python, -m, tests.participants.belt_drives, ints]
            cwd: {ROOT}
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path)
    assert str(info.value) == ("participant 'drive' sent a bad output message: output 'running' of step 0: "
                               "expected a bool, got 0 (at t = 0.05 s); the run stops here, the recording so far "
                               "is kept")


@pytest.mark.parametrize("how", ["freezes", "stalls"])
def test_with_the_pause_policy_a_participant_that_stops_for_a_while_carries_on_bit_for_bit(tmp_path, how):
    """A joined participant stops answering for a second, three times the run's lease: frozen
    (SIGSTOP; its connection expires and it says hello again when it thaws) or stalled in a step
    (its connection stays; it answers late). The run pauses and goes on, and as the participant
    kept its state the recording is the in-process one."""
    import threading

    from hub.bus.session import Bus
    from hub.bus.settings import BusSettings

    from .bus_support import BELT_FMU, BELT_PARTICIPANT, process, same_files

    scene = tmp_path / "joined.yaml"
    scene.write_text(BELT_PARTICIPANT.read_text().replace("    command: [python, -m, modules.belt_drive_logic]\n", ""))
    overrides = {"name": "line1"}
    command = ["-m", "tests.participants.belt_drives", "plain"]
    if how == "stalls":   # the step from t = 1.02 s takes a second
        overrides["objects.drive.parameters"] = {"ramp": 0.5, "stall_at": 1.02, "stall": 1.0}
        command[-1] = "stalls"
    with Bus(BusSettings(lease=0.3, on_loss="pause")) as bus, \
            hub(scene, tmp_path / "paused", overrides, bus=bus) as master:
        with process(*command, "--run", "line1", "--name", "drive", "--connect", bus.endpoints[0]) as proc, \
                resumed_at_exit(proc.pid):
            master.run(until_tick=MID_RUN)
            before = master.link.lockstep.peers["drive"].key   # agreed in its hello and the hub's welcome
            timer = None
            if how == "freezes":
                os.kill(proc.pid, signal.SIGSTOP)
                timer = threading.Timer(1.0, os.kill, (proc.pid, signal.SIGCONT))
                timer.start()
            try:
                master.run()
            finally:
                if timer is not None:
                    timer.join()
            after = master.link.lockstep.peers["drive"].key
    notices = [r["detail"] for r in rows(tmp_path / "paused" / "bus_log.csv")]
    assert [n.split(":")[0] for n in notices] == ["paused", "resumed"]
    if how == "stalls":
        assert notices[1] == "resumed: participant 'drive' answered late"
    # A rejoin after the loss is a new hello with a new key pair: a new seal key. A late answer keeps it.
    assert len(before) == 32 and (after != before) == notices[1].endswith("rejoined")
    # The replay (here with the logic in the hub: the same results, bit for bit) has no pause:
    # the pause is in bus_log.csv, and what the plant did is the same, event log included.
    with hub(BELT_FMU, tmp_path / "replayed", {"name": "line1"}, replay=tmp_path / "paused") as master:
        master.run()
    assert not (tmp_path / "replayed" / "bus_log.csv").exists()
    assert same_files(tmp_path / "paused", tmp_path / "replayed")
