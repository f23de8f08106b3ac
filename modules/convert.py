"""Convert: a value passed on as another slot type or scale — int ↔ real, bool → number, a threshold, PLC analogue scaling.

`from` and `to` are each `bool`, `int` or `real`:

| from → to          | rule                                                                         |
|--------------------|------------------------------------------------------------------------------|
| int → real         | the same number (beyond 2^53 the nearest double)                             |
| real → int         | rounded by `round` (below)                                                    |
| bool → int, real   | false → `levels[0]`, true → `levels[1]` (default 0 and 1)                    |
| int → bool         | true for any value but 0                                                     |
| real → bool        | true once above `threshold`, false again at or below `threshold − hysteresis`; in between it keeps its state (false before the first value); `hysteresis` 0 (the default) is a plain `>` |
| int, real → int, real | with `scale: {from: [a, b], to: [c, d]}`: a → c, b → d, linear in between |

**Scaling** is the PLC's analogue I/O: `scale: {from: [0, 27648], to: [0.0, 0.5]}` turns raw counts
into m/s, and the other way round for an output card (`from: real, to: int`, the ranges swapped).
It is computed as c·(1 − s) + d·s with s = (x − a)/(b − a), so a and b give c and d exactly. It
composes with the type change: an int result is rounded after scaling. A value outside a … b is
taken by `out_of_range`: `clamp` (the default) passes the nearest end on, as an input card's
range limit does; `stop` ends the run naming the object, the value, the range and the time.
**Rounding** to int (`round`): `nearest` (the default, ties away from zero: 2.5 → 3, −2.5 → −3),
`half_even` (2.5 → 2, 3.5 → 4), `down` (floor), `up` (ceiling), `toward_zero` (truncate). A
result beyond a 64-bit int slot stops the run, naming it.

Every value is checked where it enters: a real on `in` that is not finite stops the run naming
the slot, the value and the time. The output follows the input within the same step (zero delay,
like `constant` and `connector`): an FMU's counter read at a communication point reaches the belt
at that point, and a ring through converters is a zero-delay loop that the scenario check rejects.
Before anything fed `in`, `value.out` holds the conversion of the input type's zero (clamped into
the scale), so a flow with `when: target` pulls a value at once. Parameters that make no sense
together — a threshold for int → real, a scale of zero width, `from` equal to `to` with no scale
— are reported at load, each at its line.
"""
from __future__ import annotations

import math
from collections.abc import Callable

from hub.core import state
from hub.core.component import Component
from hub.core.errors import SimulationError
from hub.core.module import Module
from hub.core.slots import INT_RANGE, Slot, SlotFamily, SlotType

TYPES = ("bool", "int", "real")
RANGE = {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}


def _nearest(x: float) -> int:
    whole = math.trunc(x)
    # x − trunc(x) is exact for every double, so a tie is seen as a tie (floor(x + 0.5) is not:
    # 0.49999999999999994 + 0.5 rounds up to 1.0).
    if abs(x - whole) >= 0.5:
        whole += 1 if x > 0 else -1
    return whole


ROUNDING: dict[str, Callable[[float], int]] = {
    "nearest": _nearest,
    "half_even": round,
    "down": math.floor,
    "up": math.ceil,
    "toward_zero": math.trunc,
}


class Threshold:
    """real → bool with a hysteresis band below the threshold; remembers its state."""

    STATE = ("state",)

    def __init__(self, threshold: float, hysteresis: float):
        self.on_above = threshold
        self.off_at = threshold - hysteresis
        self.state = False

    def __call__(self, x: float) -> bool:
        if x > self.on_above:
            self.state = True
        elif x <= self.off_at:
            self.state = False
        return self.state


def conversion(params: dict, clamp_always: bool = False) -> Callable:
    """The function from an input value to an output value; ValueError names what it cannot pass on."""
    source, target = params["from"], params["to"]
    if source == "bool":
        low, high = params.get("levels", [0, 1])
        low, high = (float(low), float(high)) if target == "real" else (int(low), int(high))
        return lambda x: high if x else low
    if target == "bool":
        if source == "int":
            return lambda x: x != 0
        return Threshold(float(params["threshold"]), float(params.get("hysteresis", 0.0)))
    steps = [_scaling(params, clamp_always)] if "scale" in params else []
    if target == "int":
        steps.append(_rounding(ROUNDING[params.get("round", "nearest")]))
    elif source == "int":
        steps.append(float)

    def convert(x):
        for step in steps:
            x = step(x)
        return x
    return convert


def _scaling(params: dict, clamp_always: bool) -> Callable:
    (a, b), (c, d) = params["scale"]["from"], params["scale"]["to"]
    lo, hi = min(a, b), max(a, b)
    clamp = clamp_always or params.get("out_of_range", "clamp") == "clamp"
    width = b - a

    def scale(x):
        if x < lo or x > hi:
            if not clamp:
                raise ValueError(f"{x!r} is outside scale.from {a} … {b} (out_of_range: stop)")
            x = lo if x < lo else hi
        s = (x - a) / width
        return c * (1.0 - s) + d * s
    return scale


def _rounding(rule: Callable[[float], int]) -> Callable:
    def to_int(x):
        n = rule(x)
        if not INT_RANGE[0] <= n <= INT_RANGE[1]:
            raise ValueError(f"{x!r} rounds to {n}, beyond a 64-bit int slot")
        return n
    return to_int


