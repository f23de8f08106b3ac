"""Faults in a run: what each kind does to the plant's slots (FaultBook), and the schedule that starts and ends the scenario's faults (FaultSchedule).

A fault begins and ends as an operator command (`fault`, `repair`: hub/bus/commands.py), so it is
recorded in commands.csv and events.csv (slot `@fault`) with its tick, and a replay applies the
recorded commands at the same points instead of scheduling the faults again: the same files, bit
for bit. What a kind does, at the points while it lasts (hub/scenario/faults.py says which
targets fit):

- `sensor_stuck` — `value: true`: `occupied` is true and `on_stay` fires at every point,
  `on_enter` fires at the first, and nothing else the sensor gives (`on_leave`, the id) goes
  out; `false`: `occupied` is false and nothing else goes out. When it ends, the edge the
  sensor missed is given: `on_leave` if it was stuck on and is free, `on_enter` (and `object`)
  if it was stuck off and sees a bottle. A fault `after` an event counts what the sensor sensed,
  before any fault or operator changed it. The event log has what the sensor reported (an entry
  it missed is not there), and the fault's own rows say when it lied.
- `belt_failure` — the drive's `speed` is forced (as `force` does) to `speed` × what it was at
  the fault's start; the belt still says it runs. At the end the drive gets back what its
  logic gave it meanwhile (as `release` does).
- `part_stuck` — the part's targets take no commands (their writes are dropped before it
  actuates): a switch blade, a gate or a stopper stays where it is (a move under way ends).
- `reader_fault` — `reads: nothing`: the reader's entry (`on_enter`, `object`, `destination`,
  `filled`, `capped`) does not go out; `reads: wrong`: each entry goes out with the given
  `destination` and `id`.
- `bottle_tipped` — the bottle in the sensor's volume when the fault begins (the one that
  entered last), or else the next to enter it, is laid on its side where it stands, its axis
  along the way it moves (hub/physics/parking.py `lay`): a real obstacle the physics has to deal
  with (it jams at a switch's blade, a curve, a gate). Once: its end changes nothing.
- `logic_dead` — nothing of the logic component's outputs goes out (no events, values frozen
  at what they were at the start). The logic itself still steps (a participant's process is not
  killed: that would end a run by its lease, at no tick a replay could reproduce); when the
  fault ends its outputs reach the plant again, from the state it stepped to.

Effects are applied last at their direction's step of the point, after the operator's
forces (hub/run/master.py, steps 1 and 2).

An instructor injects a fault live (`planthub view`'s instructor panel, or `fault` on the
instructor's key): checked here as a scenario's fault is, and with `for: S` in its value it lasts
S s (on the grid of points): the schedule then puts a `repair` in at its end, recorded like the
fault, so a replay ends it where the live run did without timing anything itself. What the
instructor's page shows of the faults is `board` (hub/view/broadcast.py sends it on the
instructor's key, never where a trainee reads).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from hub.bus.commands import MAX_NAME, Command, CommandError
from hub.core.slots import Direction
from hub.scenario.faults import KINDS, PARAMETERS, WHAT, check_values, components, fits, on_grid, target_component

MAX_FOR = 86_400.0   # s: the longest a live fault may be given to last


@dataclass
class Started:
    """A fault that began: its name, kind, target, and ticks (end None: still in effect)."""

    name: str
    kind: str
    target: str
    start: int
    end: int | None = None


class FaultBook:
    """The faults in effect in a run and what they do: the `fault` and `repair` commands' hook
    (Commands.faults), over the plant's slot numbers."""

    def __init__(self, plant):
        self.plant = plant
        self.signals = plant.signals
        self.commands = None   # the Commands whose forces a belt failure uses (attach)
        tables: dict[str, dict] = {}
        self._slots: dict[tuple[str, str], dict[str, int]] = {}
        for ref, index in plant.index.items():
            tables.setdefault(ref.obj, {})[(ref.component, ref.slot)] = plant.signals.slots[index]
            self._slots.setdefault((ref.obj, ref.component), {})[ref.slot] = index
        self._tables = tables
        self._owners = {(c.obj, c.name): c for c in plant.components}
        run = plant.scenario.run
        self.rate, self.substeps = run.physics_rate, run.substeps
        self.timed = False     # a live run: a fault given `for` gets its repair from the schedule (`ends`)
        self.ends: dict[str, tuple[str, int, str]] = {}   # fault → (target, end tick, by) of timed live faults
        self.version = 0       # changes whenever a fault begins or ends (the instructor's board is sent again)
        self.on_first = None   # called when the first fault begins (the run assembly adds the faults' figures)
        self._targets = None
        self.active: dict[str, _Effect] = {}
        self._ending: list[_Effect] = []   # ended at this point: their last word at the next SOURCE step
        self.log: list[Started] = []

    def attach(self, commands) -> None:
        commands.faults = self
        self.commands = commands

    # --- commands ----------------------------------------------------------------------------
    def parse(self, message: dict) -> Command:
        """A `fault` or `repair` command message checked against this plant, or CommandError."""
        op, by, value = message["op"], message.get("by", ""), message.get("value")
        if not isinstance(value, dict) or not isinstance(value.get("name"), str) or \
                not 0 < len(value["name"]) <= MAX_NAME:
            raise CommandError(f"{op}: its value is a map with the fault's `name` (a string of at most {MAX_NAME} "
                               f"characters), got {str(value)[:80]}")
        if op == "repair":
            if set(value) != {"name"}:
                raise CommandError(f"repair: its value names the fault only, got keys {sorted(value)}")
            return Command("repair", str(message.get("slot", ""))[:MAX_NAME], {"name": value["name"]}, by)
        kind, target = value.get("kind"), message.get("slot")
        if kind not in KINDS:
            raise CommandError(f"fault: kind must be one of {', '.join(KINDS)}, got {str(kind)[:80]}")
        if not isinstance(target, str) or len(target) > MAX_NAME:
            raise CommandError(f"fault: its slot is the part it acts on (object.component), got {str(target)[:80]}")
        found, why = target_component(kind, target, self._tables)
        if found != target:
            raise CommandError(f"fault {value['name']}: {why or f'name the component: {found}'}")
        params = {k: v for k, v in value.items() if k not in ("name", "kind", "for")}
        unknown = sorted(str(k) for k in set(params) - {"value", "speed", "reads", "destination", "id"})
        problems = [f"unknown parameter {unknown[0][:80]!r}"] if unknown else _bad_types(params)
        made = None if problems else check_values(kind, params, (), lambda path, text: problems.append(text))
        lasts = value.get("for")
        if not problems and lasts is not None and (isinstance(lasts, bool) or not isinstance(lasts, (int, float))
                                                   or not 0 < lasts <= MAX_FOR):
            problems.append(f"`for` is how long it lasts, s: above 0 and at most {MAX_FOR:g}, got {str(lasts)[:80]}")
        if problems:
            raise CommandError(f"fault {value['name']}: {problems[0]}")
        return Command("fault", target, {"name": value["name"], "kind": kind, **made,
                                         **({} if lasts is None else {"for": float(lasts)})}, by)

    def begin(self, tick: int, command: Command) -> None:
        if self.on_first is not None:
            self.on_first()
            self.on_first = None
        name = command.value["name"]
        if name in self.active:
            self._stop(tick, name)
        obj, comp = command.slot.split(".")
        effect = _EFFECTS[command.value["kind"]](self, obj, comp, command.value)
        self.active[name] = effect
        self.log.append(Started(name, command.value["kind"], command.slot, tick))
        self.version += 1
        self.ends.pop(name, None)
        if self.timed and "for" in command.value:
            self.ends[name] = (command.slot, tick + max(self.substeps, on_grid(command.value["for"], self.rate,
                                                                               self.substeps)), command.by)
        effect.begin()

    def end(self, tick: int, command: Command) -> None:
        if command.value["name"] in self.active:
            self._stop(tick, command.value["name"])

    def _stop(self, tick: int, name: str) -> None:
        self.version += 1
        self.ends.pop(name, None)
        effect = self.active.pop(name)
        effect.end()
        self._ending.append(effect)
        for started in reversed(self.log):
            if started.name == name and started.end is None:
                started.end = tick
                break

    # --- at a communication point -------------------------------------------------------------
    def apply(self, signals, direction: Direction) -> None:
        if direction is Direction.SOURCE and self._ending:
            for effect in self._ending:
                effect.after(signals)
            self._ending.clear()
        for effect in self.active.values():
            effect.apply(signals, direction)

    def slots(self, obj: str, comp: str) -> dict[str, int]:
        return self._slots[(obj, comp)]

    # --- checkpoints (hub/core/state.py: saved by FaultsState) ---------------------------------
    def save_state(self) -> dict:
        """The faults in effect (each its command and its own state), the log, and the forces of
        the Commands that applies them (a belt failure's)."""
        c = self.commands
        return {"active": [(name, e.target, dict(e.value), {k: getattr(e, k) for k in type(e).STATE})
                           for name, e in self.active.items()],
                "log": [(f.name, f.kind, f.target, f.start, f.end) for f in self.log],
                "ends": dict(self.ends),
                "forces": None if c is None else (dict(c._forced), dict(c._own), dict(c._released))}

    def restore_state(self, saved: dict) -> None:
        self.active.clear()
        for name, target, value, own in saved["active"]:
            obj, comp = target.split(".")
            effect = _EFFECTS[value["kind"]](self, obj, comp, value)
            for key, item in own.items():
                setattr(effect, key, item)
            self.active[name] = effect
        self._ending.clear()
        self.log[:] = [Started(*f) for f in saved["log"]]
        self.ends = {name: tuple(end) for name, end in saved.get("ends", {}).items()}
        self.version += 1
        if saved["forces"] is not None and self.commands is not None:
            for held, back in zip((self.commands._forced, self.commands._own, self.commands._released),
                                  saved["forces"]):
                held.clear()
                held.update(back)

    def component(self, obj: str, comp: str):
        return self._owners[(obj, comp)]

    # --- the instructor's board -----------------------------------------------------------------
    def targets(self) -> dict[str, list[str]]:
        """Kind → the parts a fault of that kind fits (`object.component`), what a live fault may name."""
        if self._targets is None:
            by_object = {obj: components(table) for obj, table in self._tables.items()}
            self._targets = {kind: [f"{obj}.{comp}" for obj, comps in by_object.items()
                                    for comp, slots in comps.items() if fits(kind, comp, slots)] for kind in KINDS}
        return self._targets

    def board(self, schedule=None) -> dict:
        """What an instructor's page shows (schemas/scene.schema.json `faults_message`): each kind with
        the parts it fits and its parameters, the scenario's faults and when, those in effect, and
        every fault that began."""
        rate, targets = self.rate, self.targets()
        kinds = {kind: {"targets": targets[kind], "what": WHAT[kind], "needs": list(PARAMETERS[kind][0]),
                        "optional": list(PARAMETERS[kind][1])} for kind in KINDS}
        scheduled = []
        for n, spec in enumerate(schedule.specs if schedule is not None else ()):
            state = "pending" if n in schedule.pending else "active" if spec.name in self.active else "ended"
            scheduled.append({"name": spec.name, "kind": spec.kind, "target": spec.target,
                              "parameters": dict(spec.parameters), "when": spec.when(rate),
                              "state": state})
        active = [{"name": name, "kind": e.value["kind"], "target": e.target, "parameters":
                   {k: v for k, v in e.value.items() if k not in ("name", "kind", "for")},
                   "until": self.ends[name][1] / rate if name in self.ends else None}
                  for name, e in self.active.items()]
        started = [{"name": f.name, "kind": f.kind, "target": f.target, "start": f.start / rate,
                    "end": None if f.end is None else f.end / rate} for f in self.log]
        return {"kinds": kinds, "scheduled": scheduled, "active": active, "started": started}


