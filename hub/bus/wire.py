"""The wire format of the bus (schemas/wire.md): key expressions, slot value codecs, control messages."""
from __future__ import annotations

import hmac
import re
import struct

import msgpack

from hub.core.errors import PlanthubError
from hub.core.slots import SlotRef, SlotType

PROTOCOL = 1
MSGPACK = "application/msgpack"          # Zenoh encoding of every control message
AGENT = "planthub-python/0.1"
#: The largest control message or data-plane sample decoded, bytes: a step of the bottling plant's
#: router is under 200 bytes; anything near this is a mistake or an attack, and is refused unread.
MAX_MESSAGE = 1 << 20
#: The largest save answer or restore request: they carry a participant's whole state, which may
#: outgrow a step by far; they are sealed, so a stranger cannot make the hub read one this big.
MAX_STATE = 1 << 26


class WireError(PlanthubError):
    """A message on the bus does not follow the wire format; the message says which part."""


# --- key expressions ---------------------------------------------------------------------
_CHUNK = re.compile(r"^[^/*$?#@]+$")


def check_run_name(run: str) -> str:
    """A run name is one key chunk: no `/`, `*`, `$`, `?`, `#` or `@`."""
    if not isinstance(run, str) or not _CHUNK.match(run):
        raise WireError(f"run name {run!r} cannot be a Zenoh key chunk (no / * $ ? # @, not empty)")
    return run


def data_key(run: str, ref: SlotRef) -> str:
    """Data plane: `plant/<run>/<object>/<component>/<slot>`."""
    return f"plant/{run}/{ref.obj}/{ref.component}/{ref.slot}"


def control_key(run: str, *parts: str) -> str:
    """Control plane, under the verbatim chunk `@cosim` (so `plant/**` never matches it)."""
    return "/".join(("plant", run, "@cosim") + parts)


def instructor_key(run: str, *parts: str) -> str:
    """The instructor's plane, under its own verbatim chunk `@instructor`: neither `plant/**` nor a
    controller's `plant/*/@cosim/**` matches it, so under access control only the names in
    run.bus.access.instructor reach it (faults: injecting them, and seeing them)."""
    return "/".join(("plant", run, "@instructor") + parts)


def hub_token(run: str) -> str:
    return control_key(run, "hub")


def logic_key(run: str, name: str, *parts: str) -> str:
    """Keys of one lockstep participant: its liveliness token, hello, welcome, step, output,
    checkpoint (save and restore requests) and checkpoint_answer."""
    return control_key(run, "logic", name, *parts)


# --- data plane: one slot value, raw little-endian ------------------------------------------
_STRUCTS = {
    SlotType.BOOL: struct.Struct("<?"),
    SlotType.INT: struct.Struct("<q"),
    SlotType.REAL: struct.Struct("<d"),
    SlotType.VEC3: struct.Struct("<3d"),
    SlotType.QUAT: struct.Struct("<4d"),
}
TICK = struct.Struct("<Q")   # the attachment of a data-plane sample: the tick of its communication point


def value_encoding(kind: SlotType) -> str:
    """Zenoh encoding of a data-plane sample of this slot type."""
    return f"zenoh/bytes;planthub/{kind.value}"


def value_packer(kind: SlotType):
    """A function value → bytes for this slot type (void: empty, string: UTF-8, others: struct)."""
    if kind is SlotType.VOID:
        return lambda value: b""
    if kind is SlotType.STRING:
        return lambda value: value.encode("utf-8")
    s = _STRUCTS[kind]
    return (lambda value: s.pack(*value)) if kind in (SlotType.VEC3, SlotType.QUAT) else s.pack


def unpack_value(kind: SlotType, data: bytes):
    """The canonical Python value of a data-plane payload (None for void); WireError if it is not one."""
    if len(data) > MAX_MESSAGE:
        raise WireError(f"a {kind.value} sample of {len(data)} bytes (at most {MAX_MESSAGE})")
    if kind is SlotType.VOID:
        return None
    if kind is SlotType.STRING:
        try:
            return bytes(data).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise WireError(f"a string sample that is not UTF-8 ({exc.reason} at byte {exc.start})") from None
    s = _STRUCTS[kind]
    if len(data) != s.size:
        raise WireError(f"a {kind.value} sample is {s.size} bytes, this one {len(data)}")
    values = s.unpack(data)
    return values if kind in (SlotType.VEC3, SlotType.QUAT) else values[0]


