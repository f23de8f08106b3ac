"""The WebSocket protocol between the view and a browser (`/ws`): what a browser may send, checked,
and the JSON text frames the view sends.

view → browser, text frames, JSON objects with `type`: `hello` first (`run`, `viewer`, `control`
and the `reason` when it is false; `mode: "playback"` and the recording's span for a run folder),
`scene` (the scene document, schemas/scene.schema.json), `state`, `figures`, `events` (`rows`),
`result` (a command's answer, with the `op`, `slot` and `ref` it was sent with), `slots` (live
values of the belts' velocities), `hub` (`alive`), `checkpoints` (the ticks a rewind may go back
to, the hub's `checkpoints` message as it came: `tick`, `time`, `rate`, `checkpoints`;
schemas/wire.schema.json `checkpoints`), `error`, and for playback `playback` and
`recording`; to an instructor's page only, `faults` (the board, schemas/scene.schema.json
`faults_message`) — hello's `role` says which page it is (`instructor`, `trainee`, with the
`role_reason` a trainee's is one). Binary frames: the bodies message exactly as it came from the bus
(schemas/scene.schema.json `bodies_message`). browser → view: `{"type": "command", "op", "slot",
"value", "ref"}` (`fault`: slot `object.component`, value a map with the fault's `name`, `kind`, its
parameters and an optional `for` in s; `repair`: value `{"name"}`; `rewind`: value the tick to go
back to), `{"type": "rate", "period"}`, and for playback `{"type": "playback", "op":
play|pause|speed|seek, "value"}`.

A browser's frame that is not one of these gets an error frame back naming what is wrong; the
view goes on. Commands and rate requests go to a live run; playback requests to a recorded one's
playback (hub/view/playback.py). The hub checks a command's slot and value again
(hub/bus/commands.py), with its did-you-mean: here only the shape is checked, so that nothing
malformed goes on the bus.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass

from hub.bus.commands import MAX_NAME
from hub.core.errors import PlanthubError
from hub.core.numbers import is_number

#: the operator commands a browser may send; those that name a slot, and those that carry a value
OPS = ("set", "force", "release", "stop", "pause", "resume", "step", "pace", "rewind", "fault", "repair")
FAULT_OPS = ("fault", "repair")   # an instructor's only (hub/view/server.py refuses them from a trainee's page)
SLOT_OPS = ("set", "force", "release")
#: the largest text frame a browser may send, bytes (a command is under 200)
MAX_FRAME = 64 * 1024
MAX_REF = 64          # characters of the browser's own id for a command, echoed in its result
MAX_STEP = 100_000    # points a single step command may ask for
MAX_PERIOD = 3600.0   # s: the slowest bodies rate a browser may ask for
#: what a browser may ask of a recorded run's playback (`planthub view RUN_DIR`), and its speeds
PLAYBACK_OPS = ("play", "pause", "speed", "seek")
SPEEDS = (0.1, 10.0)


class FrameError(PlanthubError):
    """A browser's frame is not one the view takes; the message goes back to it in an error frame."""


@dataclass(frozen=True)
class CommandRequest:
    op: str
    slot: str = ""
    value: object = None
    ref: str = ""       # the browser's own id for it, if it gave one


@dataclass(frozen=True)
class RateRequest:
    period: float | None   # s of plant time between two bodies messages; None: the hub's default


@dataclass(frozen=True)
class PlaybackRequest:
    op: str                # play, pause, speed, seek
    value: float | None = None   # speed: a factor of the recorded pace; seek: a time, s


def parse(text) -> CommandRequest | RateRequest | PlaybackRequest:
    """A browser's text frame → the request it makes, or FrameError."""
    if not isinstance(text, str):
        raise FrameError("expected a JSON text frame (binary frames go only from the view to the browser)")
    if len(text) > MAX_FRAME:
        raise FrameError(f"a frame of {len(text)} characters (at most {MAX_FRAME})")
    try:
        message = json.loads(text, parse_constant=_no_constant)
    except ValueError as exc:
        raise FrameError(f"not JSON: {exc}") from None
    if not isinstance(message, dict):
        raise FrameError(f"expected a JSON object with a type, got {_shown(message)}")
    kind = message.get("type")
    if kind == "command":
        return _command(message)
    if kind == "rate":
        return _rate(message)
    if kind == "playback":
        return _playback(message)
    raise FrameError(f"unknown type {_shown(kind)}: expected command, rate or playback")