def _bad_types(params: dict) -> list[str]:
    checks = {"value": (bool,), "speed": (int, float), "reads": (str,), "destination": (str,), "id": (str,)}
    for key, value in params.items():
        if not isinstance(value, checks[key]) or (key == "speed" and (isinstance(value, bool) or not 0 <= value < 1)):
            return [f"`{key}` cannot be {str(value)[:80]}"]
        if key == "reads" and value not in ("nothing", "wrong"):
            return ["`reads` is nothing or wrong"]
        if isinstance(value, str) and len(value) > MAX_NAME:
            return [f"`{key}` is longer than {MAX_NAME} characters"]
    return []


class _Effect:
    STATE: tuple[str, ...] = ()   # what changes while it lasts (FaultBook.save_state)

    def __init__(self, book: FaultBook, obj: str, comp: str, value: dict):
        self.target = f"{obj}.{comp}"
        self.book = book
        self.owner = book.component(obj, comp)
        self.slot = book.slots(obj, comp)
        self.value = value
        self.kinds = {name: book.signals.slots[i] for name, i in self.slot.items()}

    def begin(self) -> None:
        """At the point the fault begins (before the point's sources are set)."""

    def apply(self, signals, direction: Direction) -> None:
        """At every point while it lasts, at both directions' steps."""

    def end(self) -> None:
        """At the point it ends."""

    def after(self, signals) -> None:
        """At the SOURCE step of the point it ended at."""

    def sources(self):
        return [i for name, i in self.slot.items() if self.kinds[name].direction is Direction.SOURCE]


