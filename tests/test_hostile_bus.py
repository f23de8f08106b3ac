"""Broken or hostile messages on the bus never crash the hub and never take a participant's place:
every decoder raises only WireError, a stranger's hello is refused with a reason while the run goes
on, and a launched participant's name is only the launched process's. The stranger here is a plain
Zenoh session in the test process, writing what schemas/wire.md describes."""
from __future__ import annotations

import subprocess
import sys
import threading
import time

import msgpack
import pytest

from hub.bus import wire
from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings
from hub.core.slots import SlotType

from .bus_support import BELT_PARTICIPANT, hub
from .helpers import ROOT

RUN = "belt_ramp_participant"
FITTING = {"protocol": 1, "id": "stranger", "inputs": [["run", "bool"], ["speed_setpoint", "real"]],
           "outputs": [["speed", "real"], ["running", "bool"]]}


@pytest.mark.parametrize("kind, data", [
    (SlotType.REAL, b"\x00" * 7), (SlotType.VEC3, b"\x00" * 25), (SlotType.INT, b""), (SlotType.BOOL, b"\x00\x00"),
    (SlotType.STRING, b"\xff\xfe"), (SlotType.REAL, b"\x00" * (wire.MAX_MESSAGE + 1))])
def test_a_bad_sample_gives_a_wire_error(kind, data):
    with pytest.raises(wire.WireError):
        wire.unpack_value(kind, data)


@pytest.mark.parametrize("data", [b"\xc1", b"\x92\x01", b"\x00" * (wire.MAX_MESSAGE + 1), b"\xdd\xff\xff\xff\xff"])
def test_a_bad_control_message_gives_a_wire_error(data):
    with pytest.raises(wire.WireError):
        wire.unpack(data)


@pytest.mark.parametrize("step", [[0, 0, 1, 0.0, 0.01, "no list"], ["n", 0, 1, 0.0, 0.01, []], [0, 0, 1, "t", 0.01, []], 7])
def test_a_bad_step_message_gives_a_wire_error(step):
    with pytest.raises(wire.WireError):
        wire.read_step(msgpack.packb(step))


@pytest.mark.parametrize("entries", [[["a", ["real"]]], [["a", {"real": 1}]], [[1, "real"]], "real", [["a", "float"]]])
def test_a_hello_interface_of_any_shape_gives_a_wire_error(entries):
    with pytest.raises(wire.WireError):
        wire.read_interface(entries, "inputs")


class Stranger:
    """Another process on the bus: once the hub is there, says each hello — again every 0.5 s, as a
    participant does, until it has an answer — and collects the answers."""

    def __init__(self, bus: Bus, hellos: list[tuple[str, object]]):
        self.bus, self.hellos = bus, hellos
        self.answers = Inbox()
        self.refused: dict[str, str] = {}
        for name in {n for n, _ in hellos}:
            bus.subscribe(wire.logic_key(RUN, name, "welcome"),
                          lambda m, name=name: self.answers.put((name, wire.unpack(m.payload))))
        self.hub = Inbox()
        bus.watch_tokens(wire.hub_token(RUN), lambda m: self.hub.put(m.alive))
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._say, daemon=True)
        self.thread.start()

    def _say(self):
        if self.hub.get(20) is not True:
            return
        deadline = time.monotonic() + 20
        while len(self.refused) < len(self.hellos) and time.monotonic() < deadline:
            for name, hello in self.hellos:
                if name not in self.refused:
                    self.bus.put(wire.logic_key(RUN, name, "hello"), msgpack.packb(hello), wire.MSGPACK)
            until = time.monotonic() + 0.5
            while (item := self.answers.get(until - time.monotonic())) is not None:
                name, answer = item
                if answer.get("id") == "stranger" and not answer.get("accepted"):
                    self.refused.setdefault(name, answer["error"])
        self.done.set()

    def refusals(self, timeout=25.0) -> list[str]:
        self.done.wait(timeout)
        return list(self.refused.values())


def test_a_hello_that_no_decoder_takes_is_refused_and_the_run_goes_on(tmp_path):
    """The unhashable hello that killed the hub, a hello for no object, and a fitting hello for the
    launched participant that lacks its token: each refused, the run ends normally."""
    bad = {"protocol": 1, "id": "stranger", "inputs": [["a", ["real"]]], "outputs": []}
    with Bus(BusSettings()) as bus, Bus(BusSettings(connect=tuple(bus.endpoints)), listen=False) as other:
        stranger = Stranger(other, [("ghost", bad), ("drive", FITTING)])
        with hub(BELT_PARTICIPANT, tmp_path, {"run.duration": 1.0}, bus=bus) as run:
            result = run.run()
        assert result.ticks == 150
        refusals = stranger.refusals()
    assert "bad hello: inputs: expected [name, type] with type one of void, bool, int, real, vec3, quat, string, " \
           "got ['a', ['real']]" in refusals
    assert any("this hello does not carry the token its process was given" in r
               or "is already on the bus" in r for r in refusals), refusals


