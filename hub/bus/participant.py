"""The Python participant library: serve a piece of logic to a running plant over the bus, in lockstep.

    from hub.bus.participant import Participant, serve

    class Doubler(Participant):
        inputs = {"x": "real"}
        outputs = {"y": "real"}

        def step(self, t, h):
            self.y = 2 * self.x

    raise SystemExit(serve(Doubler()))

Inputs, outputs and parameters are attributes: the hub's values are set before every `step`,
the outputs read after it. A checkpoint of the run saves every attribute of the participant and
puts them back on restore (`save_state`/`restore_state`; override both for state held elsewhere). Where to connect comes from the command line (`--run`, `--name`,
`--connect`, `--mode`, `--lease`, `--tls-*`) or, for a process the hub launched, from its environment.
"""
from __future__ import annotations

import argparse
import logging
import os
import pickle
import time
import traceback
import uuid
from typing import ClassVar

from hub.bus import wire
from hub.bus.session import Bus, Inbox
from hub.bus.settings import BusSettings
from hub.bus.tls import TlsSettings
from hub.bus.tls import problems as tls_problems
from hub.core.errors import CheckpointError, PlanthubError
from hub.core.slots import SlotType

_RESERVED = {"inputs", "outputs", "parameters", "start", "step", "close", "interface", "begin", "advance",
             "current_outputs", "save_state", "restore_state"}


#: The library's own attributes, set in `interface()`: derived from the class, not state, so a
#: default save leaves them out and a restore keeps those of the participant it restores into.
_INTERNAL = frozenset({"_in", "_out", "_readers", "_in_names", "_in_types", "_out_names", "_events_out"})
#: The first item of a default state: tells it from other bytes (and from a later layout).
STATE_FORMAT = "planthub.participant.state/1"

_log = logging.getLogger(__name__)   # a process that sets up no logging still gets its errors on stderr

__all__ = ["Participant", "serve", "add_options", "add_tls_options", "check_options", "tls_settings"]

