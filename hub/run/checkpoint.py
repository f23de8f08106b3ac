"""Checkpoints: a running plant's whole state at a communication point, as bytes and as a file, and put back into a run of the same scenario.

A checkpoint is taken right after a communication point (the master's `communicate`): the world
at that tick, every slot's value and the point's activity, every flow's arming, every
component's own state and its logic's (FMUs through FMI's FMU-state calls, participants
through the bus's save message), the observers whose figures depend on the past (the event
counts, the plant's tally, the expectations' watcher) and the master's own flags. A run that
puts it back continues with the physics and logic steps that follow that point, and gives, bit
for bit, the rows and events the run that saved it gave after it (tests/test_checkpoint.py).
Its own recording starts after the point.

The file: a first line `planthub checkpoint`, a JSON header line (format, tick, rate, the
scenario's name and fingerprint, the payload's size and SHA-256), then the payload
(hub/core/state.py `dumps`). It is written to a temporary file beside its place and renamed, so
a reader never sees half of one.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from hub.core import state
from hub.core.errors import CheckpointError
from hub.core.files import written

FORMAT = 2
MAGIC = b"planthub checkpoint\n"
#: Object parameters that may differ between the run that saved and the one that resumes: where
#: logic runs (in the hub, in a child process, over the bus) changes no result, nor does whether
#: a crashed worker is restarted (on_fault).
_WHERE_LOGIC_RUNS = ("runs", "launch", "on_fault")


@dataclass(frozen=True)
class Header:
    format: int
    tick: int
    rate: int
    scenario: str
    fingerprint: str
    size: int
    sha256: str

    @property
    def time(self) -> float:
        return self.tick / self.rate


def fingerprint(scenario) -> str:
    """What a snapshot must fit: the scenario's plant (objects, their parameters, flows) and the
    run settings that shape its state. Its duration, its expectations, its recording and where its
    logic runs may differ (`planthub run --resume … --set run.duration=…`), and so may the
    parameters of its logic, which its saved state overrides."""
    run = scenario.run
    objects = []
    for spec in scenario.objects:
        params = {k: v for k, v in spec.params.items() if k not in _WHERE_LOGIC_RUNS and k != "parameters"}
        logic = None if spec.logic is None else {k: v for k, v in spec.logic.items()
                                                 if k not in _WHERE_LOGIC_RUNS and k != "parameters"}
        objects.append([spec.name, spec.module_name, params, logic])
    flows = [[str(f.source), str(f.target), f.condition.value, f.mode.value, str(f.rearm)] for f in scenario.flows]
    shape = {"rate": run.physics_rate, "substeps": run.substeps, "seed": run.seed, "event_driven": run.event_driven,
             "master": run.master, "sleep_after": run.sleep_after, "max_speed": run.max_speed,
             "on_violation": run.on_violation, "solver_iterations": run.solver_iterations,
             "integrator": run.integrator, "jam_after": run.jam_after, "objects": objects, "flows": flows}
    text = json.dumps(shape, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def by_kind(parts) -> dict[str, object]:
    """Parts by class and occurrence (`module.Class`, `module.Class#2`, …): a part of a run built
    again from the same scenario finds its counterpart under the same key."""
    out = {}
    for part in parts:
        name = f"{type(part).__module__}.{type(part).__qualname__}"
        key, n = name, 1
        while key in out:
            n += 1
            key = f"{name}#{n}"
        out[key] = part
    return out


def _observers(run) -> dict[str, object]:
    """The run's observers and stop conditions that keep state, by class and occurrence."""
    parts = {id(p): p for p in (*run.master.observers, *run.master.stops, *run.contributed) if state.is_stateful(p)}
    return by_kind(parts.values())


