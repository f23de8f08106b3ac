"""Operator commands: set, force or release a slot, or stop the run — applied at a communication
point, recorded with its tick in `commands.csv`, and replayed from there bit for bit.

- `set SLOT VALUE`: once, at the next point. A source takes the value after the components
  sensed (flows pass it on); a target after the flows were evaluated (it wins over them), as if
  a flow had fed it.
- `force SLOT VALUE`: the same at every point until `release SLOT`.
- `stop`: the run ends after this point.
- `pause`, `resume`, `step N` (N points, while paused), `pace F` (F × real time, a paced run):
  the run's control (hub/run/hold.py). They change when points are computed, never what: a
  replay ignores them and gives the same recording. While paused, they are taken at once; other
  commands wait for the next point.
- `fault`, `repair`: a fault begins or ends (hub/scenario/faults.py; the scenario's `faults:`,
  put in by their schedule, hub/run/faults.py). Its value is the fault as a map (name, kind and
  its parameters), its slot the part it acts on. Recorded like the others, so a replay applies
  the same faults at the same points without scheduling them again. Live, they come only on the
  instructor's key `plant/<run>/@instructor/command` (answered on `…/command/result` there):
  under access control only the names in run.bus.access.instructor may put there, and a
  trainee watching the run sees neither the command nor its answer.
- `checkpoint`: the run is saved at the next point into its folder's `checkpoints/TICK.ckpt`
  (hub/run/checkpoint.py). Like the run's control it changes nothing the run computes: recorded
  and noted, and a replay goes past it.
- `rewind TICK`: the run goes back to the checkpoint it took at or before TICK (this run's, at a
  tick not past the present) and on from there (hub/run/rewind.py): the plant built again with
  the checkpoint put in, the bus session and its participants kept. Recorded with the tick of the
  checkpoint it went back to, so that a replay rewinds at the same point to the same state. Taken
  once the point is complete; while the run is paused, at once.

A target read by its own component within the step (a constant's or connector's input) cannot
be commanded: command the slot that feeds it.
"""
from __future__ import annotations

import csv
import json
from collections import deque
from dataclasses import dataclass
from pathlib import Path

from hub.bus import wire
from hub.bus.session import Bus, Inbox
from hub.core.errors import PlanthubError
from hub.core.observer import Stop
from hub.core.registry import did_you_mean
from hub.core.slots import Direction, SlotType

OPS = ("set", "force", "release", "stop", "pause", "resume", "step", "pace", "checkpoint", "rewind", "fault",
       "repair")
FAULTS = ("fault", "repair")   # a fault's begin and end: hub/run/faults.py
CONTROL = ("pause", "resume", "step", "pace")   # the run's control: hub/run/hold.py
MAX_STEPS = 100_000   # points one `step` may ask for
MAX_PACE = 1000.0     # the fastest pace one may ask for, × real time


class CommandError(PlanthubError):
    """A command cannot be applied (unknown slot, wrong value) or a command file cannot be read."""


@dataclass(frozen=True)
class Command:
    op: str
    slot: str = ""          # object.component.slot; empty for stop
    value: object = None    # the canonical slot value; None for void, release, stop
    by: str = ""            # who sent it, as it asked to be logged

    def value_text(self, kind: SlotType | None) -> str:
        """The value as JSON (empty where there is none), exact for every double."""
        if self.op in ("step", "pace", "rewind", *FAULTS):
            return json.dumps(self.value)
        if self.op in ("release", "stop") or kind in (None, SlotType.VOID):
            return ""
        return json.dumps(wire.to_wire(kind, self.value))

    def describe(self, kind: SlotType | None) -> str:
        text = " ".join(p for p in (self.op, self.value_text(kind)) if p)
        return text + (f" by {self.by}" if self.by else "")