class Participant:
    """Base of a participant's logic. Declare `inputs` and `outputs` (name → slot type: void, bool,
    int, real, vec3, quat, string) and default `parameters`; write `step(t, h)`.

    A void input is True in the steps a flow fed it; a void output set True fires the event.
    Outputs start at their type's initial value (0, False, …) unless `start` sets them.
    """

    inputs: ClassVar[dict[str, str]] = {}
    outputs: ClassVar[dict[str, str]] = {}
    parameters: ClassVar[dict] = {}

    def start(self) -> None:
        """Called when the hub has welcomed this participant and set its parameters."""

    def step(self, t: float, h: float) -> None:
        """Advance from t to t + h with the inputs (attributes) of t; set the outputs (attributes)."""

    def close(self) -> None:
        """Called once when the run is over."""

    def save_state(self) -> bytes:
        """The participant's whole state at this communication point, as bytes only it reads back.

        By default every instance attribute (inputs, outputs, parameters and whatever the logic
        keeps) except the library's own, pickled in one go (so two attributes that share a list
        still share it after a restore). Override both this and `restore_state` when the state
        lives elsewhere (a device, a file, another language's runtime) or is not picklable.
        An attribute that cannot be pickled (a socket, a lock, an open file) is a CheckpointError
        that names it.

        The bytes are the participant's business: the hub stores them unread and hands them back to
        the same participant class for `restore_state`. The default unpickles them there, so they
        must come from a checkpoint you trust (over the bus only the hub can send them: sealed).
        """
        attributes = {name: value for name, value in getattr(self, "__dict__", {}).items() if name not in _INTERNAL}
        try:
            return pickle.dumps((STATE_FORMAT, type(self).__qualname__, attributes), protocol=5)
        except Exception as exc:   # pickle raises PicklingError, TypeError, AttributeError, … for what it cannot take
            bad = [name for name, value in attributes.items() if not _picklable(value)]
            what = (f"attribute{'s' if len(bad) > 1 else ''} {', '.join(map(repr, bad))}" if bad
                    else "its attributes together")
            raise CheckpointError(f"{type(self).__name__} cannot save {what} ({type(exc).__name__}: {exc}); "
                                  f"override save_state and restore_state for state that pickle cannot "
                                  f"take") from None

    def restore_state(self, data: bytes) -> None:
        """Put back a state `save_state` of this participant class gave: its attributes become the
        saved ones (one set since then and not saved is removed), the library's own stay."""
        try:
            form, kind, attributes = pickle.loads(data)
        except Exception as exc:   # anything in the bytes may fail to load, in any way
            raise CheckpointError(f"{type(self).__name__} cannot read the saved state "
                                  f"({type(exc).__name__}: {exc})") from None
        if form != STATE_FORMAT or not isinstance(attributes, dict):
            raise CheckpointError(f"{type(self).__name__}: the saved state is not a participant's default "
                                  f"state ({STATE_FORMAT})")
        if kind != type(self).__qualname__:
            raise CheckpointError(f"{type(self).__name__}: the saved state is a {kind}'s")
        own = self.__dict__
        for name in [name for name in own if name not in _INTERNAL and name not in attributes]:
            del own[name]
        own.update((name, value) for name, value in attributes.items() if name not in _INTERNAL)

    # --- what the protocol loop calls; an adapter (an FMU, another language's binding) overrides these
    def interface(self) -> tuple[list[tuple[str, SlotType]], list[tuple[str, SlotType]]]:
        problems = []
        pairs = []
        for label, table in (("input", self.inputs), ("output", self.outputs)):
            group = []
            for name, kind in table.items():
                if name in _RESERVED or name.startswith("_"):
                    problems.append(f"{label} {name!r} collides with a Participant attribute")
                try:
                    group.append((name, SlotType(kind)))
                except ValueError:
                    problems.append(f"{label} {name!r} has type {kind!r}; slot types are "
                                    f"{', '.join(t.value for t in SlotType)}")
            pairs.append(group)
        if problems:
            raise PlanthubError(f"{type(self).__name__}: " + "; ".join(problems))
        self._in, self._out = pairs
        self._readers = [(name, wire.reader(kind)) for name, kind in self._in]
        # The hot path of `advance` and `current_outputs`: names once, and the msgpack types of
        # inputs that arrive ready to use (so no reader needs to run).
        self._in_names = tuple(name for name, _ in self._in)
        self._in_types = wire.python_types(kind for _, kind in self._in)
        self._out_names = tuple(name for name, _ in self._out)
        self._events_out = tuple(name for name, kind in self._out if kind is SlotType.VOID)
        return pairs[0], pairs[1]

    def begin(self, parameters: dict, time: float) -> None:
        for name, value in {**self.parameters, **parameters}.items():
            setattr(self, name, value)
        for name, kind in self._in + self._out:
            if not hasattr(self, name):
                setattr(self, name, False if kind is SlotType.VOID else kind.initial())
        self.start()

    def advance(self, t: float, h: float, values: list) -> list:
        if tuple(map(type, values)) == self._in_types:   # each value as its slot wants it
            for name, value in zip(self._in_names, values):
                setattr(self, name, value)
        else:
            try:
                for (name, read), value in zip(self._readers, values):
                    setattr(self, name, read(value))
            except wire.WireError:
                for (name, kind), value in zip(self._in, values):   # again, to name the input
                    wire.from_wire(kind, value, f"input {name!r}")
                raise
        self.step(t, h)
        return self.current_outputs()

    def current_outputs(self) -> list:
        out = [getattr(self, name) for name in self._out_names]
        for name in self._events_out:
            setattr(self, name, False)   # an event fires once
        return out


def _picklable(value) -> bool:
    try:
        pickle.dumps(value, protocol=5)
    except Exception:   # whatever pickle raises for it
        return False
    return True


def add_options(parser: argparse.ArgumentParser) -> None:
    """Where to join: command-line options, defaulting to what a launching hub put in the environment."""
    env = os.environ.get
    parser.add_argument("--run", default=env("PLANTHUB_RUN"), help="the run's name (the scenario's name)")
    parser.add_argument("--name", default=env("PLANTHUB_NAME"), help="the logic object this participant serves")
    parser.add_argument("--connect", action="append", metavar="ENDPOINT",
                        help="the hub's (or a router's) endpoint, e.g. tcp/192.168.1.5:7447; repeatable")
    parser.add_argument("--mode", default=env("PLANTHUB_MODE", "peer"), choices=["peer", "client"],
                        help="peer: connect to the hub itself; client: through a Zenoh router (or a router hub)")
    parser.add_argument("--lease", type=float, default=float(env("PLANTHUB_LEASE", "1.0")),
                        help="s after which the hub declares this process frozen")
    parser.add_argument("--join-timeout", type=float, default=float(env("PLANTHUB_JOIN_TIMEOUT", "30")),
                        help="s to wait for the hub (and for it to come back after a lost connection)")
    add_tls_options(parser)


