"""The Zenoh session: every Zenoh call planthub makes goes through this file (but setting up Zenoh's log: hub/bus/log.py).

Received samples reach the caller through callbacks that only append to an `Inbox`; the main
thread waits on that queue (which releases the GIL), never inside Zenoh. A callback that did real
work would starve while the main thread steps the physics (measured: callbacks wait for the GIL).
"""
from __future__ import annotations

import atexit
import json
import queue
import re
import socket
import threading
import time
import weakref
from dataclasses import dataclass

import zenoh

from hub.bus import log as zenoh_log
from hub.bus.settings import BusSettings
from hub.bus.tls import TlsSettings
from hub.bus.tls import common_name as tls_common_name
from hub.bus.tls import problems as tls_problems
from hub.bus.tls import refused as tls_refused
from hub.core.errors import PlanthubError, format_path


class BusError(PlanthubError):
    """The bus cannot be opened or used; the message names the endpoint or key and Zenoh's cause."""


@dataclass(frozen=True)
class Message:
    """One received sample, with Zenoh's types turned into plain Python."""

    key: str
    payload: bytes
    encoding: str
    attachment: bytes | None = None
    alive: bool = True   # False: a DELETE (for liveliness: the token went away)


class Inbox:
    """A queue filled by the bus's threads and emptied by the main thread, always with a timeout."""

    def __init__(self):
        self._queue = queue.SimpleQueue()
        self.put = self._queue.put

    def get(self, timeout: float):
        """The next item, or None when nothing came within `timeout` seconds."""
        try:
            return self._queue.get(True, timeout if timeout > 0.0 else 0.0)
        except queue.Empty:
            return None

    def drain(self) -> list:
        items = []
        while True:
            try:
                items.append(self._queue.get_nowait())
            except queue.Empty:
                return items

    def empty(self) -> bool:
        return self._queue.empty()


