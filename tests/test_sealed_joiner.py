"""A participant that joins by itself is sealed like a launched one (schemas/wire.md, item 7): its
hello and the hub's welcome carry ephemeral X25519 public keys, both sides derive the seal key, and
from then on a process that reads the bus can neither answer a step in its place nor step it. A
joiner without `key` still joins, unsealed, with a warning; a malformed key is refused with the reason.

    drive.logic ══ bus ══ python -m modules.belt_drive_logic --run … --connect …   (hub.participant)
    drive.logic ══ bus ══ python -m tests.participants.joiner_from_the_doc …        (wire.md alone)
"""
from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

import msgpack
import pytest

from hub.bus import wire
from hub.bus.lockstep import Lockstep, RemoteSpec
from hub.bus.session import Bus, Inbox, Message
from hub.bus.settings import BusSettings
from hub.core.slots import SlotType

from .bus_support import BELT_PARTICIPANT, hub, output_of, process
from .helpers import ROOT, run_scenario

RUN = "line1"
LAUNCHED = "    command: [python, -m, modules.belt_drive_logic]\n"
LIBRARY = ["-m", "modules.belt_drive_logic"]
FROM_THE_DOC = ["-m", "tests.participants.joiner_from_the_doc"]
UNSEALED = ("participant 'drive' joined without a key (its hello has no `key`): its steps and outputs are not "
            "sealed, so any process on the bus can answer in its place (schemas/wire.md, \"Sealed messages\")")


def variant(tmp_path, how: str, name: str):
    """belt_ramp_participant.yaml with the drive served another way ('' : it joins by itself)."""
    text = BELT_PARTICIPANT.read_text()
    assert LAUNCHED in text
    path = tmp_path / f"{name}.yaml"
    path.write_text(text.replace(LAUNCHED, how))
    return path


OVERRIDES = {"name": RUN, "run.duration": 1.0, "objects.drive.join_timeout": 20}


@pytest.fixture(scope="module")
def in_process(tmp_path_factory):
    """The same run with the drive's logic in the hub (tests.participants.belt_drives `plain` is
    modules.belt_drive_logic's BeltDrive): the reference recording."""
    folder = tmp_path_factory.mktemp("sealed")
    how = f"    python: [tests.participants.belt_drives, plain]\n    cwd: {ROOT}\n    runs: hub\n"
    run_scenario(variant(folder, how, "in_process"), folder / "out", OVERRIDES)
    return (folder / "out" / "recording.csv").read_bytes()


def joined_run(tmp_path, command: list, *, disturb=None, out: str = "joined", router: bool = False):
    """Run the joined scenario with `command` as the joiner (started by hand, as a user would);
    `disturb(bus)`, if given, starts a stranger on a second session and returns its stop function.
    With `router` the hub is a Zenoh router and the others its clients, so what the stranger puts
    reaches the joiner too (a peer hub forwards nothing between its peers). Returns (recording, the
    drive's peer, dropped counts, warnings, the joiner's exit code and stderr)."""
    scene = variant(tmp_path, "", out)
    warnings = []
    mode = "client" if router else "peer"
    with Bus(BusSettings(mode="router" if router else "peer")) as bus, \
            Bus(BusSettings(mode=mode, connect=tuple(bus.endpoints)), listen=False) as other:
        stop = disturb(other) if disturb else (lambda: None)
        try:
            with hub(scene, tmp_path / out, OVERRIDES, bus=bus, log=warnings.append) as master, \
                    process(*command, "--run", RUN, "--name", "drive", "--connect", bus.endpoints[0],
                            *(["--mode", "client"] if router else [])) as proc:
                master.run()
                lockstep = master.link.lockstep
                code, _, err = output_of(proc)
        finally:
            stop()
    return ((tmp_path / out / "recording.csv").read_bytes(), lockstep.peers["drive"], dict(lockstep.dropped),
            warnings, code, err)


@pytest.mark.parametrize("command", [LIBRARY, FROM_THE_DOC], ids=["hub.participant", "from_the_doc"])
def test_a_joiner_is_sealed_and_gives_the_in_process_recording(in_process, tmp_path, command):
    recording, peer, dropped, warnings, code, err = joined_run(tmp_path, command)
    assert code == 0, err   # it ended by itself when the run stopped
    assert recording == in_process
    assert len(peer.key) == 32 and len(peer.hub_key) == 32   # a seal key agreed over the bus
    assert not dropped and not any("without a key" in w for w in warnings)


def test_a_joiner_without_key_is_welcomed_unsealed_with_a_warning(in_process, tmp_path):
    """A participant from before sealed joiners: it joins, the run is the same, and the hub says once
    that anyone on the bus can answer in its place."""
    recording, peer, dropped, warnings, code, err = joined_run(tmp_path, FROM_THE_DOC + ["--no-key"])
    assert code == 0, err
    assert recording == in_process
    assert peer.key is None and peer.hub_key is None
    assert [w for w in warnings if "without a key" in w] == [UNSEALED]