class Commands:
    """The commands of one run: from the bus (`listen`) or from a recording (`replay`), never both."""

    def __init__(self, plant, recorder, replay: list[tuple[int, Command]] | None = None):
        self.recorder = recorder
        self.rate = plant.scenario.run.physics_rate
        self.slots = {}    # "obj.comp.slot" → (index, Slot)
        self._objects: dict[str, list[str]] = {}   # object → its slots' names, for "did you mean"
        for ref in plant.index:
            self._objects.setdefault(ref.obj, []).append(str(ref))
        owners = {(c.obj, c.name): c for c in plant.components}
        self._owner = {index: owners[(ref.obj, ref.component)] for ref, index in plant.index.items()}
        feedthrough = {(c.obj, c.name, t) for c in plant.components for t, _ in c.FEEDTHROUGH}
        self._inner = set()
        for ref, index in plant.index.items():
            self.slots[str(ref)] = (index, plant.signals.slots[index])
            if (ref.obj, ref.component, ref.slot) in feedthrough:
                self._inner.add(str(ref))
        self._replay = deque(replay) if replay is not None else None
        self._inbox = Inbox()
        self._results = None
        self._forced: dict[int, object] = {}
        # What the plant itself gave a forced slot (its flows' last write, or its own state): what
        # `release` gives back. And the slots released at this point, to restore once.
        self._own: dict[int, object] = {}
        self._released: dict[int, object] = {}
        self._once: list[tuple[int, object]] = []
        self._waiting: list = []   # commands taken in while paused, applied at the next point
        self.stop_pending = False    # a stop came while the run was held: it ends the run at the next point
        self.control = None        # the run's control (hub/run/hold.py Hold): pause, resume, step, pace
        self.on_checkpoint = None  # asks for a checkpoint at this point (hub/run/checkpoint.py Checkpointer.request)
        self.rewinds = None        # goes back to a checkpoint (hub/run/rewind.py Rewinder); None: refused
        self.stop_requested = False
        self.faults = None         # applies `fault` and `repair` (hub/run/faults.py FaultBook); None: refused

    def stop(self, tick: int) -> Stop | None:
        """A stop condition (hub/core/observer.py): an operator's `stop` ends the run at its point."""
        if self.stop_requested:
            return Stop(f"stopped by an operator at t = {tick / self.rate:.9g} s")
        return None

    # --- sources of commands -------------------------------------------------------------
    def listen(self, bus: Bus, run: str) -> None:
        """Take live commands from `plant/<run>/@cosim/command`; answer on `…/command/result`."""
        bus.subscribe(wire.control_key(run, "command"), lambda m: self._inbox.put((m.payload, False)))
        bus.subscribe(wire.instructor_key(run, "command"), lambda m: self._inbox.put((m.payload, True)))
        self._results = bus.publisher(wire.control_key(run, "command", "result"), wire.MSGPACK)
        self._instructor_results = bus.publisher(wire.instructor_key(run, "command", "result"), wire.MSGPACK)

    def parse(self, message) -> Command:
        """A command message (a map: op, slot, value, by) → a checked Command, or CommandError."""
        if not isinstance(message, dict) or message.get("op") not in OPS:
            raise CommandError(f"expected a map with op one of {', '.join(OPS)}, got {_shown(message)}")
        op, by = message["op"], message.get("by", "")
        if not isinstance(by, str) or len(by) > MAX_NAME:
            raise CommandError(f"`by` must be a string of at most {MAX_NAME} characters, got {_shown(by)}")
        if op in ("stop", "pause", "resume", "checkpoint"):
            return Command(op, by=by)
        if op in FAULTS:
            if self.faults is None:
                raise CommandError(f"{op}: this run takes no faults")
            return self.faults.parse(message)
        if op == "step":
            count = message.get("value", 1)
            if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_STEPS:
                raise CommandError(f"step takes a number of points from 1 to {MAX_STEPS}, got {_shown(count)}")
            return Command("step", value=count, by=by)
        if op == "pace":
            factor = message.get("value")
            if isinstance(factor, bool) or not isinstance(factor, (int, float)) or not 0 < factor <= MAX_PACE:
                raise CommandError(f"pace takes a factor of real time above 0 and at most {MAX_PACE:g}, "
                                   f"got {_shown(factor)}")
            return Command("pace", value=float(factor), by=by)
        if op == "rewind":
            tick = message.get("value")
            if isinstance(tick, bool) or not isinstance(tick, int) or tick < 0:
                raise CommandError(f"rewind takes the tick to go back to (a whole number, 0 or more), got {_shown(tick)}")
            return Command("rewind", value=tick, by=by)
        name = message.get("slot")
        if not isinstance(name, str) or name not in self.slots:
            raise CommandError(f"no slot {_shown(name)}{self._nearest(name)}")
        if name in self._inner:
            raise CommandError(f"{name} is read by its own component within the step; command the slot "
                               f"that feeds it instead")
        kind = self.slots[name][1].type
        if op == "release":
            return Command("release", name, by=by)
        if kind is SlotType.VOID:
            value = None
        else:
            try:
                value = kind.coerce(message.get("value"))
            except ValueError as exc:
                raise CommandError(f"{name} is {kind.value}: {exc}") from None
        return Command(op, name, value, by)

    def _nearest(self, name) -> str:
        """A "did you mean" that costs about what an applied command does: among the slots of the
        named object (or among the objects), never over every slot of the plant."""
        if not isinstance(name, str) or len(name) > MAX_NAME:
            return ""
        obj = name.split(".", 1)[0]
        if obj not in self._objects:
            return did_you_mean(obj, self._objects)
        return did_you_mean(name, self._objects[obj])

    def pending(self) -> bool:
        """Whether live commands wait for the next point."""
        return not self._inbox.empty()

    # --- at a communication point ----------------------------------------------------------
    def take(self, tick: int) -> list[tuple[int, str, str]]:
        """Apply the commands due at this point: record them and return their event-log rows."""
        due = []
        if self._replay is not None:
            while self._replay and self._replay[0][0] <= tick:
                at, command = self._replay.popleft()
                if at < tick:
                    raise CommandError(f"the replayed command at tick {at} ({command.describe(None)} "
                                       f"{command.slot}) falls between two communication points of this run")
                due.append(command)
        else:
            due, self._waiting = self._waiting, []
            if not self._inbox.empty():
                due += self._live(tick)
        rows = []
        for command in due:
            if command.op in FAULTS:
                (self.faults.begin if command.op == "fault" else self.faults.end)(tick, command)
                self.recorder.command(tick, command.op, command.slot, command.value_text(None), command.by)
                rows.append((tick, "@fault", command.describe(None)))
                continue
            kind = self.slots[command.slot][1].type if command.slot else None
            if command.op == "stop":
                self.stop_requested = True
            elif command.op == "checkpoint":
                if self._replay is None:
                    self.on_checkpoint()
                self._note_control(tick, command, "a checkpoint at this point")
                continue
            elif command.op == "rewind":
                self._rewind(tick, command, now=False)
                continue
            elif command.op in CONTROL:
                # When points are computed is no part of the results: recorded for a replay, which
                # runs through, and noted in bus_log.csv — events.csv holds only what the plant did.
                if self._replay is None and self.control is not None:
                    self.control.apply(command)
                self._note_control(tick, command)
                continue
            else:
                index = self.slots[command.slot][0]
                if command.op == "set":
                    self._once.append((index, command.value))
                elif command.op == "force":
                    self.hold(index, command.value)
                else:
                    self.let_go(index)
            self.recorder.command(tick, command.op, command.slot, command.value_text(kind), command.by)
            rows.append((tick, command.slot or "@run", command.describe(kind)))
        return rows

    def hold(self, index: int, value) -> None:
        """Force slot `index` to `value` at every point from this one on (`force`; a fault)."""
        self._forced[index] = value

    def let_go(self, index: int) -> None:
        """End a force: the slot has again what the plant gives it (`release`; a fault's end)."""
        self._forced.pop(index, None)
        if index in self._own:
            self._released[index] = self._own.pop(index)

    def inject(self, command: Command) -> None:
        """A command from inside the hub (a scheduled fault), applied at this point: given before
        `take` (hub/run/faults.py FaultSchedule is the manipulator before this one)."""
        self._waiting.append(command)

    def _live(self, tick: int, first=()) -> list[Command]:
        """The live commands waiting in the inbox (after those in `first`), checked and answered
        (a refused one only answered)."""
        due = []
        for payload, instructor in [*first, *self._inbox.drain()]:
            try:
                command = self.parse(wire.unpack(payload))
                if command.op in FAULTS and not instructor:
                    raise CommandError(f"{command.op}: faults are an instructor's: put it on "
                                       "plant/<run>/@instructor/command (under run.bus.access, with a certificate "
                                       "named in access.instructor)")
                if command.op in CONTROL:
                    refused = (self.control.refuse(command) if self.control is not None else
                               "this run has no control of its points (a replay, or no live commands)")
                    if refused:
                        raise CommandError(refused)
                if command.op == "checkpoint" and self.on_checkpoint is None:
                    raise CommandError("checkpoint: this run has no folder to write checkpoints into "
                                       "(planthub run --out)")
                if command.op == "rewind":
                    refused = (self.rewinds.refuse(tick, command.value) if self.rewinds is not None else
                               "rewind: this run keeps no checkpoints to go back to: it has no folder "
                               "(planthub run --out)")
                    if refused:
                        raise CommandError(refused)
            except (CommandError, wire.WireError) as exc:
                self._answer(payload, tick, str(exc), instructor)
                continue
            due.append(command)
            self._answer(payload, tick, None, instructor)
        return due

    def wait(self, tick: int, timeout: float) -> None:
        """While the run is held at `tick`: wait up to `timeout` s for live commands. The run's
        control among them is applied and recorded now; the others wait for the next point, and a
        stop ends the hold so that the run ends there (recorded at that point as any stop, so a
        replay ends at the same tick)."""
        item = self._inbox.get(timeout)
        if item is None:
            return
        for command in self._live(tick, [item]):
            if command.op in CONTROL:
                self.control.apply(command)
                self._note_control(tick, command)
            elif command.op == "rewind":   # the held point is complete: back at once, still held
                self._rewind(tick, command, now=True)
            else:
                self._waiting.append(command)
                self.stop_pending |= command.op == "stop"

    def _rewind(self, tick: int, command: Command, now: bool) -> None:
        """Ask for the rewind (at the end of this point, or `now` while held), recorded with the
        tick of the checkpoint it goes back to: what a replay goes back to."""
        back = self.rewinds.request(tick, command, now)
        self._note_control(tick, Command("rewind", value=back, by=command.by),
                           f"back to the checkpoint at tick {back}, asked for tick {command.value}")

    def _note_control(self, tick: int, command: Command, what: str = "the run's control") -> None:
        self.recorder.command(tick, command.op, "", command.value_text(None), command.by)
        self.recorder.notice(tick, f"{command.describe(None)} ({what})")

    def _answer(self, payload: bytes, tick: int, error: str | None, instructor: bool = False) -> None:
        if self._results is None:
            return
        try:
            ident = wire.unpack(payload).get("id", "")
            if not isinstance(ident, str) or len(ident) > MAX_NAME:
                ident = ""   # echoed to everyone: only an id of the form wire.md gives
        except (wire.WireError, AttributeError):
            ident = ""
        results = self._instructor_results if instructor else self._results
        results.put(wire.pack({"id": ident, "ok": error is None, "tick": tick, "error": error or ""}))

    def rebind(self, plant) -> None:
        """Work on `plant`, built again by a rewind (hub/run/rewind.py): its components, and no
        force of the abandoned branch (a checkpoint holds those of the faults in effect)."""
        owners = {(c.obj, c.name): c for c in plant.components}
        self._owner = {index: owners[(ref.obj, ref.component)] for ref, index in plant.index.items()}
        for held in (self._forced, self._own, self._released):
            held.clear()
        self._once.clear()

    def apply(self, signals, direction: Direction) -> None:
        """Write the commanded values of this direction's slots (sources after sensing, targets after flows).

        A forced slot keeps, aside, what the plant gives it meanwhile — a flow's write to a target,
        a component's emit of a source — and `release` hands that back: the slot then has the value
        it would have had without the force, not the forced one (hub/bus/README.md).
        Then the faults in effect do what they do to this direction's slots (hub/run/faults.py)."""
        if self._once or self._forced or self._released:
            self._apply(signals, direction)
        if self.faults is not None:
            self.faults.apply(signals, direction)

    def _apply(self, signals, direction: Direction) -> None:
        written = signals.updated if direction is Direction.TARGET else signals.active
        for index, value in list(self._released.items()):
            if signals.slots[index].direction is direction:
                del self._released[index]
                if not written[index] and signals.slots[index].type is not SlotType.VOID:
                    signals.values[index] = value   # nothing wrote it at this point: its own value again
                    if direction is Direction.TARGET:
                        signals.updated[index] = True   # written back, so its component applies it
        for index in self._forced:
            if signals.slots[index].direction is not direction:
                continue
            if written[index]:
                self._own[index] = signals.values[index]   # what the plant gave it at this point
            elif index not in self._own:   # the force begins: what the slot or its component held
                held = self._owner[index].held(signals.slots[index].name) if direction is Direction.TARGET else None
                self._own[index] = signals.values[index] if held is None else held
        for index, value in [*self._forced.items(), *self._once]:
            slot = signals.slots[index]
            if slot.direction is not direction:
                continue
            if direction is Direction.SOURCE:
                signals.emit(index, value)
            else:
                if value is not None:
                    signals.values[index] = value
                signals.updated[index] = True
        if direction is Direction.TARGET:
            self._once.clear()