def _command(message: dict) -> CommandRequest:
    op = message.get("op")
    if op not in OPS:
        raise FrameError(f"unknown op {_shown(op)}: expected one of {', '.join(OPS)}")
    ref = message.get("ref", "")
    if not isinstance(ref, str) or len(ref) > MAX_REF:
        raise FrameError(f"ref must be a string of at most {MAX_REF} characters, got {_shown(ref)}")
    slot = message.get("slot", "")
    value = message.get("value")
    if op in FAULT_OPS:
        parts = slot.split(".") if isinstance(slot, str) else []
        if (op == "fault" or slot) and (len(parts) != 2 or not all(parts) or len(slot) > MAX_NAME):
            raise FrameError(f"{op} needs the part it acts on, object.component (at most {MAX_NAME} characters), "
                             f"got {_shown(slot)}")
        if not isinstance(value, dict) or not isinstance(value.get("name"), str) or not value["name"]:
            raise FrameError(f"{op} takes a map with the fault's name, got {_shown(value)}")
        return CommandRequest(op, slot or "", value, ref)
    if op in SLOT_OPS:
        parts = slot.split(".") if isinstance(slot, str) else []
        if len(parts) != 3 or not all(parts) or len(slot) > MAX_NAME:
            raise FrameError(f"{op} needs a slot object.component.slot (at most {MAX_NAME} characters), "
                             f"got {_shown(slot)}")
    elif slot not in ("", None):
        raise FrameError(f"{op} takes no slot, got {_shown(slot)}")
    else:
        slot = ""
    if op == "step":
        value = 1 if value is None else value
        if not _integer(value) or not 1 <= value <= MAX_STEP:
            raise FrameError(f"step takes a number of points from 1 to {MAX_STEP}, got {_shown(value)}")
    elif op == "pace":
        if not is_number(value) or not value > 0:
            raise FrameError(f"pace takes a positive factor of real time (1.0, 2.0), got {_shown(value)}")
    elif op == "rewind":
        if not _integer(value) or value < 0:
            raise FrameError(f"rewind takes the tick to go back to (a whole number, 0 or more), got {_shown(value)}")
    elif op in ("release", "stop", "pause", "resume") and value is not None:
        raise FrameError(f"{op} takes no value, got {_shown(value)}")
    return CommandRequest(op, slot, value, ref)


def _rate(message: dict) -> RateRequest:
    period = message.get("period")
    if period is not None and (not is_number(period) or not 0 < period <= MAX_PERIOD):
        raise FrameError(f"rate takes a period in s, more than 0 and at most {MAX_PERIOD:g}, or null; "
                         f"got {_shown(period)}")
    return RateRequest(None if period is None else float(period))


def _playback(message: dict) -> PlaybackRequest:
    op, value = message.get("op"), message.get("value")
    if op not in PLAYBACK_OPS:
        raise FrameError(f"unknown playback op {_shown(op)}: expected one of {', '.join(PLAYBACK_OPS)}")
    if op in ("play", "pause"):
        if value is not None:
            raise FrameError(f"{op} takes no value, got {_shown(value)}")
        return PlaybackRequest(op)
    if op == "speed":
        if not is_number(value) or not SPEEDS[0] <= value <= SPEEDS[1]:
            raise FrameError(f"speed takes a factor of the recorded pace from {SPEEDS[0]:g} to {SPEEDS[1]:g}, "
                             f"got {_shown(value)}")
    elif not is_number(value):
        raise FrameError(f"seek takes a time in s of the recorded run, got {_shown(value)}")
    return PlaybackRequest(op, float(value))


def _integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def _shown(value) -> str:
    """A value for a message, cut to 80 characters (never echo a whole frame back)."""
    text = json.dumps(value) if _jsonable(value) else repr(value)
    return text if len(text) <= 80 else f"{text[:60]}… ({len(text)} characters)"


def _jsonable(value) -> bool:
    try:
        json.dumps(value)
        return True
    except (TypeError, ValueError):
        return False


# --- what the view sends ----------------------------------------------------------------
def frame(kind: str, body: dict | None = None, **fields) -> str:
    """A text frame {"type": kind, …body, …fields}, as JSON a browser's JSON.parse takes: a
    non-finite float is null, bytes are a list of numbers (a map from the hub may hold either)."""
    message = {**(body or {}), **fields, "type": kind}
    return json.dumps(_plain(message), separators=(",", ":"), allow_nan=False)


def _plain(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if value is None or isinstance(value, (str, int, bool)):
        return value
    return str(value)