# --- control plane: msgpack ------------------------------------------------------------
def pack(message) -> bytes:
    return msgpack.packb(message, use_bin_type=True)


def unpack(data: bytes, limit: int = MAX_MESSAGE):
    """A control message; WireError for anything that is not one msgpack value of at most `limit` bytes."""
    if len(data) > limit:
        raise WireError(f"a message of {len(data)} bytes (at most {limit})")
    try:
        return msgpack.unpackb(data, raw=False, strict_map_key=False)
    except Exception as exc:   # msgpack raises several types for bad input
        raise WireError(f"not a msgpack message ({exc})") from None


def to_wire(kind: SlotType, value):
    """A slot value as it travels in step and output messages (void: whether it fired)."""
    if kind in (SlotType.VEC3, SlotType.QUAT):
        return list(value)
    return value


def reader(kind: SlotType):
    """A fast function wire value → canonical slot value for this type; it raises WireError (without
    context: the caller names the slot) for a value that does not fit."""
    def check(value):
        return from_wire(kind, value, "value")
    if kind in (SlotType.VOID, SlotType.BOOL):
        return lambda value: value if value is True or value is False else check(value)
    if kind is SlotType.REAL:
        return lambda value: value if type(value) is float else check(value)
    if kind is SlotType.INT:
        return lambda value: value if type(value) is int and -2**63 <= value < 2**63 else check(value)
    if kind is SlotType.STRING:
        return lambda value: value if type(value) is str else check(value)
    return check


_PYTHON_TYPES = {SlotType.VOID: bool, SlotType.BOOL: bool, SlotType.INT: int, SlotType.REAL: float,
                 SlotType.STRING: str}


def python_types(kinds) -> tuple | None:
    """The Python types msgpack gives for values of these slot types that need no conversion
    (`reader` returns them as they are), or None if one of them always does (vec3, quat)."""
    types = tuple(_PYTHON_TYPES.get(kind) for kind in kinds)
    return None if None in types else types


def from_wire(kind: SlotType, value, what: str):
    """The canonical slot value of a value received in a message; WireError names `what` if it does not fit."""
    if kind in (SlotType.VOID, SlotType.BOOL):
        if isinstance(value, bool):
            return value
    elif kind is SlotType.INT:
        if isinstance(value, int) and not isinstance(value, bool) and -2**63 <= value < 2**63:
            return value
    elif kind is SlotType.REAL:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)   # exact for a float64; an integer is taken as its double
    elif kind is SlotType.STRING:
        if isinstance(value, str):
            return value
    else:
        n = 3 if kind is SlotType.VEC3 else 4
        if isinstance(value, (list, tuple)) and len(value) == n and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in value):
            return tuple(float(x) for x in value)
    expected = "true or false" if kind is SlotType.VOID else f"a {kind.value}"
    raise WireError(f"{what}: expected {expected}, got {value!r}")


def interface(pairs) -> list[list[str]]:
    """[(slot name, SlotType)] → the `inputs`/`outputs` list of a hello message."""
    return [[name, kind.value] for name, kind in pairs]


_TYPE_NAMES = frozenset(t.value for t in SlotType)


def read_interface(entries, what: str) -> list[tuple[str, SlotType]]:
    if not isinstance(entries, list):
        raise WireError(f"{what}: expected a list of [name, type] pairs, got {entries!r}")
    out = []
    for entry in entries:
        if not (isinstance(entry, list) and len(entry) == 2 and isinstance(entry[0], str)
                and isinstance(entry[1], str) and entry[1] in _TYPE_NAMES):
            raise WireError(f"{what}: expected [name, type] with type one of "
                            f"{', '.join(t.value for t in SlotType)}, got {entry!r}")
        out.append((entry[0], SlotType(entry[1])))
    return out