class _SensorStuck(_Effect):
    STATE = ("first",)

    def begin(self):
        self.first = True

    def apply(self, signals, direction):
        if direction is not Direction.SOURCE:
            return
        on, slot, active = self.value["value"], self.slot, signals.active
        for i in self.sources():
            active[i] = False
        signals.emit(slot["occupied"], on)
        if on:
            active[slot["on_stay"]] = True
            active[slot["on_enter"]] = self.first
        self.first = False

    def after(self, signals):
        slot, seen = self.slot, signals.values[self.slot["occupied"]]
        if self.value["value"] and not seen:
            signals.active[slot["on_leave"]] = True
        elif not self.value["value"] and seen:
            signals.active[slot["on_enter"]] = True
            inside = getattr(self.owner.latch, "inside", ())
            if "object" in slot and inside:   # which bottle it now sees: the last inside, as on an entry
                signals.emit(slot["object"], self.book.plant.world.labels[inside[-1]])


class _BeltFailure(_Effect):
    def begin(self):
        index = self.slot["speed"]
        held = self.owner.held("speed")   # the drive's speed now (a target keeps no value of its own)
        speed = self.book.signals.values[index] if held is None else held
        self.book.commands.hold(index, float(speed) * self.value["speed"])

    def end(self):
        self.book.commands.let_go(self.slot["speed"])


