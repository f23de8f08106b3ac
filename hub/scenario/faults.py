"""Scheduled faults (`faults:`): what breaks, where, when it starts and when it ends — checked against the plant's slots.

A fault starts at a time (`at: S`), after the n-th occurrence of a void source (`after: {event:
r3.trigger.on_enter, count: 5}`), or at a time drawn from the run's seed within a window
(`between: [S, S]`); it ends after `for: S`, at `until: S` (a time, not with `after`), or never.
A start or end falls on the first communication point at or after it. Kinds and their targets
(an object, or `object.component` where the object has several fitting components):

| kind            | target                                  | parameters                                          |
|-----------------|-----------------------------------------|-----------------------------------------------------|
| `sensor_stuck`  | a light barrier, an ID reader (trigger)  | `value: true` (always sees a bottle) or `false` (never) |
| `belt_failure`  | a belt's drive (conveyor, curve; `sw1.main`) | `speed`: fraction of its speed it still runs at, 0 (stops, the default) … below 1 |
| `part_stuck`    | a switch's blade, a gate, a stopper       | — (the part stays where it is and ignores commands) |
| `reader_fault`  | an ID reader                             | `reads: nothing`, or `reads: wrong` with `destination` (and `id`, default "?") |
| `logic_dead`    | an object's `logic` (FMU, participant)    | — (its outputs stop reaching the plant: no events, values frozen) |
| `bottle_tipped` | a light barrier or ID reader: the place   | — (the bottle in its volume at the start, or else the next to enter, is laid on its side there) |

What a kind does to the slots is hub/run/faults.py's; a fault becomes an operator command
(`fault`, `repair`: hub/bus/commands.py) at its point, so it is in events.csv and commands.csv
and a replay applies it again from there.
"""
from __future__ import annotations

import random
from dataclasses import dataclass

from hub.core.registry import did_you_mean
from hub.core.slots import Direction, SlotType

KINDS = ("sensor_stuck", "belt_failure", "part_stuck", "reader_fault", "logic_dead", "bottle_tipped")

#: kind → (required parameters, optional parameters)
PARAMETERS = {
    "sensor_stuck": (("value",), ()),
    "belt_failure": ((), ("speed",)),
    "part_stuck": ((), ()),
    "reader_fault": (("reads",), ("destination", "id")),
    "logic_dead": ((), ()),
    "bottle_tipped": ((), ()),
}

#: kind → what a fitting component is, said in an error
WHAT = {
    "sensor_stuck": "a sensor (a volume trigger: on_enter and occupied)",
    "belt_failure": "a belt drive (speed and running)",
    "part_stuck": "a part with two positions (a switch blade, a gate, a stopper: blocked)",
    "reader_fault": "an ID reader (on_enter and destination)",
    "logic_dead": "state logic (a `logic` component: an FMU or a participant)",
    "bottle_tipped": "a sensor that names what enters it (on_enter and object)",
}


def fits(kind: str, component: str, slots: dict[str, object]) -> bool:
    """Whether a component (its name, and its slots by name → Slot) can take a fault of `kind`."""
    def source(name, kind_=None):
        s = slots.get(name)
        return s is not None and s.direction is Direction.SOURCE and (kind_ is None or s.type is kind_)

    def target(name, kind_=None):
        s = slots.get(name)
        return s is not None and s.direction is Direction.TARGET and (kind_ is None or s.type is kind_)

    if kind == "sensor_stuck":
        return source("on_enter", SlotType.VOID) and source("occupied", SlotType.BOOL)
    if kind == "belt_failure":
        return target("speed", SlotType.REAL) and source("running", SlotType.BOOL)
    if kind == "part_stuck":
        return source("blocked", SlotType.BOOL) and any(s.direction is Direction.TARGET for s in slots.values())
    if kind == "reader_fault":
        return source("on_enter", SlotType.VOID) and source("destination", SlotType.STRING)
    if kind == "bottle_tipped":
        return source("on_enter", SlotType.VOID) and source("object", SlotType.STRING) and \
            source("occupied", SlotType.BOOL)
    return component == "logic"


def components(table: dict[tuple[str, str], object]) -> dict[str, dict[str, object]]:
    """A slot table {(component, slot): Slot} by component: {component: {slot: Slot}}."""
    out: dict[str, dict[str, object]] = {}
    for (comp, name), slot in table.items():
        out.setdefault(comp, {})[name] = slot
    return out