_hot = msgpack.Packer()   # step and output messages: packed on one thread (the hub's or a participant's main)


def step_message(n: int, tick: int, ticks: int, t: float, h: float, inputs: list) -> bytes:
    """Hub → participant: step `n` over [t, t + h] = ticks [tick, tick + ticks], with its inputs
    (a tuple packs as an array, so vec3 and quat values need no conversion)."""
    return _hot.pack([n, tick, ticks, t, h, inputs])


def read_step(data: bytes):
    message = unpack(data)
    if not (isinstance(message, list) and len(message) == 6 and isinstance(message[5], list)
            and all(type(x) is int for x in message[:3]) and all(isinstance(x, (int, float)) for x in message[3:5])):
        raise WireError(f"step message: expected [n, tick, ticks, t, h, inputs], got {message!r}")
    return message


def output_message(n: int, outputs: list) -> bytes:
    """Participant → hub: the outputs after step `n` (n = -1: the initial outputs, before any step)."""
    return _hot.pack([n, outputs])


# --- sealed lockstep messages: the hub and each participant share a key ------------------------
SEAL = 16   # bytes of HMAC-SHA256 before the message


def seal(key: bytes | None, body: bytes) -> bytes:
    """The message as it goes between the hub and a participant (None: unsealed, a joiner without `key`):
    the first 16 bytes of HMAC-SHA256(key, body), then the body. Another process on the bus may
    read it, but cannot make one that opens."""
    return body if key is None else hmac.digest(key, body, "sha256")[:SEAL] + body


def unseal(key: bytes | None, payload: bytes) -> bytes:
    """The body of a sealed message; WireError if it was not sealed with `key`."""
    if key is None:
        return payload
    body = payload[SEAL:]
    if len(payload) < SEAL or not hmac.compare_digest(hmac.digest(key, body, "sha256")[:SEAL], payload[:SEAL]):
        raise WireError("not sealed with this participant's key: another process's message")
    return body


# A participant that joins by itself has no token: it agrees on its seal key with the hub in the
# hello and the welcome, each carrying an ephemeral X25519 public key (schemas/wire.md, item 7).
# `cryptography` is imported only here, when a joiner joins: `import hub.participant` stays light.
PUBLIC_KEY = 32                   # bytes of an X25519 public key, as `key` carries it (msgpack bin)
SEAL_INFO = b"planthub seal 1"    # HKDF info: this, then the run's name, the participant's and the hello's id


def _what(value) -> str:
    """A value's kind in msgpack's words, for a message about it."""
    if isinstance(value, (bytes, bytearray)):
        return f"{len(value)} bytes"
    return {bool: "a boolean", int: "an integer", float: "a float", str: "a string", list: "an array",
            dict: "a map", type(None): "nil"}.get(type(value), type(value).__name__)


def read_public_key(value, what: str = "`key`") -> bytes:
    """The 32 raw bytes of an X25519 public key in a hello or a welcome; WireError for anything else."""
    if not isinstance(value, (bytes, bytearray)) or len(value) != PUBLIC_KEY:
        raise WireError(f"{what} must be an X25519 public key: {PUBLIC_KEY} raw bytes (msgpack bin), "
                        f"got {_what(value)}")
    return bytes(value)


def key_pair():
    """A fresh ephemeral X25519 key pair: (private key, its public key's 32 raw bytes)."""
    from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PrivateKey

    private = X25519PrivateKey.generate()
    return private, private.public_key().public_bytes_raw()


def seal_key(private, public: bytes, run: str, name: str, ident: str) -> bytes:
    """The key that seals a joiner's steps and outputs: HKDF-SHA256 (no salt) of the X25519 secret
    shared by `private` and the other side's `public`, info = SEAL_INFO + run + name + the hello's
    id (UTF-8), 32 bytes. WireError if `public` gives no secret (a low-order point)."""
    from cryptography.hazmat.primitives import hashes
    from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PublicKey
    from cryptography.hazmat.primitives.kdf.hkdf import HKDF

    try:
        shared = private.exchange(X25519PublicKey.from_public_bytes(public))
    except ValueError:
        raise WireError("`key` is not a usable X25519 public key (it gives no shared secret)") from None
    info = SEAL_INFO + run.encode("utf-8") + name.encode("utf-8") + ident.encode("utf-8")
    return HKDF(algorithm=hashes.SHA256(), length=32, salt=None, info=info).derive(shared)