class Converter(Component):
    FEEDTHROUGH = (("in", "out"),)

    STATE = ("tick", "convert")   # hub/core/state.py; `convert` keeps state only as a Threshold (save_state)

    def __init__(self, obj, name, slots, convert, start, real_input: bool, rate: int):
        super().__init__(obj, name)
        self.SLOTS = slots
        self.convert = convert
        self.start = start
        self.real_input = real_input
        self.rate = rate
        self.tick = 0

    def bind(self, signals, index, needed):
        super().bind(signals, index, needed)
        signals.values[index["out"]] = self.start

    def save_state(self) -> dict:
        threshold = self.convert if isinstance(self.convert, Threshold) else None
        return {"tick": self.tick, "threshold": None if threshold is None else state.save(threshold)}

    def restore_state(self, saved: dict) -> None:
        self.tick = saved["tick"]
        if saved["threshold"] is not None:
            state.restore(self.convert, saved["threshold"], f"{self.obj}.{self.name}")

    def sense(self, tick):
        self.tick = tick   # react() gets no clock; its errors name the point they happened at

    def react(self):
        if not self.updated("in"):
            return
        x = self.value("in")
        if self.real_input and x - x != 0.0:   # NaN and ±inf, in one subtraction
            self._stop(f"got {x!r}; every value entering the plant must be finite")
        try:
            self.emit("out", self.convert(x))
        except ValueError as exc:
            self._stop(str(exc))

    def _stop(self, what: str):
        raise SimulationError(f"{self.obj}.{self.name}.in: {what}, so the run stops here "
                              f"(at t = {self.tick / self.rate:.9g} s, tick {self.tick})")


class Convert(Module):
    """A value passed on as another slot type or scale, within the same step."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "from": {"enum": list(TYPES), "description": "slot type of value.in"},
            "to": {"enum": list(TYPES), "description": "slot type of value.out"},
            "scale": {"type": "object",
                      "properties": {"from": {**RANGE, "description": "input range [a, b] (raw counts, say)"},
                                     "to": {**RANGE, "description": "output range [c, d]: a → c, b → d"}},
                      "required": ["from", "to"], "additionalProperties": False,
                      "description": "linear scaling of int or real values"},
            "out_of_range": {"enum": ["clamp", "stop"],
                             "description": "an input outside scale.from: clamp to its nearest end (default), "
                                            "or stop the run naming it"},
            "round": {"enum": list(ROUNDING),
                      "description": "to int: nearest (default, ties away from zero), half_even, down, up, "
                                     "toward_zero"},
            "threshold": {"type": "number", "description": "real → bool: true above it"},
            "hysteresis": {"type": "number", "minimum": 0,
                           "description": "real → bool: false again only at or below threshold − hysteresis "
                                          "(default 0)"},
            "levels": {**RANGE, "description": "bool → int or real: the values of false and true (default [0, 1])"},
        },
        "required": ["from", "to"],
        "additionalProperties": False,
    }
    COMPONENTS = {"value": Converter}
    SLOT_FAMILIES = {"value": (
        SlotFamily.target("in", "param `from`", "the value to convert"),
        SlotFamily.source("out", "param `to`", "the converted value; active in the steps a flow fed `in`"))}

    @classmethod
    def slots(cls, params):
        given, made = cls.SLOT_FAMILIES["value"]
        return {"value": (Slot.target("in", params.get("from", "real"), given.doc),
                          Slot.source("out", params.get("to", "real"), made.doc))}

    @classmethod
    def check(cls, params) -> list[tuple[tuple, str]]:
        source, target = params["from"], params["to"]
        way = f"{source} → {target}"
        problems = []
        if "scale" in params:
            if "bool" in (source, target):
                problems.append((("scale",), f"{way}: a bool has no range to scale; bool → int or real "
                                             "takes `levels`, real → bool a `threshold`"))
            else:
                for end in ("from", "to"):
                    low, high = params["scale"][end]
                    if low == high:
                        problems.append((("scale", end), f"a range of zero width ({low} … {high}): "
                                         + ("no slope maps it" if end == "from" else f"every value would give {low}")))
        elif source == target:
            problems.append((("to",), f"from and to are both {source} and there is no scale: nothing to convert "
                                      "(connect the slots directly)"))
        if "out_of_range" in params and "scale" not in params:
            problems.append((("out_of_range",), "out_of_range is for a scale, and there is none"))
        if "round" in params and (target != "int" or source == "bool"):
            problems.append((("round",), f"round is for a number converted to int, not {way}"))
        thresholded = (source, target) == ("real", "bool")
        if "threshold" in params and not thresholded:
            problems.append((("threshold",), f"a threshold is for real → bool, not {way}"
                             + (" (int → bool is true for any value but 0)" if source == "int" and target == "bool" else "")))
        if "hysteresis" in params and not thresholded:
            problems.append((("hysteresis",), f"hysteresis goes with a threshold, for real → bool, not {way}"))
        if thresholded and "threshold" not in params:
            problems.append(((), "real → bool needs a threshold: true above it"))
        if "levels" in params:
            if source != "bool":
                problems.append((("levels",), f"levels are the values of false and true, for bool → int or real, "
                                              f"not {way}"))
            elif target == "int" and not all(isinstance(v, int) or float(v).is_integer() for v in params["levels"]):
                problems.append((("levels",), f"bool → int needs whole numbers, got {params['levels']}"))
        return problems

    @classmethod
    def build(cls, name, params, world):
        slots = cls.slots(params)["value"]
        start = conversion(params, clamp_always=True)(SlotType(params["from"]).initial())
        return {"value": Converter(name, "value", slots, conversion(params), start, params["from"] == "real",
                               world.rate)}