def add_tls_options(parser: argparse.ArgumentParser) -> None:
    """Certificates for tls/ endpoints (a hub that launches the process puts its own in the environment)."""
    env = os.environ.get
    tls = parser.add_argument_group("TLS (for tls/ endpoints)")
    tls.add_argument("--tls-ca", default=env("PLANTHUB_TLS_CA"), metavar="PEM",
                     help="the authority that signed the hub's certificate")
    tls.add_argument("--tls-cert", default=env("PLANTHUB_TLS_CERT"), metavar="PEM",
                     help="this process's certificate, for a hub that asks for one (mutual TLS)")
    tls.add_argument("--tls-key", default=env("PLANTHUB_TLS_KEY"), metavar="PEM", help="the private key of --tls-cert")
    tls.add_argument("--tls-no-verify-name", action="store_true", default=env("PLANTHUB_TLS_VERIFY_NAME") == "0",
                     help="accept a hub certificate that does not name the endpoint's host (it is still "
                          "checked against --tls-ca)")


_TLS_OPTIONS = {"ca": "--tls-ca", "certificate": "--tls-cert", "key": "--tls-key", "tls": "--tls-*"}


def tls_settings(parser: argparse.ArgumentParser, args: argparse.Namespace) -> TlsSettings | None:
    """The TLS settings the options give (None: none given); a bad set-up is a usage error."""
    tls = None
    if args.tls_ca or args.tls_cert or args.tls_key:
        tls = TlsSettings(args.tls_ca, args.tls_cert, args.tls_key, mutual=bool(args.tls_cert),
                          verify_name=not args.tls_no_verify_name)
    wrong = []
    for place, message in tls_problems(tls, (), args.connect, listening=False):
        if place[0] == "connect":
            endpoint = args.connect[place[1]]
            message = f"{endpoint} is a TLS endpoint: give --tls-ca, the authority that signed the hub's certificate"
        wrong.append(f"{_TLS_OPTIONS.get(place[-1], '--connect')}: {message}")
    if wrong:
        parser.error("; ".join(wrong))
    return tls


def check_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> argparse.Namespace:
    if not args.connect:
        args.connect = [e for e in os.environ.get("PLANTHUB_CONNECT", "").split(",") if e]
    missing = [o for o in ("run", "name") if not getattr(args, o)]
    if missing:
        parser.error(f"give {' and '.join('--' + o for o in missing)} (or start me from a scenario)")
    args.tls = tls_settings(parser, args)
    return args


def serve(logic: Participant, argv=None, args: argparse.Namespace | None = None) -> int:
    """Serve `logic` until the run stops (options from `argv`, default the command line, or parsed
    `args`); the exit status: 0 when the run ended, 1 on an error."""
    if args is None:
        doc = (type(logic).__doc__ or "a planthub participant").strip().splitlines()[0]
        parser = argparse.ArgumentParser(description=doc)
        add_options(parser)
        args = check_options(parser, parser.parse_args(argv))
    try:
        with _Link(logic, args) as link:
            return link.serve()
    except PlanthubError as exc:
        _log.error(f"planthub participant {args.name!r}: {exc}")
        return 1