def test_a_misfit_hello_while_the_hub_waits_for_a_joiner_does_not_abort_the_join(tmp_path):
    """A stranger's wrong hello is refused; the real participant, joining after it, runs the scene."""
    misfit = {**FITTING, "outputs": [["speed", "int"], ["running", "bool"]]}
    scene = tmp_path / "joined.yaml"
    scene.write_text(BELT_PARTICIPANT.read_text().replace("    command: [python, -m, modules.belt_drive_logic]\n", ""))
    overrides = {"name": RUN, "run.duration": 1.0, "objects.drive.join_timeout": 20}
    with Bus(BusSettings()) as bus, Bus(BusSettings(connect=tuple(bus.endpoints)), listen=False) as other:
        stranger = Stranger(other, [("drive", misfit)])
        with hub(scene, tmp_path / "out", overrides, bus=bus) as run:
            # The real participant starts only once the stranger was refused: the order is the test's.
            joiner = threading.Thread(target=lambda: stranger.done.wait(25) and joined.append(subprocess.Popen(
                [sys.executable, "-m", "modules.belt_drive_logic", "--run", RUN, "--name", "drive",
                 "--connect", bus.endpoints[0]], cwd=ROOT)))
            joined = []
            joiner.start()
            try:
                result = run.run()
            finally:
                joiner.join(30)
                for proc in joined:
                    try:
                        assert proc.wait(20) == 0   # it ended by itself when the run stopped
                    finally:
                        if proc.poll() is None:
                            proc.kill()
                            proc.wait()
        assert result.ticks == 150
        (refusal,) = stranger.refusals()
    assert refusal.startswith("participant 'drive' does not fit the scenario: its output 'speed' is int")


def test_outputs_from_another_process_are_dropped_not_taken(tmp_path):
    """A stranger answers every step of the launched participant with its own outputs, tagged with
    the step the hub waits for: none is taken (they are not sealed with the participant's key),
    so the recording is the participant's own, and the drops are counted and named."""
    reference = tmp_path / "alone"
    with hub(BELT_PARTICIPANT, reference, {"run.duration": 1.0}) as run:
        run.run()
    with Bus(BusSettings()) as bus, Bus(BusSettings(connect=tuple(bus.endpoints)), listen=False) as other:
        steps = Inbox()
        other.subscribe(wire.logic_key(RUN, "drive", "step"), lambda m: steps.put(m.payload))
        stop = threading.Event()

        def answer():
            while not stop.is_set():
                payload = steps.get(0.1)
                if payload is not None:   # the step's number sits after the hub's seal
                    n = msgpack.unpackb(payload[wire.SEAL:])[0]
                    other.put(wire.logic_key(RUN, "drive", "output"), msgpack.packb([n, [99.0, True]]), wire.MSGPACK)

        thread = threading.Thread(target=answer, daemon=True)
        thread.start()
        warnings = []
        try:
            with hub(BELT_PARTICIPANT, tmp_path / "attacked", {"run.duration": 1.0}, bus=bus) as run:
                run.start()
                run.link.lockstep.warn = warnings.append
                run.run()
                dropped = dict(run.link.lockstep.dropped)
        finally:
            stop.set()
            thread.join(5)
    assert (tmp_path / "attacked" / "recording.csv").read_bytes() == (reference / "recording.csv").read_bytes()
    assert dropped.get(("drive", "foreign"), 0) > 10
    assert any("dropped a foreign message for participant 'drive'" in w for w in warnings)


def test_a_refused_command_is_cheap_and_never_echoes_unbounded_input():
    from hub.bus.commands import CommandError, Commands
    from hub.run.plant import Plant
    from hub.scenario.checker import load_scenario

    with Plant(load_scenario(ROOT / "scenarios" / "bottling_plant.yaml")) as plant:
        commands = Commands(plant, recorder=None)
        with pytest.raises(CommandError) as huge:
            commands.parse({"op": "set", "slot": "x" * 10_000_000, "value": 1})
        with pytest.raises(CommandError) as typo:
            commands.parse({"op": "set", "slot": "sw1.blade.to_wrking", "value": None})
        with pytest.raises(CommandError) as unknown:
            commands.parse({"op": "set", "slot": "sw9.blade.to_working"})
    assert len(str(huge.value)) < 200 and "(10000002 characters)" in str(huge.value)
    assert str(typo.value) == "no slot 'sw1.blade.to_wrking' (did you mean 'sw1.blade.to_working'?)"
    assert str(unknown.value).startswith("no slot 'sw9.blade.to_working' (did you mean 'sw")
