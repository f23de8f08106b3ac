"""Lockstep: the hub's side of logic served by participants over the bus — join, step, collect, loss.

Protocol (schemas/wire.md): a participant declares a liveliness token, announces itself with a
hello naming its inputs and outputs, gets a welcome with its parameters and answers with its
initial outputs. Every communication step the hub sends each participant a step message
(step number, tick, ticks, t, h, inputs) and, before the outputs are used at the next point,
waits for the output message tagged with that step number. Messages of different participants
may arrive in any order; each is filed under its sender. At a communication point the hub may ask
a participant for its whole state (save) or hand one back (restore), each answered within the lease.
"""
from __future__ import annotations

import logging
import secrets
import time
from dataclasses import dataclass, field
from pathlib import Path

from hub.bus import wire
from hub.bus.launcher import Launched
from hub.bus.session import Bus, Inbox, local_endpoint
from hub.bus.tls import environment as tls_environment
from hub.core.errors import CheckpointError, SimulationError
from hub.core.registry import did_you_mean
from hub.core.slots import SlotType

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RemoteSpec:
    """What the scenario expects of one participant."""

    name: str                                   # the logic object's name, its name on the bus
    inputs: tuple[tuple[str, SlotType], ...]    # in the scenario's order
    outputs: tuple[tuple[str, SlotType], ...]
    parameters: dict = field(default_factory=dict)
    command: tuple[str, ...] | None = None      # the hub starts it, or None: it joins by itself
    cwd: str | None = None
    join_timeout: float = 10.0
    detail: str = ""                            # how it is served, for messages: "FMU x.fmu"
    tls: tuple[str, str] | None = None          # a launched process's own certificate and key; None: the hub's

    @property
    def label(self) -> str:
        return f"participant {self.name!r}" + (f" ({self.detail})" if self.detail else "")


@dataclass
class _Peer:
    slave: object   # hub.logic.remote.RemoteSlave: the bus side knows it by its spec, link and counters
    process: Launched | None = None
    token: str | None = None           # handed to a launched process: its hello must carry it
    key: bytes | None = None           # seals its steps and outputs: the token, or agreed with a joiner
    hub_key: bytes | None = None       # a joiner's: the hub's X25519 public key in its last welcome
    warned_unsealed: bool = False      # a joiner without `key` was named once
    refused: str = ""                  # why the last hello under its name was refused (for the time-out message)
    id: str | None = None              # the participant's own id, from its hello
    welcomed: bool = False
    ready: bool = False                # initial outputs received after the last welcome
    lost: bool = False
    losses: int = 0                    # times its launched process was lost and relaunched
    in_order: list | None = None       # wire position → scenario input index (None: the same order)
    out_order: list = field(default_factory=list)   # scenario output index → wire position
    readers: list = field(default_factory=list)     # per scenario output: wire value → slot value
    wire_types: tuple | None = None    # the Python types of outputs that need no conversion, in wire order
    in_scenario_order: bool = True     # its outputs come in the scenario's order
    result_n: int | None = None
    result: list | None = None
    pending: bytes | None = None       # the last step message (unsealed), re-sent to a participant that rejoins
    from_tick: int = 0                 # where its next (or re-sent) step starts
    sent_at: float = 0.0
    step_pub: object = None
    welcome_pub: object = None
    checkpoint_pub: object = None
    held: bool = False                 # `result` came from a restore: initial outputs sent after it do not replace it

    @property
    def name(self) -> str:
        return self.slave.spec.name