def load_commands(run_dir: Path, plant, faults=None) -> list[tuple[int, Command]]:
    """The commands a run recorded (`RUN_DIR/commands.csv`; none if it has no such file);
    `faults` checks its faults (hub/run/faults.py FaultBook; without, a fault is refused)."""
    run_dir = Path(run_dir)
    if not (run_dir / "recording.csv").is_file() and not (run_dir / "events.csv").is_file():
        raise CommandError(f"{run_dir}: not a run folder (no recording.csv or events.csv)")
    path = run_dir / "commands.csv"
    if not path.is_file():
        return []
    checker = Commands(plant, recorder=None)
    checker.faults = faults
    out = []
    with open(path, newline="", encoding="utf-8") as handle:
        for line, row in enumerate(csv.DictReader(handle), start=2):
            try:
                message = {"op": row["op"], "slot": row["slot"], "by": row.get("by") or ""}
                if row["value"]:
                    message["value"] = json.loads(row["value"])
                out.append((int(row["tick"]), checker.parse(message)))
            except (CommandError, ValueError, KeyError, TypeError) as exc:
                raise CommandError(f"{path}:{line}: {exc}") from None
    return out


def command_message(op: str, slot: str = "", value=None, by: str = "", ident: str = "") -> bytes:
    """A command as it goes on the bus (what `planthub send` and `hub.live.Viewer.command` put)."""
    message = {"op": op, "id": ident, "by": by}
    if slot:
        message["slot"] = slot
    if value is not None:
        message["value"] = list(value) if isinstance(value, tuple) else value
    return wire.pack(message)


#: the longest slot name or sender a command may carry: longer ones are refused unread and never echoed
MAX_NAME = 200


def _shown(value) -> str:
    """A value for a message: repr, cut to 80 characters (a refused command is answered to everyone)."""
    text = repr(value)
    return text if len(text) <= 80 else f"{text[:60]}… ({len(text)} characters)"