class _PartStuck(_Effect):
    def apply(self, signals, direction):
        if direction is Direction.TARGET:
            updated = signals.updated
            for name, i in self.slot.items():
                if self.kinds[name].direction is Direction.TARGET:
                    updated[i] = False


class _ReaderFault(_Effect):
    STATE = ("kept",)
    ENTRY = ("on_enter", "object", "destination", "filled", "capped")

    def begin(self):
        values = self.book.signals.values   # what it read last: kept while it reads nothing
        self.kept = [(self.slot[name], values[self.slot[name]]) for name in self.ENTRY if name in self.slot]

    def apply(self, signals, direction):
        if direction is not Direction.SOURCE:
            return
        slot = self.slot
        if self.value["reads"] == "nothing":
            for i, value in self.kept:
                signals.values[i] = value
                signals.active[i] = False
        elif signals.active[slot["on_enter"]]:
            signals.values[slot["destination"]] = self.value["destination"]
            if "object" in slot:
                signals.values[slot["object"]] = self.value["id"]


class _LogicDead(_Effect):
    STATE = ("frozen",)

    def begin(self):
        values = self.book.signals.values
        self.frozen = [(i, values[i]) for i in self.sources()]

    def apply(self, signals, direction):
        if direction is not Direction.SOURCE:
            return
        values, active = signals.values, signals.active
        for i, value in self.frozen:
            values[i] = value
            active[i] = False