class Lockstep:
    """Coordinates every participant of one run on the bus (none is fine: the hub still shows
    itself and its run state to viewers). `log(text)` receives what happened to the run (a pause,
    a resumption: the event log keeps it), `warn(text)` what happened beside it (a stranger refused)."""

    def __init__(self, bus: Bus, run: str, slaves: list, *, lease: float, on_loss: str,
                 rate: int, log=lambda text: None, warn=lambda text: None, logs: Path | None = None):
        self.bus = bus
        self.run = run
        self.lease = lease
        self.on_loss = on_loss
        self.rate = rate
        self.log = log
        self.warn = warn
        self.peers = {s.spec.name: _Peer(s) for s in slaves}
        for peer in self.peers.values():
            peer.slave.peer = peer
        self.inbox = Inbox()
        self.tick = 0
        self._closing = False
        self.logs = logs   # the folder where a launched process's output is kept when it ends (the run's)
        self.dropped: dict[tuple[str, str], int] = {}   # (participant, kind) → messages not taken
        self._tag = 0   # the last save or restore request's tag: an answer is taken only under its own
        self._token = None

    # --- start: launch what the scenario launches, wait for everyone ------------------------
    def start(self, tick: int = 0) -> None:
        self.tick = tick
        bus, run, inbox = self.bus, self.run, self.inbox
        self._state = bus.publisher(wire.control_key(run, "state"), wire.MSGPACK)
        bus.subscribe(wire.logic_key(run, "*", "hello"), lambda m: inbox.put(("hello", m)))
        bus.watch_tokens(wire.logic_key(run, "*"), lambda m: inbox.put(("token", m)))
        for name, peer in self.peers.items():
            bus.subscribe_payloads(wire.logic_key(run, name, "output"),
                                   lambda payload, peer=peer: inbox.put(("output", peer, payload)))
            peer.step_pub = bus.publisher(wire.logic_key(run, name, "step"), wire.MSGPACK)
            peer.welcome_pub = bus.publisher(wire.logic_key(run, name, "welcome"), wire.MSGPACK)
            bus.subscribe_payloads(wire.logic_key(run, name, "checkpoint_answer"),
                                   lambda payload, peer=peer: inbox.put(("checkpoint", peer, payload)))
            peer.checkpoint_pub = bus.publisher(wire.logic_key(run, name, "checkpoint"), wire.MSGPACK)
        self.publish_state("waiting" if self.peers else "running")
        self._token = bus.declare_token(wire.hub_token(run))
        for peer in self.peers.values():
            peer.slave.link = self
            if peer.slave.spec.command:
                peer.process = self._launch(peer)
        self._wait_ready(list(self.peers.values()), "join")
        if self.peers:
            self.publish_state("running")

    def _launch(self, peer: _Peer) -> Launched:
        spec = peer.slave.spec
        connect = [local_endpoint(e) for e in self.bus.endpoints] + list(self.bus.settings.connect)
        # A Zenoh router forwards only for clients; a peer hub talks to its peers directly.
        mode = "peer" if self.bus.settings.mode == "peer" else "client"
        if peer.token is None:   # one per participant and run: a relaunched process gets the same
            peer.token = secrets.token_hex(16)
            peer.key = peer.token.encode("ascii")
        env = {"PLANTHUB_RUN": self.run, "PLANTHUB_NAME": spec.name, "PLANTHUB_TOKEN": peer.token,
               "PLANTHUB_CONNECT": ",".join(connect),
               "PLANTHUB_MODE": mode, "PLANTHUB_LEASE": repr(self.lease),
               "PLANTHUB_JOIN_TIMEOUT": repr(spec.join_timeout),
               # when the hub stops waiting for it (wall clock): a process with a wait of its own
               # before it joins (a gateway waiting for its PLC) ends that wait first and says why
               "PLANTHUB_JOIN_DEADLINE": repr(time.time() + spec.join_timeout),
               **tls_environment(self.bus.settings.tls, loopback=not self.bus.settings.connect, own=spec.tls)}
        if spec.tls is None and "PLANTHUB_TLS_KEY" in env and "--tls-key" not in spec.command:
            self.warn(f"{spec.label} is launched with the hub's own certificate and private key "
                      f"(PLANTHUB_TLS_KEY): it can act as the hub on the bus; give it a certificate of its "
                      f"own with `tls: {{certificate, key}}` on its object")
        return Launched(spec.name, list(spec.command), spec.cwd, env)

    def _wait_ready(self, peers: list[_Peer], verb: str, done=lambda peer: peer.ready) -> None:
        """Wait until every peer in `peers` is welcomed and sent its initial outputs (or is `done`
        otherwise), each within its join timeout; a launched process that ends first is reported
        with its last output lines."""
        started = time.monotonic()
        if verb == "join":   # a rejoin is announced by _pause, with its reason
            for peer in peers:
                if not done(peer):
                    spec = peer.slave.spec
                    how = "launched, " if peer.process else ""
                    _log.info(f"waiting for {spec.label} to join ({how}up to {spec.join_timeout:g} s)")
        while True:
            waiting = [p for p in peers if not done(p)]
            if not waiting:
                return
            now = time.monotonic()
            for peer in waiting:
                self._check_process(peer, f"before it could {verb}")
                if now - started >= peer.slave.spec.join_timeout:
                    raise SimulationError(self._not_joined(peer, verb))
            nearest = min(started + p.slave.spec.join_timeout for p in waiting) - now
            item = self.inbox.get(min(0.05, nearest))
            if item is not None:
                self._dispatch(item)

    def _not_joined(self, peer: _Peer, verb: str) -> str:
        spec = peer.slave.spec
        where = ", ".join(local_endpoint(e) for e in self.bus.endpoints) or ", ".join(self.bus.settings.connect)
        started = (f"its command {' '.join(spec.command)!r} is running but did not announce itself"
                   if peer.process else
                   f"start it with the run name {self.run!r} and the hub's endpoint ({where or 'see run.bus'})")
        seen = "; it said hello but sent no initial outputs" if peer.welcomed else ""
        seen += f"; a hello under its name was refused: {peer.refused}" if peer.refused and not peer.welcomed else ""
        return (f"{spec.label} did not {verb} within {spec.join_timeout:g} s: {started}{seen}"
                f"{self._tail(peer)}")

    def _check_process(self, peer: _Peer, when: str) -> None:
        if peer.process is None:
            return
        code = peer.process.poll()
        if code is not None:
            spec = peer.slave.spec
            raise SimulationError(f"{spec.label}: its process {peer.process.how_it_ended(code)} "
                                  f"{when}{self._tail(peer)}")

    def _tail(self, peer: _Peer) -> str:
        tail = peer.process.tail() if peer.process else ""
        return f"\n  its output ends with:\n{tail}" if tail else ""

    # --- stepping -------------------------------------------------------------------------
    def send_step(self, slave, tick: int, ticks: int, t: float, h: float, values: list) -> None:
        peer = slave.peer
        if peer.in_order is not None:
            values = [values[i] for i in peer.in_order]
        peer.pending = body = wire.step_message(slave.sent, tick, ticks, t, h, values)
        slave.sent += 1
        peer.held = False
        peer.from_tick = tick
        self.tick = tick + ticks   # the point at which the run now waits for the answers
        peer.sent_at = time.monotonic()
        peer.step_pub.put(wire.seal(peer.key, body))

    def collect(self, slave) -> list:
        """The outputs of the last step sent to `slave` (before any step: its initial outputs)."""
        peer = slave.peer
        want = slave.sent - 1
        while peer.result_n != want:   # outputs that came meanwhile were filed already (poll, other collects)
            item = self.inbox.get(peer.sent_at + self.lease - time.monotonic())
            if item is not None:
                self._dispatch(item)
                continue
            for item in self.inbox.drain():   # a slow hub may not have looked for a while
                self._dispatch(item)
            if peer.result_n != want:
                self._lost(peer, f"did not answer step {want} within its lease of {self.lease:g} s: "
                                 f"it is frozen or too slow (a longer run.bus.lease gives it more time)")
        return peer.result

    def poll(self) -> None:
        """Handle whatever arrived, without waiting (a loss is noticed even between two collects)."""
        if not self.inbox.empty():
            for item in self.inbox.drain():
                self._dispatch(item)

    # --- save and restore: a participant's whole state at a communication point -------------------
    def save(self, slave) -> bytes:
        """The state bytes of `slave`'s participant after its last step (whose outputs are collected
        first); CheckpointError naming it and why if it cannot give them."""
        return self._checkpoint(slave, "save")["state"]

    def restore(self, slave, state: bytes, outputs: list) -> None:
        """Give `slave`'s participant back `state`; `outputs` (in the scenario's order) are then the
        outputs of its last step, as they were when the state was saved."""
        self._checkpoint(slave, "restore", state)
        peer = slave.peer
        peer.result, peer.result_n, peer.held = outputs, slave.sent - 1, True

    def _checkpoint(self, slave, op: str, state: bytes | None = None) -> dict:
        peer = slave.peer
        label = peer.slave.spec.label
        if peer.lost or not peer.welcomed:
            raise CheckpointError(f"{label} cannot {op} its state: it is not on the bus ({self._where()})")
        # At a communication point: the last step's outputs are in, so the participant is between steps.
        self.collect(slave)
        step = slave.sent - 1
        self._tag += 1
        tag = self._tag
        body = wire.save_request(tag, step) if op == "save" else wire.restore_request(tag, step, state)
        if len(body) > wire.MAX_STATE:
            raise CheckpointError(f"{label} cannot restore a state of {len(state)} bytes: a restore request "
                                  f"carries at most {wire.MAX_STATE} ({self._where()})")
        peer.checkpoint_pub.put(wire.seal(peer.key, body))
        deadline = time.monotonic() + self.lease
        others = []   # everything else waits until the answer is in: no step, loss or hello is handled half-way
        try:
            while True:
                item = self.inbox.get(deadline - time.monotonic())
                if item is None:
                    raise CheckpointError(
                        f"{label} did not answer the {op} request within its lease of {self.lease:g} s "
                        f"({self._where()}): it is frozen, or an older participant that does not know the "
                        f"message (schemas/wire.md, \"Save and restore\"){self._tail(peer)}")
                if item[0] == "checkpoint" and item[1] is peer:
                    answer = self._checkpoint_answer(peer, item[2], op, tag)
                    if answer is not None:
                        return answer
                    continue
                others.append(item)
                if item[0] == "token" and not item[1].alive and item[1].key.rsplit("/", 1)[-1] == peer.name:
                    # Kept for the loss handling of the next collect: the run decides about the loss.
                    raise CheckpointError(f"{label} {self._gone(peer)} while it was asked to {op} its state "
                                          f"({self._where()}){self._tail(peer)}")
        finally:
            for item in others:
                self.inbox.put(item)

    def _checkpoint_answer(self, peer: _Peer, payload: bytes, op: str, tag: int) -> dict | None:
        """The answer to request `tag`, or None for a message to drop; CheckpointError for an error answer."""
        label = peer.slave.spec.label
        try:
            payload = wire.unseal(peer.key, payload)
        except wire.WireError as exc:
            self._drop(peer, "foreign", str(exc))
            return None
        try:
            answer = wire.read_checkpoint_answer(payload)
        except wire.WireError as exc:
            raise CheckpointError(f"{label} sent a bad answer to the {op} request: {exc} ({self._where()})") from None
        if answer["tag"] != tag:
            self._drop(peer, "late checkpoint", f"an answer to request {answer['tag']}, the hub waits for {tag}")
            return None
        if answer["op"] != op:
            raise CheckpointError(f"{label} answered the {op} request as a {answer['op']} request ({self._where()})")
        if "error" in answer:
            trace = answer.get("traceback")
            where = ("\n  its traceback:\n" + "\n".join(f"    {line}" for line in trace[-4000:].rstrip().splitlines())
                     if isinstance(trace, str) and trace else "")
            raise CheckpointError(f"{label} could not {op} its state: {answer['error'][:2000]} "
                                  f"({self._where()}){where}")
        return answer

    # --- what arrives -------------------------------------------------------------------------
    def _dispatch(self, item) -> None:
        kind = item[0]
        if kind == "output":
            self._output(item[1], item[2])
        elif kind == "hello":
            self._hello(item[1])
        elif kind == "checkpoint":   # a save or restore answer after the hub stopped waiting for it
            self._drop(item[1], "late checkpoint", "an answer to a save or restore request no longer awaited")
        elif kind == "token":
            message = item[1]
            peer = self.peers.get(message.key.rsplit("/", 1)[-1])
            if peer is not None and not message.alive and peer.welcomed and not self._closing:
                reason = self._gone(peer)
                self._last_words(peer)
                self._lost(peer, reason)

    def _last_words(self, peer: _Peer) -> None:
        """What a participant said just before it went (an error report) may trail its token's end
        by a moment: take it in first, it names the cause."""
        deadline, others = time.monotonic() + 0.05, []
        try:
            while (item := self.inbox.get(deadline - time.monotonic())) is not None:
                if item[0] == "output" and item[1] is peer:
                    self._dispatch(item)
                else:
                    others.append(item)
        finally:
            for item in others:
                self.inbox.put(item)

    def _gone(self, peer: _Peer) -> str:
        if peer.process is not None:
            code = peer.process.poll(0.5)   # a killed process is gone before its token is
            if code is not None:
                return f"left the bus: its process {peer.process.how_it_ended(code)}"
            return ("stopped answering: its liveliness token expired while its process still runs "
                    "(frozen, or its connection broke)")
        return ("left the bus: its liveliness token went away (its process ended, froze longer than "
                "its lease, or lost its connection)")

    def _drop(self, peer: _Peer, kind: str, detail: str) -> None:
        """A message for `peer` not taken: counted by kind, logged the first time of each kind."""
        key = (peer.name, kind)
        self.dropped[key] = self.dropped.get(key, 0) + 1
        if self.dropped[key] == 1:
            self.warn(f"dropped a {kind} message for participant {peer.name!r} ({detail}); "
                      f"further ones are counted, not logged")

    def _output(self, peer: _Peer, payload: bytes) -> None:
        try:
            payload = wire.unseal(peer.key, payload)
        except wire.WireError as exc:
            self._drop(peer, "foreign", str(exc))
            return
        try:
            message = wire.unpack(payload)
            # The common case, decided with a few type tests: the answer to the step the hub waits
            # for, every value already of its slot's type (what the readers below would return).
            if type(message) is list and len(message) == 2:
                n, values = message
                if (type(n) is int and n == peer.slave.sent - 1 and n >= 0 and type(values) is list
                        and tuple(map(type, values)) == peer.wire_types):
                    peer.result = values if peer.in_scenario_order else [values[j] for j in peer.out_order]
                    peer.result_n = n
                    return
            if isinstance(message, dict) and "error" in message:
                trace = message.get("traceback")
                where = ("\n  its traceback:\n" + "\n".join(f"    {line}" for line in trace[-4000:].rstrip().splitlines())
                         if isinstance(trace, str) and trace else "")
                self._fail(peer, f"failed in step {message.get('step')}: {str(message['error'])[:2000]}", where)
            if not (isinstance(message, list) and len(message) == 2 and isinstance(message[0], int)
                    and isinstance(message[1], list)):
                raise wire.WireError(f"expected [n, outputs], got {message!r}")
            n, values = message
            outputs = peer.slave.spec.outputs
            if len(values) != len(outputs):
                raise wire.WireError(f"step {n}: {len(values)} outputs, announced {len(outputs)}")
            if n == -1:
                peer.ready = peer.welcomed
                if peer.slave.sent or peer.held:   # rejoined mid-run (or restored): its step results count, not these
                    return
            elif n != peer.slave.sent - 1:
                if n > peer.slave.sent - 1 or n < -1:
                    self._drop(peer, "future" if n > 0 else "malformed", f"an output for step {n}, "
                                                                         f"the hub is at step {peer.slave.sent - 1}")
                elif not peer.pending or n < peer.slave.sent - 2:
                    self._drop(peer, "stale", f"an output for step {n}, the hub is at step {peer.slave.sent - 1}")
                return   # an answer to a step the hub no longer waits for (re-sent after a rejoin)
            try:
                peer.result = [read(values[j]) for read, j in zip(peer.readers, peer.out_order)]
            except wire.WireError:
                for (slot, kind), j in zip(outputs, peer.out_order):   # again, to name the slot
                    wire.from_wire(kind, values[j], f"output {slot!r} of step {n}")
                raise
            peer.result_n = n
        except wire.WireError as exc:
            self._fail(peer, f"sent a bad output message: {exc}")

    def _hello(self, message) -> None:
        name = message.key.split("/")[-2]
        peer = self.peers.get(name)
        try:
            hello = wire.unpack(message.payload)
            if not isinstance(hello, dict) or hello.get("protocol") != wire.PROTOCOL:
                raise wire.WireError(f"expected a hello map with protocol {wire.PROTOCOL}, got {hello!r}")
            ident = hello.get("id")
            if not isinstance(ident, str):
                raise wire.WireError("the hello has no string `id`")
            inputs = wire.read_interface(hello.get("inputs"), "inputs")
            outputs = wire.read_interface(hello.get("outputs"), "outputs")
            key = wire.read_public_key(hello["key"]) if "key" in hello else None
        except wire.WireError as exc:
            try:
                sent = wire.unpack(message.payload)
            except wire.WireError:
                sent = None
            ident = sent.get("id") if isinstance(sent, dict) and isinstance(sent.get("id"), str) else None
            self._welcome(name, ident, error=f"bad hello: {exc}")
            return
        if peer is None:
            self._welcome(name, ident, error=f"run {self.run!r} has no participant {name!r}"
                                             f"{did_you_mean(name, self.peers)}")
            self.warn(f"refused participant {name!r}: the scenario has no such logic object")
            return
        if peer.welcomed and not peer.lost:
            if ident == peer.id:
                # Its welcome was lost, or it thought it had lost the hub: the same welcome again,
                # with the same `key`, so the seal key stays (a process that copied the id gains nothing).
                self._welcome(name, ident)
            else:
                self._refuse(peer, ident, f"participant {name!r} is already on the bus (id {peer.id})")
            return
        if peer.token is not None and hello.get("token") != peer.token:
            # The hub launched this participant: only the process it started knows the token.
            self._refuse(peer, ident, f"{peer.slave.spec.label} is launched by the hub, and this hello does not carry "
                                      "the token its process was given (PLANTHUB_TOKEN): another process")
            return
        problems = misfit(peer.slave.spec, inputs, outputs)
        if problems:
            error = f"{peer.slave.spec.label} does not fit the scenario: " + "; ".join(problems)
            self._welcome(name, ident, error=error)
            if peer.process is not None:
                raise SimulationError(error)   # the process the hub launched will not change: stop now
            self._refuse(peer, ident, error, answered=True)   # one that joins may be a stranger: wait on
            return
        hub_key = seal = None
        if peer.token is None and key is not None:   # it joined by itself: agree on its seal key
            private, hub_key = wire.key_pair()
            try:
                seal = wire.seal_key(private, key, self.run, name, ident)
            except wire.WireError as exc:
                self._welcome(name, ident, error=f"bad hello: {exc}")
                return
        spec = peer.slave.spec
        if peer.token is None:
            peer.key, peer.hub_key = seal, hub_key
            if key is None and not peer.warned_unsealed and self.bus.settings.control is None:
                peer.warned_unsealed = True   # under run.bus.access, mutual TLS and the ACL keep strangers off
                self.warn(f"{spec.label} joined without a key (its hello has no `key`): its steps and outputs "
                          f"are not sealed, so any process on the bus can answer in its place "
                          f"(schemas/wire.md, \"Sealed messages\")")
        in_names = [n for n, _ in inputs]
        out_names = [n for n, _ in outputs]
        in_order = [[n for n, _ in spec.inputs].index(n) for n in in_names]
        peer.in_order = None if in_order == sorted(in_order) else in_order
        peer.out_order = [out_names.index(n) for n, _ in spec.outputs]
        peer.readers = [wire.reader(kind) for _, kind in spec.outputs]
        peer.wire_types = wire.python_types([kind for _, kind in outputs])
        peer.in_scenario_order = peer.out_order == list(range(len(outputs)))
        peer.id, peer.welcomed, peer.ready, peer.lost = ident, True, False, False
        peer.sent_at = time.monotonic()
        self._welcome(name, ident)

    def _refuse(self, peer: _Peer, ident: str | None, error: str, answered: bool = False) -> None:
        """Refuse a hello without disturbing the run: say why to its sender and in the log."""
        if not answered:
            self._welcome(peer.name, ident, error=error)
        if error != peer.refused:   # a repeated hello (every 0.5 s) is logged once
            self.warn(f"refused a hello for {peer.name!r} (id {ident!r}): {error}")
        peer.refused = error

    def _welcome(self, name: str, ident: str | None, error: str | None = None) -> None:
        if error is None:
            peer = self.peers[name]
            start = peer.from_tick if peer.result_n != peer.slave.sent - 1 else self.tick
            body = {"protocol": wire.PROTOCOL, "id": ident, "accepted": True, "run": self.run, "rate": self.rate,
                    "tick": start, "time": start / self.rate, "lease": self.lease,
                    "parameters": peer.slave.spec.parameters}
            if peer.hub_key is not None:   # a joiner that sent `key`: the hub's half of its seal key
                body["key"] = peer.hub_key
        else:
            body = {"protocol": wire.PROTOCOL, "id": ident, "accepted": False, "error": error}
        publisher = self.peers[name].welcome_pub if name in self.peers else None
        if publisher is not None:
            publisher.put(wire.pack(body))
        else:
            self.bus.put(wire.logic_key(self.run, name, "welcome"), wire.pack(body), wire.MSGPACK)

    # --- loss -------------------------------------------------------------------------------
    def _where(self) -> str:
        return f"at t = {self.tick / self.rate:.9g} s"

    def _fail(self, peer: _Peer, reason: str, detail: str = "") -> None:
        spec = peer.slave.spec
        raise SimulationError(f"{spec.label} {reason} ({self._where()}); "
                              f"the run stops here, the recording so far is kept{detail}")

    def _lost(self, peer: _Peer, reason: str) -> None:
        peer.lost = True
        if self.on_loss != "pause" or self._closing:
            self._fail(peer, reason)
        self._pause(peer, reason)

    def _pause(self, peer: _Peer, reason: str) -> None:
        spec = peer.slave.spec
        text = f"{spec.label} {reason} ({self._where()})"
        self.publish_state("paused", text)
        self.log(f"paused: {text}; waiting up to {spec.join_timeout:g} s for it to rejoin")
        peer.welcomed = peer.ready = False
        if peer.process is not None:   # what it said says why it was lost: kept, per attempt, and shown
            peer.losses += 1
            kept = f"{spec.name}.lost{peer.losses}"
            self._echo(peer, peer.process.stop(grace=0.0, keep=self.logs, as_name=kept), kept)
            peer.process = self._launch(peer)
        # It comes back with a new hello — or, if it only stalled and never lost its connection,
        # with its late answer.
        answered = lambda p: p.result_n == p.slave.sent - 1
        self._wait_ready([peer], "rejoin", done=lambda p: p.ready or answered(p))
        if not answered(peer):
            peer.sent_at = time.monotonic()
            peer.step_pub.put(wire.seal(peer.key, peer.pending))   # a joiner that rejoined has a new key
        peer.lost, peer.welcomed = False, True
        self.publish_state("running")
        self.log(f"resumed: {spec.label} {'rejoined' if peer.ready else 'answered late'}")

    # --- the end ------------------------------------------------------------------------------
    def publish_state(self, state: str, reason: str = "") -> None:
        self._state.put(wire.pack({"state": state, "tick": self.tick, "time": self.tick / self.rate,
                                   "reason": reason}))

    def release(self, slave) -> None:
        slave.link = None

    def close(self, reason: str = "") -> None:
        """Tell everyone the run stopped, then make sure every launched process has ended."""
        if self._closing:
            return
        self._closing = True
        try:
            if not self.bus.closed and hasattr(self, "_state"):
                self.publish_state("stopped", reason)
        finally:
            for peer in self.peers.values():
                peer.slave.link = None
                if peer.process is not None:
                    said = peer.process.stop(grace=0.0 if peer.lost else 3.0, keep=self.logs)
                    self._echo(peer, said)
            if self.dropped:
                counts = ", ".join(f"{n} {kind} for {name!r}" for (name, kind), n in sorted(self.dropped.items()))
                self.warn(f"messages dropped on the bus in this run: {counts}")
            if self._token is not None:
                self._token.undeclare()


    def _echo(self, peer: _Peer, said: list[str], kept: str | None = None, most: int = 12) -> None:
        """What a launched process said (a gateway's refused writes), on the hub's console too: its last
        lines; `kept` is the name its output was kept under (NAME.log unless given)."""
        if not said:
            return
        where = f" (all {len(said)} in {self.logs / ((kept or peer.slave.spec.name) + '.log')})" \
            if self.logs is not None else ""
        lines = "\n".join(f"    {line}" for line in said[-most:])
        _log.info(f"{peer.slave.spec.label} said{where}:\n{lines}")


def misfit(spec: RemoteSpec, inputs, outputs) -> list[str]:
    """Differences between what the scenario expects and what a participant announced."""
    problems = []
    for label, want, have in (("input", spec.inputs, inputs), ("output", spec.outputs, outputs)):
        have_map, want_map = dict(have), dict(want)
        for name, kind in want:
            if name not in have_map:
                problems.append(f"it lacks {label} {name!r} ({kind.value})")
            elif have_map[name] is not kind:
                problems.append(f"its {label} {name!r} is {have_map[name].value}, the scenario's is {kind.value}")
        for name, kind in have:
            if name not in want_map:
                problems.append(f"its {label} {name!r} ({kind.value}) is not in the scenario"
                                f"{did_you_mean(name, want_map)}")
        if len(have_map) != len(have):
            problems.append(f"it announces an {label} twice")
    return problems


def pid_of(slave) -> int | None:
    """The process id of a launched participant (tests kill it), or None."""
    link = slave.link
    peer = link.peers.get(slave.spec.name) if link else None
    return peer.process.pid if peer and peer.process else None