def steps_of(bus: Bus) -> Inbox:
    steps = Inbox()
    bus.subscribe(wire.logic_key(RUN, "drive", "step"), lambda m: steps.put(m.payload))
    return steps


def stranger(bus: Bus, act, forged=frozenset()) -> callable:
    """A plain Zenoh session written from wire.md: `act(n, step body)` for every step the hub sends
    the drive (the step's number and body sit after the hub's 16-byte seal), but the steps it
    `forged` itself. Returns its stop."""
    steps, stop = steps_of(bus), threading.Event()

    def loop():
        while not stop.is_set():
            payload = steps.get(0.1)
            if payload is not None and payload not in forged:   # not one of its own, coming back
                body = msgpack.unpackb(payload[wire.SEAL:])
                act(body[0], body)

    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    return lambda: (stop.set(), thread.join(5))


def test_outputs_from_another_process_are_dropped_for_a_joiner(in_process, tmp_path):
    """tests/test_hostile_bus.py's stranger, against a participant that joined by itself: it answers
    every step with its own outputs, tagged with the step the hub waits for; none is taken."""
    def disturb(other):
        output = wire.logic_key(RUN, "drive", "output")
        return stranger(other, lambda n, body: other.put(output, msgpack.packb([n, [99.0, True]]), wire.MSGPACK))

    recording, peer, dropped, warnings, code, err = joined_run(tmp_path, LIBRARY, disturb=disturb)
    assert code == 0, err
    assert recording == in_process
    assert dropped.get(("drive", "foreign"), 0) > 10
    assert any("dropped a foreign message for participant 'drive'" in w for w in warnings)


def test_a_step_whose_seal_does_not_open_is_dropped_by_the_joiner(in_process, tmp_path):
    """A stranger steps the joiner ahead with wild inputs — once unsealed, once behind 16 bytes of
    its own — before the hub does: were either taken, the joiner would answer the hub's step with
    those outputs. It drops them, says so once, and the run is the undisturbed one."""
    def disturb(other):
        step = wire.logic_key(RUN, "drive", "step")

        forged = set()

        def forge(n, body):
            _, tick, ticks, t, h, _ = body
            fake = msgpack.packb([n + 1, tick + ticks, ticks, t + h, h, [True, 9.0]])
            for payload in (fake, os.urandom(wire.SEAL) + fake):
                forged.add(payload)
                other.put(step, payload, wire.MSGPACK)
        return stranger(other, forge, forged)

    recording, peer, dropped, warnings, code, err = joined_run(tmp_path, LIBRARY, disturb=disturb, router=True)
    assert code == 0, err
    assert recording == in_process
    assert err.count("planthub participant 'drive': dropped a step message not sealed by the hub\n") == 1, err


def test_a_hello_with_a_malformed_key_is_refused_with_the_reason(in_process, tmp_path):
    """Keys of the wrong length, of the wrong kind and one that gives no shared secret: each refused
    with a welcome that says why, while the hub goes on waiting for the real joiner."""
    fitting = {"protocol": 1, "name": "drive", "inputs": [["run", "bool"], ["speed_setpoint", "real"]],
               "outputs": [["speed", "real"], ["running", "bool"]]}
    bad = {"short": b"\x01" * 31, "text": "k" * 32, "list": list(range(32)), "zero": bytes(32)}
    refused: dict[str, str] = {}
    done = threading.Event()

    def disturb(other):
        answers, hub_seen = Inbox(), Inbox()
        other.subscribe(wire.logic_key(RUN, "drive", "welcome"), lambda m: answers.put(wire.unpack(m.payload)))
        other.watch_tokens(wire.hub_token(RUN), lambda m: hub_seen.put(m.alive))

        def say():
            if hub_seen.get(20) is not True:
                return
            deadline = time.monotonic() + 20
            while len(refused) < len(bad) and time.monotonic() < deadline:
                for ident, key in bad.items():
                    if ident not in refused:
                        other.put(wire.logic_key(RUN, "drive", "hello"),
                                  msgpack.packb({**fitting, "id": ident, "key": key}, use_bin_type=True), wire.MSGPACK)
                until = time.monotonic() + 0.5
                while (answer := answers.get(until - time.monotonic())) is not None:
                    if answer.get("id") in bad and not answer["accepted"]:
                        refused.setdefault(answer["id"], answer["error"])
            done.set()

        thread = threading.Thread(target=say, daemon=True)
        thread.start()
        return lambda: thread.join(5)

    # The real joiner starts once every bad hello was refused: the order is the test's.
    scene = variant(tmp_path, "", "malformed")
    joined = []
    with Bus(BusSettings()) as bus, Bus(BusSettings(connect=tuple(bus.endpoints)), listen=False) as other:
        stop = disturb(other)
        with hub(scene, tmp_path / "malformed", OVERRIDES, bus=bus) as master:
            joiner = threading.Thread(target=lambda: done.wait(25) and joined.append(subprocess.Popen(
                [sys.executable, *LIBRARY, "--run", RUN, "--name", "drive", "--connect", bus.endpoints[0]],
                cwd=ROOT, stderr=subprocess.PIPE, text=True)))
            joiner.start()
            try:
                master.run()
            finally:
                joiner.join(30)
                stop()
                for proc in joined:
                    try:
                        _, err = proc.communicate(timeout=20)   # it ends by itself when the run stopped
                        assert proc.returncode == 0, err
                    finally:
                        if proc.poll() is None:
                            proc.kill()
                            proc.wait()
    assert joined
    assert (tmp_path / "malformed" / "recording.csv").read_bytes() == in_process
    why = "bad hello: `key` must be an X25519 public key: 32 raw bytes (msgpack bin), got "
    assert refused == {"short": why + "31 bytes", "text": why + "a string", "list": why + "an array",
                       "zero": "bad hello: `key` is not a usable X25519 public key (it gives no shared secret)"}