class _Link:
    """One participant's session with the hub: hello, welcome, then steps until the run stops."""

    def __init__(self, logic: Participant, args):
        self.logic, self.args = logic, args
        self.run, self.name = wire.check_run_name(args.run), args.name
        self.inputs, self.outputs = logic.interface()
        self.id = uuid.uuid4().hex
        self.inbox = Inbox()
        settings = BusSettings(mode=args.mode, connect=tuple(args.connect), lease=args.lease,
                               tls=getattr(args, "tls", None))
        self.bus = Bus(settings, listen=False)
        self.hub_alive = False
        self.lost_at = None       # when the hub's token went away, while it is away
        self.last = None          # (step number, output message) of the last step served
        self.at = -1              # the number of the last step served (or restored to): a save is of that point
        self.begun = False        # the logic has its parameters and started (a rejoin or a restore does not redo it)
        # Steps and outputs are sealed, so no other process can speak for either side (schemas/wire.md,
        # "Sealed messages"): launched by the hub, with its token; joined by itself, with a key agreed
        # in the hello and the welcome (a new one at every join).
        self.token = os.environ.get("PLANTHUB_TOKEN") or None
        self.key = self.token.encode("ascii") if self.token else None
        self.hub_key = None       # a joiner: the hub's public key in the last welcome
        self.foreign = 0          # step messages that did not open with the key: not ours, dropped

    def __enter__(self):
        bus, inbox, key = self.bus, self.inbox, lambda *p: wire.logic_key(self.run, self.name, *p)
        try:
            bus.subscribe_payloads(key("welcome"), lambda p: inbox.put(("welcome", p)))
            bus.subscribe_payloads(key("step"), inbox.put)   # a step is the bare payload: see serve
            bus.subscribe_payloads(wire.control_key(self.run, "state"), lambda p: inbox.put(("state", p)))
            bus.subscribe_payloads(key("checkpoint"), lambda p: inbox.put(("checkpoint", p)))
            bus.watch_tokens(wire.hub_token(self.run), lambda m: inbox.put(("hub", m.alive)))
            self.output = bus.publisher(key("output"), wire.MSGPACK)
            self.hello = bus.publisher(key("hello"), wire.MSGPACK)
            self.answer = bus.publisher(key("checkpoint_answer"), wire.MSGPACK)
            bus.declare_token(key())
        except BaseException:
            bus.close()
            raise
        return self

    def __exit__(self, *exc):
        try:
            self.logic.close()
        finally:
            self.bus.close()

    def serve(self) -> int:
        self._join()
        # Steps arrive as bare payloads (bytes), everything else as (kind, value): the loop a step
        # takes is kept short, as it runs at every communication point of the run.
        take, step = self.inbox.get, self._step
        while True:
            item = take(1.0)
            if type(item) is bytes:
                step(item)
                if self.lost_at is not None:
                    self.lost_at = time.monotonic()   # its token went, yet it steps us: give it time
                continue
            news = self._news(item)
            if news == "stopped":
                return 0
            if news == "rejoin":
                self._join()

    def _news(self, item) -> str | None:
        """What a message other than a step means: "stopped", "rejoin" or None (also for nothing
        within a second); the hub's absence is bounded by the join timeout."""
        if item is None:
            grace = self.args.join_timeout
            if self.lost_at is not None and time.monotonic() - self.lost_at > grace:
                raise PlanthubError(f"the hub of run {self.run!r} went away and did not come back "
                                    f"within {grace:g} s")
            return None
        kind, value = item
        if kind == "checkpoint":
            self._checkpoint(value)
            return None
        if kind == "state" and _map(value).get("state") == "stopped":
            return "stopped"
        if kind == "hub":
            self.hub_alive = value
            if value and self.lost_at is not None:
                return "rejoin"   # it came back (a broken connection healed): say hello again
            if not value:
                self.lost_at = time.monotonic()
        return None

    def _join(self) -> None:
        """Wait for the hub, say hello until welcomed, start the logic, send the initial outputs."""
        limit = self.args.join_timeout
        deadline = time.monotonic() + limit
        hello = {"protocol": wire.PROTOCOL, "name": self.name, "id": self.id, "agent": wire.AGENT,
                 "inputs": wire.interface(self.inputs), "outputs": wire.interface(self.outputs)}
        private = None
        if self.token:   # launched by the hub: prove it is the process it started
            hello["token"] = self.token
        else:            # joined by itself: our half of the seal key, fresh for every join
            private, hello["key"] = wire.key_pair()
        hello = wire.pack(hello)
        sent_at = None
        while True:
            now = time.monotonic()
            if now > deadline:
                where = ", ".join(self.args.connect) or "no --connect endpoint"
                state = "no welcome from it" if self.hub_alive else "no hub seen"
                raise PlanthubError(f"{state} within {limit:g} s (run {self.run!r}, {where})")
            if self.hub_alive and (sent_at is None or now - sent_at > 0.5):
                self.hello.put(hello)   # repeated: the hub may not have been listening yet
                sent_at = now
            item = self.inbox.get(0.1)
            if item is None or type(item) is bytes:
                continue   # a step before the welcome: the hub sends it again once we are back
            kind, value = item
            if kind == "hub":
                self.hub_alive, sent_at = value, None
            elif kind == "welcome":
                welcome = _map(value)
                if welcome.get("id") != self.id:
                    continue   # meant for another process under this name
                if not welcome.get("accepted"):
                    raise PlanthubError(f"the hub refused me: {welcome.get('error')}")
                break
            elif kind == "state" and _map(value).get("state") == "stopped":
                raise PlanthubError(f"the run stopped before I could {'re' if self.last else ''}join")
        if private is not None:
            if "key" in welcome:
                hub_key = wire.read_public_key(welcome["key"], "the welcome's `key`")
                if hub_key != self.hub_key or self.key is None:
                    self.key = wire.seal_key(private, hub_key, self.run, self.name, self.id)
                # else: the welcome of our last join, again: the hub never lost us, the seal key stays
                self.hub_key = hub_key
            else:   # a hub that does not seal joiners' messages (it ignored our `key`)
                self.key = self.hub_key = None
                _log.warning(f"planthub participant {self.name!r}: the hub's welcome has no `key`: steps and "
                             f"outputs are not sealed, any process on the bus can answer in my place")
        if not self.begun:
            self.logic.begin(dict(welcome.get("parameters") or {}), float(welcome.get("time", 0.0)))
            self.begun = True
        self.output.put(wire.seal(self.key, wire.output_message(-1, self.logic.current_outputs() if self.last is None
                                                                else wire.unpack(self.last[1])[1])))
        self.lost_at = None if self.hub_alive else time.monotonic()

    def _step(self, payload: bytes) -> None:
        try:
            payload = wire.unseal(self.key, payload)
        except wire.WireError:
            self.foreign += 1   # another process's step on our key: the hub's own ones open
            if self.foreign == 1:
                _log.warning(f"planthub participant {self.name!r}: dropped a step message not sealed by the hub")
            return
        n, _tick, _ticks, t, h, values = wire.read_step(payload)
        if self.last is not None and self.last[0] == n:
            self.output.put(wire.seal(self.key, self.last[1]))   # asked again after a rejoin: the same answer
            return
        try:
            outputs = self.logic.advance(t, h, values)
        except Exception as exc:
            # The logic's own named error (a gateway's PLC that stopped answering) says all there is:
            # no traceback for it; anything else is a bug of the logic, and its traceback helps.
            named = isinstance(exc, PlanthubError)
            detail = str(exc) if named else "".join(traceback.format_exception_only(type(exc), exc)).strip()
            trace = "" if named else "".join(traceback.format_tb(exc.__traceback__))
            self.output.put(wire.seal(self.key, wire.error_message(n, detail, trace)))
            raise PlanthubError(f"step {n} failed: {detail}") from exc
        message = wire.output_message(n, outputs)
        self.last, self.at = (n, message), n
        self.output.put(wire.seal(self.key, message))

    def _checkpoint(self, payload: bytes) -> None:
        """Answer a save or restore request (schemas/wire.md, "Save and restore"); a failure is
        answered with its cause, and the participant goes on: the run decides what a failed
        checkpoint means."""
        try:
            request = wire.read_checkpoint(wire.unseal(self.key, payload))
        except wire.WireError as exc:
            # Not the hub's (a stranger cannot seal), or junk: no tag to answer under; logged once, as steps.
            self.foreign += 1
            if self.foreign == 1:
                _log.warning(f"planthub participant {self.name!r}: dropped a checkpoint message: {exc}")
            return
        op, tag, step = request["op"], request["tag"], request["step"]
        try:
            if op == "save":
                if step != self.at:   # the hub collects a step's outputs before it saves: never mid-step
                    raise CheckpointError(f"asked to save the state after step {step}, but my last step is {self.at}")
                state = self.logic.save_state()
                if not isinstance(state, (bytes, bytearray)):
                    raise CheckpointError(f"save_state gave {type(state).__name__}, not bytes")
                answer = wire.saved_answer(tag, step, bytes(state))
                if len(answer) > wire.MAX_STATE:
                    raise CheckpointError(f"the state is {len(state)} bytes; a save answer carries at most "
                                          f"{wire.MAX_STATE}")
            else:
                self.logic.restore_state(bytes(request["state"]))
                # Now at the restored point: the next step is step + 1, and no earlier answer stands.
                self.last, self.at, self.begun = None, step, True
                answer = wire.restored_answer(tag, step)
        except Exception as exc:   # the logic's own save or restore may raise anything: the hub is told why
            detail = str(exc) if isinstance(exc, PlanthubError) else \
                "".join(traceback.format_exception_only(type(exc), exc)).strip()
            _log.error(f"planthub participant {self.name!r}: {op} failed: {detail}")
            answer = wire.checkpoint_error(op, tag, step, detail, "".join(traceback.format_tb(exc.__traceback__)))
        self.answer.put(wire.seal(self.key, answer))


def _map(payload: bytes) -> dict:
    """A control message that should be a map; anything else (not msgpack, not a map) counts as an
    empty one: a stranger's junk on our keys must not end the participant."""
    try:
        message = wire.unpack(payload)
    except wire.WireError:
        return {}
    return message if isinstance(message, dict) else {}