def free_loopback_endpoint() -> str:
    """`tcp/127.0.0.1:<port>` on a port free right now (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def local_endpoint(endpoint: str) -> str:
    """The endpoint a process on this machine connects to, for one the hub listens on."""
    return re.sub(r"^(tcp|udp|tls|quic)/(0\.0\.0\.0|\[::\])(:\d+)", r"\1/127.0.0.1\3", endpoint)


def _configure_tls(config, tls: TlsSettings) -> None:
    """The `transport/link/tls` part: one certificate serves both directions (listening, and
    presenting it to a listener that asks, with `mutual`)."""
    entries = {"root_ca_certificate": tls.ca,
               "listen_certificate": tls.certificate, "listen_private_key": tls.key,
               "connect_certificate": tls.certificate if tls.mutual else None,
               "connect_private_key": tls.key if tls.mutual else None,
               "enable_mtls": tls.mutual, "verify_name_on_connect": tls.verify_name}
    for key, value in entries.items():
        if value is not None:
            config.insert_json5(f"transport/link/tls/{key}", json.dumps(value))


# Under access control, watching — the data plane and the run, rate requests — is for the common
# names listed in `watch` and `control`; the control plane as a whole (serving logic: hello, output,
# its token; commands) for those in `control`; and both for the hub's own. A certificate signed by
# the authority but not named gets a connection and nothing through it.
_WATCH_KEYS = ["plant/*/**", "plant/*/@cosim/hub", "plant/*/@cosim/state", "plant/*/@cosim/command/result",
               "plant/*/@cosim/viewer/**", "plant/*/@cosim/scene", "plant/*/@cosim/bodies",
               "plant/*/@cosim/events", "plant/*/@cosim/figures", "plant/*/@cosim/checkpoints"]
_MESSAGES = ["put", "delete", "declare_subscriber", "query", "declare_queryable", "reply", "liveliness_token",
             "declare_liveliness_subscriber", "liveliness_query"]


def _configure_access(config, control: tuple[str, ...], watch: tuple[str, ...], tls: TlsSettings,
                      instructor: tuple[str, ...] = ()) -> None:
    """Zenoh's access control, by certificate common name. A denied message is dropped without a
    word to its sender; hub/bus/README.md says what that looks like. An instructor watches, and
    alone (with the hub's own) reaches the instructor's key, where faults are injected and shown:
    a controller's `plant/*/@cosim/**` does not match that verbatim chunk."""
    controllers = list(dict.fromkeys(control))
    own = tls_common_name(tls.certificate) if tls.certificate else None
    if own:
        controllers = list(dict.fromkeys([*controllers, own]))   # the participants the hub launches present it
    instructors = list(dict.fromkeys([*instructor, *([own] if own else [])]))
    watchers = list(dict.fromkeys([*watch, *controllers, *instructor]))
    rules = [{"id": "watch", "permission": "allow", "messages": _MESSAGES, "key_exprs": _WATCH_KEYS},
             {"id": "control", "permission": "allow", "messages": _MESSAGES, "key_exprs": ["plant/*/@cosim/**"]},
             {"id": "instruct", "permission": "allow", "messages": _MESSAGES, "key_exprs": ["plant/*/@instructor/**"]}]
    subjects, policies = [], []
    if instructors:
        subjects.append({"id": "instructors", "cert_common_names": instructors})
        policies.append({"rules": ["instruct"], "subjects": ["instructors"]})
    if watchers:
        subjects.append({"id": "watchers", "cert_common_names": watchers})
        policies.append({"rules": ["watch"], "subjects": ["watchers"]})
    if controllers:
        subjects.append({"id": "controllers", "cert_common_names": controllers})
        policies.append({"rules": ["control"], "subjects": ["controllers"]})
    acl = {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects, "policies": policies}
    config.insert_json5("access_control", json.dumps(acl))


def _cause(exc: Exception) -> str:
    # Zenoh's messages end with the Rust source location, which helps nobody here.
    return re.sub(r"\s+at /\S+\.rs:\d+\.?", "", str(exc)).strip()


class Bus:
    """One Zenoh session, opened from `BusSettings`.

    A session in peer or router mode with no listen endpoint listens on a free loopback port (tls/
    with a certificate in `settings.tls`), so a plain run reaches nothing beyond this machine;
    `endpoints` tells where others connect. TLS and access control: hub/bus/tls.py, hub/bus/README.md.
    Gossip and multicast scouting stay off unless `scouting` is on: participants reach the hub
    at its endpoints, never each other.
    """

    def __init__(self, settings: BusSettings, *, listen: bool = True):
        self.settings = settings
        tls = settings.tls
        listening = listen and settings.mode != "client"
        wrong = tls_problems(tls, settings.listen, settings.connect, listening=listening, control=settings.control)
        if wrong:
            raise BusError("cannot open the bus: " + "; ".join(
                f"{format_path(('run', 'bus') + place)}: {message}" for place, message in wrong))
        listen_on = list(settings.listen)
        if listening and not listen_on:
            free = free_loopback_endpoint()
            listen_on = [free.replace("tcp/", "tls/", 1) if tls and tls.certificate else free]
        self.endpoints = tuple(listen_on)
        config = zenoh.Config()
        try:
            config.insert_json5("mode", json.dumps(settings.mode))
            config.insert_json5("listen/endpoints", json.dumps(listen_on if settings.mode != "client" else []))
            config.insert_json5("connect/endpoints", json.dumps(list(settings.connect)))
            config.insert_json5("scouting/multicast/enabled", json.dumps(settings.scouting))
            config.insert_json5("scouting/gossip/enabled", json.dumps(settings.scouting))
            # Zenoh's lease is how long the *other* side waits for our keep-alives: it bounds
            # how soon a frozen process is declared gone.
            config.insert_json5("transport/link/tx/lease", str(max(1, round(settings.lease * 1000))))
            if tls is not None:
                _configure_tls(config, tls)
            if settings.control is not None:
                _configure_access(config, settings.control, settings.watch, tls, settings.instructor)
            zenoh_log.start()
            self._session = zenoh.open(config)
        except zenoh.ZError as exc:
            where = ", ".join([f"listen on {e}" for e in listen_on] + [f"connect to {e}" for e in settings.connect])
            raise BusError(f"cannot open the bus ({settings.mode}{'; ' + where if where else ''}): "
                           f"{_cause(exc)}{self._refusals(settings)}") from None
        if tls is not None and settings.connect and not self._connected():
            # A refused handshake only shows in Zenoh's log, and the session would keep trying
            # until its owner's join timeout: ask once why, and stop with the answer at once.
            # (Nothing listening there yet is no refusal: the hub may still be starting.)
            refusals = self._refusals(settings)
            if refusals:
                self._session.close()
                raise BusError(f"cannot join over TLS{refusals}")
        self._entities: list = []
        self._lock = threading.Lock()
        _open.add(self)

    @staticmethod
    def _refusals(settings: BusSettings) -> str:
        if settings.tls is None:
            return ""
        found = [(e, tls_refused(e, settings.tls)) for e in settings.connect]
        return "".join(f"; {e} refused the handshake: {why}" for e, why in found if why)

    def _connected(self) -> bool:
        info = self._session.info
        return bool(list(info.peers_zid()) or list(info.routers_zid()))

    # --- publishing --------------------------------------------------------------------
    def publisher(self, key: str, encoding: str, *, lossy: bool = False, express: bool = True) -> Publisher:
        """A publisher on `key`. `lossy`: drop samples rather than block when a reader lags
        (the data plane); otherwise block (lockstep and control messages must arrive)."""
        congestion = zenoh.CongestionControl.DROP if lossy else zenoh.CongestionControl.BLOCK
        pub = self._declare(lambda: self._session.declare_publisher(
            key, encoding=zenoh.Encoding(encoding), congestion_control=congestion, express=express), key)
        return Publisher(self, pub, key)

    def put(self, key: str, payload: bytes, encoding: str) -> None:
        """One message (a command, a hello, a rate request): blocks rather than drops when congested."""
        self._session.put(key, payload, encoding=zenoh.Encoding(encoding),
                          congestion_control=zenoh.CongestionControl.BLOCK)

    # --- receiving ---------------------------------------------------------------------
    def subscribe(self, key: str, deliver) -> None:
        """Call `deliver(Message)` for every sample on `key` (from a Zenoh thread: keep it to a queue put)."""
        self._declare(lambda: self._session.declare_subscriber(key, lambda s: deliver(_message(s))), key)

    def subscribe_payloads(self, key: str, deliver) -> None:
        """Call `deliver(payload bytes)` for every sample on `key`: the fast path of lockstep outputs."""
        self._declare(lambda: self._session.declare_subscriber(key, lambda s: deliver(s.payload.to_bytes())), key)

    # --- queries -----------------------------------------------------------------------
    def answer(self, key: str, reply, encoding: str) -> None:
        """Answer every query on `key` with the bytes `reply()` gives at that moment (the scene
        document: a late joiner asks for it at any time). Runs in a Zenoh thread: `reply` must be
        cheap and must not wait (it returns bytes made already)."""
        def respond(query):
            try:
                query.reply(key, reply(), encoding=zenoh.Encoding(encoding))
            except zenoh.ZError:
                pass   # the asker went away
        self._declare(lambda: self._session.declare_queryable(key, respond), key)

    def ask(self, key: str, timeout: float = 2.0) -> Message | None:
        """The first answer to a query on `key` within `timeout` s, or None when nobody answers."""
        with self._lock:
            if self._session is None:
                raise BusError(f"the bus is closed (asking {key})")
            session = self._session
        try:
            replies = session.get(key, timeout=timeout)
            for reply in replies:
                if reply.ok is not None:
                    return _message(reply.ok)
        except zenoh.ZError as exc:
            raise BusError(f"cannot ask {key}: {_cause(exc)}") from None
        return None

    # --- liveliness --------------------------------------------------------------------
    def declare_token(self, key: str) -> Token:
        """A liveliness token: alive while this session is, gone at once when the process dies."""
        return Token(self._declare(lambda: self._session.liveliness().declare_token(key), key))

    def watch_tokens(self, key: str, deliver, *, history: bool = True) -> None:
        """Call `deliver(Message)` when a token matching `key` appears (alive) or goes away (not alive);
        with `history`, tokens that exist already are reported first."""
        self._declare(lambda: self._session.liveliness().declare_subscriber(
            key, lambda s: deliver(_message(s)), history=history), key)

    # --- life cycle ----------------------------------------------------------------------
    def _declare(self, make, key: str):
        with self._lock:
            if self._session is None:
                raise BusError(f"the bus is closed (declaring {key})")
            try:
                entity = make()
            except zenoh.ZError as exc:
                raise BusError(f"cannot declare {key}: {_cause(exc)}") from None
            self._entities.append(entity)
            return entity

    @property
    def closed(self) -> bool:
        return self._session is None

    def close(self) -> None:
        """Undeclare everything and close the session (idempotent). Callbacks stop before it returns."""
        with self._lock:
            session, self._session = self._session, None
            entities, self._entities = self._entities, []
        if session is None:
            return
        for entity in reversed(entities):
            try:
                entity.undeclare()
            except zenoh.ZError:
                pass   # already gone with its session
        session.close()
        _open.discard(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Publisher:
    """A declared publisher; `matching` tells whether any subscriber reads its key right now."""

    __slots__ = ("_bus", "_pub", "key", "put")

    def __init__(self, bus: Bus, pub, key: str):
        self._bus = bus
        self._pub = pub
        self.key = key
        self.put = pub.put   # put(payload, attachment=None): the hot path, no wrapper call

    @property
    def matching(self) -> bool:
        return self._pub.matching_status.matching

    def matching_changes(self) -> MatchingChanges:
        """Whether subscribers came or went, kept in Zenoh's own queue until asked: no Python runs in
        Zenoh's threads. Measured in the bottling plant: a callback listener on each of 615 publishers
        made the first viewer's arrival 615 callbacks, each waiting up to 5 ms for the GIL of a loop
        stepping pybullet, and the first puts to that viewer waited on them."""
        return MatchingChanges(self._bus._declare(
            lambda: self._pub.declare_matching_listener(zenoh.handlers.RingChannel(4)), self.key))


class MatchingChanges:
    """A publisher's matching status changes, polled (60–90 µs for 615 of them, none pending)."""

    __slots__ = ("_listener",)

    def __init__(self, listener):
        self._listener = listener

    def latest(self) -> bool | None:
        """The last status reported since the previous call, or None when nothing changed."""
        status, latest = self._listener.try_recv(), None
        while status is not None:
            latest, status = status.matching, self._listener.try_recv()
        return latest


class Token:
    __slots__ = ("_token",)

    def __init__(self, token):
        self._token = token

    def undeclare(self) -> None:
        try:
            self._token.undeclare()
        except zenoh.ZError:
            pass


def _message(sample) -> Message:
    attachment = sample.attachment
    return Message(str(sample.key_expr), sample.payload.to_bytes(), str(sample.encoding),
                   attachment.to_bytes() if attachment is not None else None,
                   sample.kind == zenoh.SampleKind.PUT)


def key_intersects(a: str, b: str) -> bool:
    """Whether two key expressions share a key (Zenoh's rules, `*`, `**`, `$*`)."""
    try:
        return zenoh.KeyExpr(a).intersects(zenoh.KeyExpr(b))
    except zenoh.ZError as exc:
        raise BusError(f"not a key expression: {a!r} or {b!r}: {_cause(exc)}") from None


# A session with a callback subscriber that is never closed keeps the interpreter from exiting:
# whatever a caller forgot is closed at exit.
_open: weakref.WeakSet[Bus] = weakref.WeakSet()


@atexit.register
def _close_all() -> None:
    for bus in list(_open):
        bus.close()


def wait_until(condition, timeout: float, poll: float = 0.01) -> bool:
    """Poll `condition()` until it holds or `timeout` passes (for setup waits, never for stepping)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() >= deadline:
            return False
        time.sleep(poll)
    return True