# --- the hub's side of a hello, without a bus ------------------------------------------------------
class _Wire:
    """What Lockstep needs of a bus to answer hellos: its settings, and puts (kept)."""

    def __init__(self, settings: BusSettings):
        self.settings = settings
        self.sent: list[tuple[str, dict]] = []

    def put(self, key, payload, encoding):
        self.sent.append((key, wire.unpack(payload)))


def hub_of(settings: BusSettings | None = None):
    settings = BusSettings() if settings is None else settings
    spec = RemoteSpec("drive", (("run", SlotType.BOOL),), (("speed", SlotType.REAL),))
    warnings = []
    lockstep = Lockstep(_Wire(settings), RUN, [SimpleNamespace(spec=spec, sent=0, peer=None)], lease=1.0,
                        on_loss="stop", rate=100, warn=warnings.append)
    return lockstep, warnings


def say_hello(lockstep, ident: str, **extra) -> dict:
    hello = {"protocol": 1, "name": "drive", "id": ident, "inputs": [["run", "bool"]],
             "outputs": [["speed", "real"]], **extra}
    lockstep._hello(Message(wire.logic_key(RUN, "drive", "hello"), wire.pack(hello), wire.MSGPACK))
    return lockstep.bus.sent[-1][1]


def test_the_hub_and_a_joiner_derive_the_same_seal_key():
    lockstep, _ = hub_of()
    private, public = wire.key_pair()
    welcome = say_hello(lockstep, "p1", key=public)
    assert welcome["accepted"] and len(welcome["key"]) == 32
    mine = wire.seal_key(private, welcome["key"], RUN, "drive", "p1")
    assert mine == lockstep.peers["drive"].key
    body = wire.output_message(-1, [0.0])
    assert wire.unseal(lockstep.peers["drive"].key, wire.seal(mine, body)) == body
    with pytest.raises(wire.WireError):   # the same agreement under another id gives another key
        wire.unseal(wire.seal_key(private, welcome["key"], RUN, "drive", "p2"), wire.seal(mine, body))


def test_a_repeated_hello_gets_the_same_welcome_and_a_copied_id_gains_nothing():
    """Its welcome was lost, or the participant thought the hub gone: the same `key` comes back, the
    seal key stays. A stranger repeating the id with a key of its own gets that welcome too — and
    cannot open it."""
    lockstep, _ = hub_of()
    _, public = wire.key_pair()
    first = say_hello(lockstep, "p1", key=public)
    seal = lockstep.peers["drive"].key
    _, other = wire.key_pair()
    again, copied = say_hello(lockstep, "p1", key=public), say_hello(lockstep, "p1", key=other)
    assert again["key"] == copied["key"] == first["key"] and lockstep.peers["drive"].key == seal
    assert say_hello(lockstep, "p2", key=other)["error"] == "participant 'drive' is already on the bus (id p1)"


def test_a_joiner_without_key_is_named_once_and_not_under_access_control():
    lockstep, warnings = hub_of()
    assert say_hello(lockstep, "p1")["accepted"] and "key" not in lockstep.bus.sent[-1][1]
    lockstep.peers["drive"].lost = True   # it rejoins: no second warning
    assert say_hello(lockstep, "p1")["accepted"]
    assert warnings == [UNSEALED] and lockstep.peers["drive"].key is None
    guarded, warnings = hub_of(BusSettings(control=("plc",), watch=("hmi",)))
    assert say_hello(guarded, "p1")["accepted"] and warnings == []


def test_a_rejoin_after_a_loss_agrees_on_a_new_key():
    lockstep, _ = hub_of()
    _, public = wire.key_pair()
    first = say_hello(lockstep, "p1", key=public)["key"]
    seal = lockstep.peers["drive"].key
    lockstep.peers["drive"].lost = True
    _, fresh = wire.key_pair()
    assert say_hello(lockstep, "p1", key=fresh)["key"] != first and lockstep.peers["drive"].key != seal


def test_a_launched_participant_keeps_its_token_and_gets_no_key():
    lockstep, _ = hub_of()
    peer = lockstep.peers["drive"]
    peer.token, peer.key = "ab" * 16, b"ab" * 16
    _, public = wire.key_pair()
    welcome = say_hello(lockstep, "p1", token="ab" * 16, key=public)
    assert welcome["accepted"] and "key" not in welcome and peer.key == b"ab" * 16