def capture(run, in_point: bool = False) -> bytes:
    """The run's whole state now, at the communication point it is at, as a checkpoint's bytes;
    `in_point`: asked by the last observer of a point, which is complete but for the master's flag."""
    master = run.master
    if not (master.communicated or in_point):
        raise CheckpointError("a checkpoint is taken at a communication point; the run has not reached its first")
    whole = {"plant": state.save(run.plant),
             "master": {"answering": master._answering},
             "observers": {key: state.save(part) for key, part in _observers(run).items()}}
    payload = state.dumps(whole)
    scenario = run.scenario
    header = {"format": FORMAT, "tick": master.tick, "rate": scenario.run.physics_rate, "scenario": scenario.name,
              "fingerprint": fingerprint(scenario), "size": len(payload),
              "sha256": hashlib.sha256(payload).hexdigest()}
    return MAGIC + json.dumps(header, sort_keys=True).encode() + b"\n" + payload


def header(data: bytes, where: str) -> tuple[Header, bytes]:
    """The header and payload of a checkpoint's bytes, checked whole; a CheckpointError naming
    `where` (the file) and the cause otherwise."""
    if not data.startswith(MAGIC):
        raise CheckpointError(f"{where}: not a planthub checkpoint (it does not start with {MAGIC.strip().decode()!r})")
    end = data.find(b"\n", len(MAGIC))
    if end < 0:
        raise CheckpointError(f"{where}: truncated: the header line has no end")
    try:
        fields = json.loads(data[len(MAGIC):end])
        head = Header(**{name: fields[name] for name in Header.__dataclass_fields__})
    except (ValueError, KeyError, TypeError) as exc:
        raise CheckpointError(f"{where}: its header cannot be read ({type(exc).__name__}: {exc})") from None
    if head.format != FORMAT:
        raise CheckpointError(f"{where}: checkpoint format {head.format!r}; this planthub reads format {FORMAT}")
    payload = data[end + 1:]
    if len(payload) != head.size:
        raise CheckpointError(f"{where}: truncated or padded: its header promises {head.size} bytes of state, "
                              f"the file holds {len(payload)}")
    if hashlib.sha256(payload).hexdigest() != head.sha256:
        raise CheckpointError(f"{where}: corrupt: its state does not match the checksum in its header")
    return head, payload


def held_parts(data: bytes, where: str) -> set[str]:
    """The keys (`by_kind`) of the run's parts whose state a checkpoint holds: a run about to put it
    back makes the parts it would not have made otherwise (the faults' after a live fault)."""
    _, payload = header(data, where)
    return set(state.loads(payload, where)["observers"])


def apply(run, data: bytes, where: str) -> Header:
    """Put a checkpoint into `run`, a run of the same scenario built and not yet started: it then
    continues from the checkpoint's communication point."""
    head, payload = header(data, where)
    scenario = run.scenario
    if head.fingerprint != fingerprint(scenario):
        raise CheckpointError(f"{where}: taken from another plant: scenario {head.scenario!r} (fingerprint "
                              f"{head.fingerprint[:12]}), not this {scenario.name!r} ({scenario.path}, fingerprint "
                              f"{fingerprint(scenario)[:12]}); only the duration, the expectations, the recording, "
                              f"the logic's parameters and where logic runs may differ")
    if head.rate != scenario.run.physics_rate:
        raise CheckpointError(f"{where}: its physics rate is {head.rate} Hz, the scenario's {scenario.run.physics_rate}")
    if head.tick > scenario.run.end_tick:
        raise CheckpointError(f"{where}: taken at t = {head.time:g} s, after this run's end at "
                              f"t = {scenario.run.end_tick / head.rate:g} s (set run.duration longer)")
    whole = state.loads(payload, where)
    try:
        state.restore(run.plant, whole["plant"], "plant")
        run.master._answering = whole["master"]["answering"]
        observers = _observers(run)
        missing = sorted(set(observers) - set(whole["observers"]))
        if missing:
            raise CheckpointError(f"the snapshot holds no state of {', '.join(missing)} (taken by a run without it)")
        for key, part in observers.items():
            state.restore(part, whole["observers"][key], key)
    except CheckpointError as exc:
        raise CheckpointError(f"{where}: {exc}") from None
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise CheckpointError(f"{where}: its state does not fit this plant ({type(exc).__name__}: {exc})") from None
    run.master.communicated = True
    return head