class _BottleTipped(_Effect):
    STATE = ("armed", "first")

    def begin(self):
        self.armed, self.first = True, True

    def apply(self, signals, direction):
        if direction is not Direction.SOURCE or not self.armed:
            return
        # What the sensor saw, not what its slots say (another fault may make them lie).
        latch, world = self.owner.latch, self.book.plant.world
        found = latch.entered[-1][1] if latch.entered else latch.inside[-1] if self.first and latch.inside else None
        self.first = False
        if found is None:
            return
        self.armed = False
        body = int(found)
        vx, vy = world.velocities[body][:2].tolist()
        world.tip(body, math.atan2(vy, vx) if vx * vx + vy * vy > 1e-6 else 0.0)


_EFFECTS = {"sensor_stuck": _SensorStuck, "belt_failure": _BeltFailure, "part_stuck": _PartStuck,
            "reader_fault": _ReaderFault, "logic_dead": _LogicDead, "bottle_tipped": _BottleTipped}


class FaultSchedule:
    """Starts and ends the scenario's faults (hub/scenario/faults.py FaultSpec) at their points: a
    manipulator (hub/run/master.py) placed just before the Commands it gives them to, which
    apply and record them at the same point. A replay has none: its recorded commands do it."""

    STATE = ("counts", "pending", "ends")

    def __init__(self, plant, specs, commands):
        self.commands = commands
        self.specs = list(specs)
        self.index = plant.index
        self.world = plant.world
        self.pending = list(range(len(self.specs)))   # not started, in the scenario's order
        self.counts = [0] * len(self.specs)
        self.ends: dict[int, int] = {}                 # started fault → its end tick
        self._events = {n: plant.index[s.event] for n, s in enumerate(self.specs) if s.event is not None}

    def take(self, tick: int) -> list:
        return []

    def apply(self, signals, direction: Direction) -> None:
        if direction is not Direction.SOURCE:
            return
        tick = self.world.tick
        book = self.commands.faults
        for name, (target, end, by) in list(book.ends.items()) if book is not None else ():
            if tick >= end:   # a live fault given `for`: its repair, recorded as any other
                del book.ends[name]
                self.commands.inject(Command("repair", target, {"name": name}, by))
        for n, end in list(self.ends.items()):
            if end is not None and tick >= end:
                del self.ends[n]
                spec = self.specs[n]
                self.commands.inject(Command("repair", spec.target, {"name": spec.name}, "scenario"))
        for n in list(self.pending):
            spec = self.specs[n]
            if spec.event is not None:
                if not signals.fired(self._events[n]):
                    continue
                self.counts[n] += 1
                if self.counts[n] < spec.count:
                    continue
            elif tick < spec.start:
                continue
            self.pending.remove(n)
            self.ends[n] = tick + spec.duration if spec.duration is not None else spec.end
            self.commands.inject(Command("fault", spec.target, spec.message(), "scenario"))


class Board:
    """The instructor's board of a run (hub/view/broadcast.py sends it): its `version` changes
    whenever a fault begins, ends or comes due, `board()` is the message."""

    def __init__(self, book: FaultBook, schedule: FaultSchedule | None):
        self.book = book
        self.schedule = schedule

    @property
    def version(self) -> tuple[int, int]:
        return self.book.version, len(self.schedule.pending) if self.schedule is not None else 0

    def board(self) -> dict:
        return self.book.board(self.schedule)


class FaultsState:
    """The faults' part of a checkpoint (hub/run/checkpoint.py walks the run's contributed
    parts): the book's faults in effect and forces, and the schedule's counts, starts and ends."""

    def __init__(self, book: FaultBook, schedule: FaultSchedule | None):
        self.book = book
        self.schedule = schedule

    def save_state(self) -> dict:
        s = self.schedule
        return {"book": self.book.save_state(),
                "schedule": None if s is None else (list(s.pending), list(s.counts), dict(s.ends))}

    def restore_state(self, saved: dict) -> None:
        self.book.restore_state(saved["book"])
        if self.schedule is not None and saved["schedule"] is not None:
            pending, counts, ends = saved["schedule"]
            self.schedule.pending[:] = pending
            self.schedule.counts[:] = counts
            self.schedule.ends.clear()
            self.schedule.ends.update(ends)


#: The faults' part's key in a checkpoint (hub/run/checkpoint.py `by_kind`): a checkpoint that
#: holds it was taken with faults in effect or begun.
FAULTS_PART = f"{FaultsState.__module__}.{FaultsState.__qualname__}"