def error_message(n: int, error: str, trace: str = "") -> bytes:
    """Participant → hub, instead of outputs: step `n` failed (`error` one line, `trace` where)."""
    return pack({"step": n, "error": error, **({"traceback": trace} if trace else {})})


# --- save and restore: a participant's whole state at a communication point (schemas/wire.md) ------
CHECKPOINT_OPS = ("save", "restore")


def save_request(tag: int, step: int) -> bytes:
    """Hub → participant: give your whole state as it is after step `step` (-1: before any step).
    `tag` is new for every request; the answer carries it back."""
    return pack({"op": "save", "tag": tag, "step": step})


def restore_request(tag: int, step: int, state: bytes) -> bytes:
    """Hub → participant: put back `state` (bytes a save gave); the next step is `step` + 1."""
    return pack({"op": "restore", "tag": tag, "step": step, "state": state})


def read_checkpoint(data: bytes) -> dict:
    """A save or restore request (a participant reads it); WireError for anything else."""
    message = unpack(data, MAX_STATE)
    if not (isinstance(message, dict) and message.get("op") in CHECKPOINT_OPS
            and type(message.get("tag")) is int and type(message.get("step")) is int and message["step"] >= -1):
        raise WireError(f"checkpoint message: expected {{op: save or restore, tag, step}}, got {_brief(message)}")
    if message["op"] == "restore" and not isinstance(message.get("state"), (bytes, bytearray)):
        raise WireError(f"restore message: `state` must be raw bytes (msgpack bin), got {_what(message.get('state'))}")
    return message


def saved_answer(tag: int, step: int, state: bytes) -> bytes:
    """Participant → hub: its state after step `step`, opaque bytes only it reads back."""
    return pack({"op": "save", "tag": tag, "step": step, "state": state})


def restored_answer(tag: int, step: int) -> bytes:
    """Participant → hub: the state of the restore request `tag` is back in place."""
    return pack({"op": "restore", "tag": tag, "step": step, "ok": True})


def checkpoint_error(op: str, tag: int, step: int, error: str, trace: str = "") -> bytes:
    """Participant → hub, instead of the answer: the save or restore failed (`error` says why)."""
    return pack({"op": op, "tag": tag, "step": step, "error": error, **({"traceback": trace} if trace else {})})


def read_checkpoint_answer(data: bytes) -> dict:
    """A participant's answer to a save or restore request (the hub reads it); WireError for anything
    that is not one: a save answer has `state` (bin), a restore answer `ok` true, either may have
    `error` (a string) instead."""
    message = unpack(data, MAX_STATE)
    if not (isinstance(message, dict) and message.get("op") in CHECKPOINT_OPS and type(message.get("tag")) is int
            and type(message.get("step")) is int):
        raise WireError(f"checkpoint answer: expected {{op, tag, step, state | ok | error}}, got {_brief(message)}")
    if "error" in message:
        if not isinstance(message["error"], str):
            raise WireError(f"checkpoint answer: `error` must be a string, got {_what(message['error'])}")
    elif message["op"] == "save" and not isinstance(message.get("state"), (bytes, bytearray)):
        raise WireError(f"save answer: `state` must be raw bytes (msgpack bin), got {_what(message.get('state'))}")
    elif message["op"] == "restore" and message.get("ok") is not True:
        raise WireError(f"restore answer: expected `ok`: true or an `error`, got {_brief(message)}")
    return message


def _brief(value) -> str:
    """A received value for a message: its repr, cut short (a state may be megabytes)."""
    text = repr(value)
    return text if len(text) <= 200 else text[:200] + "…"