def write(path: Path, data: bytes) -> None:
    """Write a checkpoint atomically (hub/core/files.py)."""
    with written(path, "wb") as out:
        out.write(data)


def read(path: Path) -> bytes:
    """A checkpoint file's bytes (checked when applied); a CheckpointError if it cannot be read."""
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise CheckpointError(f"{path}: cannot read the checkpoint: {exc.strerror or exc}") from None


@dataclass(frozen=True)
class Taken:
    """A checkpoint of the run's line (what a rewind may go back to): its file, or its bytes when
    it is kept in memory only, and where the run's files ended at it (Recorder.marks)."""

    tick: int
    path: Path | None
    data: bytes | None
    marks: dict | None

    def bytes(self) -> bytes:
        return self.data if self.data is not None else read(self.path)

    @property
    def where(self) -> str:
        return str(self.path) if self.path is not None else f"the checkpoint at tick {self.tick}"


class Checkpointer:
    """An observer that saves the run at given ticks and every `every` ticks, after every other
    observer has seen the point, to `folder/TICK.ckpt` (`planthub run --checkpoint-at/-every`),
    and at the ticks in `keep` into memory only (the points a replay's rewinds go back to).

    `taken` holds the checkpoints of the line the run is on, by tick: a rewind goes back to one
    of them, and forgets those after it (`forget_after`), whose files it moves to
    `folder/branchN/`."""

    def __init__(self, run, folder: Path | None, ticks=(), every: int | None = None, log=None, keep=()):
        self.run = run
        self.folder = Path(folder) if folder is not None else None
        self.ticks = set(ticks)
        self.every = every
        self.keep = set(keep)
        self.log = log
        self.written: list[Path] = []
        self.taken: dict[int, Taken] = {}
        self.version = 0   # changes whenever `taken` does (the bus's timeline of checkpoints is sent again)
        self.requested = False

    def add(self, taken: Taken) -> None:
        self.taken[taken.tick] = taken
        self.version += 1

    def at_or_before(self, tick: int) -> Taken | None:
        """The latest checkpoint of the run's line at or before `tick`, or None."""
        found = [t for t in self.taken if t <= tick]
        return self.taken[max(found)] if found else None

    def forget_after(self, tick: int, branch: int) -> list[Path]:
        """Forget the checkpoints after `tick` (a rewind's abandoned branch); their files go to
        `folder/branchN/`. Returns where they went."""
        moved = []
        self.version += 1
        for t in sorted(t for t in self.taken if t > tick):
            taken = self.taken.pop(t)
            if taken.path is not None and taken.path.exists():
                place = taken.path.parent / f"branch{branch}" / taken.path.name
                place.parent.mkdir(exist_ok=True)
                taken.path.replace(place)
                moved.append(place)
        return moved

    def request(self) -> None:
        """Save the run at the point being computed (an operator's `checkpoint` command)."""
        self.requested = True

    def observe(self, tick: int, signals, events) -> None:
        saved = self.folder is not None and (
            self.requested or tick in self.ticks or (self.every and tick and tick % self.every == 0))
        if not (saved or tick in self.keep):
            return
        self.requested = False
        data = capture(self.run, in_point=True)
        path = None
        if saved:
            path = self.folder / f"{tick}.ckpt"
            write(path, data)
            self.written.append(path)
            if self.log is not None:
                self.log(f"checkpoint at t = {tick / self.run.scenario.run.physics_rate:g} s: {path}")
        self.add(Taken(tick, path, None if saved else data, self.run.recorder.marks()))

    def close(self, reason: str) -> None:
        """Nothing to release: each checkpoint is complete once written."""