def target_component(kind: str, target: str, tables: dict) -> tuple[str | None, str | None]:
    """(`object.component` the fault acts on, None) or (None, why not)."""
    obj, _, comp = target.partition(".")
    if obj not in tables:
        return None, f"unknown object {obj!r}{did_you_mean(obj, tables)}"
    by = components(tables[obj])
    if comp:
        if comp not in by:
            return None, f"object {obj!r} has no component {comp!r}{did_you_mean(comp, by)}"
        if not fits(kind, comp, by[comp]):
            return None, f"{target} is not {WHAT[kind]}, which {kind} needs"
        return target, None
    found = [c for c, slots in by.items() if fits(kind, c, slots)]
    if not found:
        return None, f"object {obj!r} has no component that is {WHAT[kind]}, which {kind} needs"
    if len(found) > 1:
        return None, f"{obj!r} has several: name one ({', '.join(f'{obj}.{c}' for c in found)})"
    return f"{obj}.{found[0]}", None


@dataclass(frozen=True)
class FaultSpec:
    """One checked fault: what (kind, target `object.component`, parameters), when and how long.

    `start` is a tick on the grid of communication points (None: after an event), `event` the
    void source counted and `count` the occurrence it starts at; `duration` ticks after its start
    or `end` tick (None, None: it lasts to the run's end)."""

    name: str
    kind: str
    target: str
    parameters: dict
    start: int | None = None
    event: object = None          # SlotRef of a void source, with `count`
    count: int = 0
    duration: int | None = None   # ticks, a whole number of communication steps
    end: int | None = None        # tick on the grid
    line: int | None = None
    window: tuple[float, float] | None = None   # `between`: the window its start was drawn from, s

    def message(self) -> dict:
        """The command's value (hub/bus/commands.py `fault`): everything the fault does, as JSON."""
        return {"name": self.name, "kind": self.kind, **self.parameters}

    def describe(self, rate: int) -> str:
        """What, where and when, in a line (`planthub validate`)."""
        text = ", ".join(f"{k} {v!r}" for k, v in self.parameters.items())
        what = f"{self.kind} at {self.target}" + (f" ({text})" if text else "")
        return f"{self.name}: {what}, {self.when(rate)}"

    def when(self, rate: int) -> str:
        """When it starts and ends, in words (`from 2 s for 1 s`)."""
        if self.event is not None:
            start = f"from the {self.count}{_th(self.count)} {self.event}"
        else:
            drawn = f" (drawn from run.seed in [{self.window[0]:g}, {self.window[1]:g}] s)" if self.window else ""
            start = f"from {self.start / rate:g} s{drawn}"
        end = f" for {self.duration / rate:g} s" if self.duration is not None else \
            f" to {self.end / rate:g} s" if self.end is not None else " to the end"
        return f"{start}{end}"


def _th(n: int) -> str:
    return "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")


def on_grid(seconds: float, rate: int, substeps: int) -> int:
    """The tick of the first communication point at or after `seconds`."""
    tick = round(seconds * rate)
    return -(-tick // substeps) * substeps


def drawn(seed: int, index: int, low: float, high: float, rate: int, substeps: int) -> int:
    """A communication point within [low, high] s drawn from the run's seed, the same for every
    run of that seed: its own generator per fault, so adding a fault changes no other's time."""
    first, last = on_grid(low, rate, substeps), (round(high * rate) // substeps) * substeps
    points = max(0, (last - first) // substeps)
    return first + substeps * random.Random(f"planthub-fault:{seed}:{index}").randint(0, points)


def check_values(kind: str, spec: dict, at: tuple, problem) -> dict | None:
    """The kind's parameters from `spec`, or None with the problems noted (`problem(path, message)`)."""
    needed, optional = PARAMETERS[kind]
    allowed = set(needed) | set(optional)
    params, bad = {}, False
    for key in ("value", "speed", "reads", "destination", "id"):
        if key in spec and key not in allowed:
            problem(at + (key,), f"`{key}` is not a parameter of {kind}"
                                 + (f" (it takes {', '.join(sorted(allowed))})" if allowed else " (it takes none)"))
            bad = True
    for key in needed:
        if key not in spec:
            problem(at, f"{kind} needs `{key}`")
            bad = True
    if bad:
        return None
    if kind == "sensor_stuck":
        params["value"] = spec["value"]
    elif kind == "belt_failure":
        params["speed"] = float(spec.get("speed", 0.0))
    elif kind == "reader_fault":
        params["reads"] = spec["reads"]
        if spec["reads"] == "wrong":
            if "destination" not in spec:
                problem(at, "reader_fault with `reads: wrong` needs the `destination` it reads instead")
                return None
            params["destination"] = spec["destination"]
            params["id"] = spec.get("id", "?")
        elif "destination" in spec or "id" in spec:
            key = "destination" if "destination" in spec else "id"
            problem(at + (key,), f"`{key}` goes with `reads: wrong`; a reader that reads nothing reads no {key}")
            return None
    return params


def check_faults(checker, specs: list, tables: dict, run) -> list[FaultSpec]:
    """The `faults:` section, its meaning (the schema judged its shape): each target, event and
    time checked, every problem noted on `checker` (hub/scenario/checker.py) at its line."""
    from hub.scenario.yamlsource import line_of

    out, names = [], {}
    rate, step, end = run.physics_rate, run.substeps, run.end_tick
    for i, spec in enumerate(specs):
        at = ("faults", i)
        if not isinstance(spec, dict) or not checker.intact(at):
            continue
        kind = spec["kind"]
        name = spec.get("name") or f"{kind} {spec['target']}"
        if "name" not in spec and name in names:
            name = f"{name} (faults[{i}])"   # unnamed faults of one kind at one target, told apart
        if name in names:
            checker.problem(at + ("name",) if "name" in spec else at,
                            f"two faults are named {name!r} (the other at line {names[name]}): name them apart")
            continue
        names[name] = line_of(checker.lines, at)
        starts = [k for k in ("at", "after", "between") if k in spec]
        if len(starts) != 1:
            checker.problem(at, "give exactly one start: `at` (a time), `after` (an event) or `between` (a window "
                                "the seed draws a time from)" + (f", not {' and '.join(starts)}" if starts else ""))
            continue
        if "for" in spec and "until" in spec:
            checker.problem(at + ("until",), "give `for` (a duration) or `until` (a time), not both")
            continue
        target, why = target_component(kind, spec["target"], tables)
        if target is None:
            if spec["target"].partition(".")[0] not in checker.broken:
                checker.problem(at + ("target",), why)
            continue
        params = check_values(kind, spec, at, checker.problem)
        if params is None:
            continue
        start = event = None
        count = 0
        if "at" in spec:
            start = on_grid(spec["at"], rate, step)
        elif "between" in spec:
            low, high = spec["between"]
            if not low < high:
                checker.problem(at + ("between",), f"the window [{low:g}, {high:g}] s is empty: give [earliest, latest]")
                continue
            if on_grid(low, rate, step) > (round(high * rate) // step) * step:
                checker.problem(at + ("between",), f"no communication point lies in [{low:g}, {high:g}] s "
                                                   f"(one every {step / rate:g} s)")
                continue
            start = drawn(run.seed, i, low, high, rate, step)
        else:
            if "until" in spec:
                checker.problem(at + ("until",), "`until` is a time, and a fault after an event starts at a time "
                                                 "no one knows before the run: give `for`")
                continue
            found = checker.resolve(spec["after"]["event"], at + ("after", "event"), tables, Direction.SOURCE)
            if found is None:
                continue
            if found[1].type is not SlotType.VOID:
                checker.problem(at + ("after", "event"), f"{found[0]} is {found[1].type.value}; a fault starts after "
                                                         "an event, a void source")
                continue
            event, count = found[0], spec["after"].get("count", 1)
        if start is not None and start > end:
            checker.problem(at + ("at" if "at" in spec else "between",),
                            f"starts at {start / rate:g} s, after the run's end at {end / rate:g} s")
            continue
        duration = until = None
        if "for" in spec:
            duration = on_grid(spec["for"], rate, step)
        elif "until" in spec:
            until = on_grid(spec["until"], rate, step)
            latest = start if "at" in spec else on_grid(spec["between"][1], rate, step)
            if until <= latest:
                checker.problem(at + ("until",), f"{spec['until']:g} s is not after the fault's "
                                                 + ("start" if "at" in spec else "latest start")
                                                 + f" at {latest / rate:g} s")
                continue
        window = tuple(spec["between"]) if "between" in spec else None
        out.append(FaultSpec(name, kind, target, params, start, event, count, duration, until, names[name], window))
    return out
