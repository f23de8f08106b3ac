"""Expectations of a scenario (`expect:`), watched at every communication point and judged after the run."""
from __future__ import annotations

import operator
from dataclasses import dataclass, field
from typing import ClassVar

from hub.core.slots import SlotRef, SlotType

NEVER_JUDGED = "never judged"   # an `always` whose `when` never fired: how its outcome opens
OPERATORS = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
             ">": operator.gt, ">=": operator.ge}


@dataclass(frozen=True)
class Expectation:
    """One checked expectation: the value of `slot` compared with `value` by `op`,
    either at the tick `at` (None: at the end of the run) or, with `always`, at every point
    (only where the void slot `when` fired, if given). `show` names a slot whose value each
    failure reports (which bottle it was). An `always` whose `when` never fired was never
    judged: it fails, unless `allow_empty` says that is fine."""

    name: str
    slot: SlotRef
    type: SlotType
    op: str
    value: object
    always: bool = False
    at: int | None = None
    when: SlotRef | None = None
    show: SlotRef | None = None
    line: int | None = None
    allow_empty: bool = False

    def describe(self) -> str:
        when = f" whenever {self.when} fires" if self.when else ""
        if self.always:
            return f"{self.slot} {self.op} {self.value!r} at every point{when}"
        return f"{self.slot} {self.op} {self.value!r} {'at the end' if self.at is None else 'at tick ' + str(self.at)}"


@dataclass(frozen=True)
class Implied:
    """An expectation a scenario's setting implies, judged by the module that contributes it: with
    `run.orders`, that the run ends with its orders out, not by its duration."""

    name: str
    line: int | None = None

    def describe(self) -> str:
        return self.name


@dataclass(frozen=True)
class NoJam:
    """`jams: none`: no bottle jammed at any time of the run (the run summary's rule,
    modules/plant/jams.py, with run.jam_after), judged from the plant's jam watch after the run."""

    name: str
    line: int | None = None

    def describe(self) -> str:
        return "no bottle jams at any time"

    def judge(self, jams, end: float) -> Outcome:
        if not jams:
            return Outcome(self, True, "held")
        listed = "; ".join(f"{j.bottle} on {j.belt} from {j.since:.4g} s"
                           + (f" to {j.until:.4g} s" if j.until is not None else f", still at {end:.4g} s")
                           for j in jams[:10])
        more = f"; … {len(jams) - 10} more" if len(jams) > 10 else ""
        return Outcome(self, False, f"{len(jams)} jammed: {listed}{more}")


@dataclass
class Outcome:
    """How one expectation came out. `judged` False: the run ended before it could be (an
    interrupted run); such an outcome has not passed either."""

    expectation: Expectation
    passed: bool
    message: str
    judged: bool = True


def interrupted(outcomes: list[Outcome], tick: int, rate: int) -> list[Outcome]:
    """The outcomes of a run interrupted at `tick`, as far as what ran can judge them. A failure
    seen stays one (an `always` broken, a jam), and so does a value at an `at` the run reached;
    everything the rest of the run could still change — a value at the end, an `always` or `jams:
    none` that held so far, orders not yet delivered — is not judged, and says so."""
    when = f"the run was interrupted at t = {tick / rate:.9g} s"
    out = []
    for outcome in outcomes:
        e = outcome.expectation
        if isinstance(e, Expectation) and not e.always:
            final = e.at is not None and e.at <= tick   # its moment came: judged as it is
        elif isinstance(e, Implied):
            final = outcome.passed                      # the orders were delivered
        elif hasattr(e, "settled"):   # an exercise's goal or score (hub/scenario/exercise.py) says itself
            final = e.settled(outcome.passed)
        else:   # an `always`, `jams: none`: a failure seen is one, a `when` that did not fire yet is not
            final = not outcome.passed and not outcome.message.startswith(NEVER_JUDGED)
        if final:
            out.append(outcome)
            continue
        if isinstance(e, Expectation) and not e.always and e.at is not None:
            message = f"not judged: {when}, before {e.at / rate:.4g} s"
        else:
            message = f"not judged: {when} (so far: {outcome.message})"
        out.append(Outcome(e, False, message, judged=False))
    return out


@dataclass
class Watcher:
    """Reads the plant's slots at every communication point and keeps what the judgement needs."""

    expectations: list[Expectation]
    index: dict[SlotRef, int]
    rate: int
    failures: dict[int, list[str]] = field(default_factory=dict)
    seen: dict[int, object] = field(default_factory=dict)
    judged: dict[int, int] = field(default_factory=dict)   # points an `always` was judged at
    STATE: ClassVar[tuple[str, ...]] = ("judged", "seen", "failures")   # hub/core/state.py: what it saw so far

    def read(self, signals, ref: SlotRef, kind: SlotType):
        i = self.index[ref]
        return signals.fired(i) if kind is SlotType.VOID else signals.values[i]

    def observe(self, tick: int, signals, events=()) -> None:
        for n, e in enumerate(self.expectations):
            if e.always:
                if e.when is not None and not signals.fired(self.index[e.when]):
                    continue
                self.judged[n] = self.judged.get(n, 0) + 1
                value = self.read(signals, e.slot, e.type)
                if not OPERATORS[e.op](value, e.value):
                    shown = f" ({e.show} = {signals.values[self.index[e.show]]!r})" if e.show else ""
                    self.failures.setdefault(n, []).append(f"at {tick / self.rate:.4g} s it was {value!r}{shown}")
            elif e.at is None or tick >= e.at:
                if e.at is None or n not in self.seen:
                    self.seen[n] = (tick, self.read(signals, e.slot, e.type))

    def close(self, reason: str) -> None:
        """Judged at any time; nothing to release."""

    def judge(self) -> list[Outcome]:
        outcomes = []
        for n, e in enumerate(self.expectations):
            if e.always:
                found = self.failures.get(n, [])
                listed = "; ".join(found[:10]) + (f"; … {len(found) - 10} more" if len(found) > 10 else "")
                if found:
                    outcomes.append(Outcome(e, False, f"failed {len(found)}×: {listed}"))
                elif not self.judged.get(n) and not e.allow_empty:
                    outcomes.append(Outcome(e, False, f"{NEVER_JUDGED}: {e.when} never fired "
                                                      "(say `allow_empty: true` if that is a pass)"))
                else:
                    outcomes.append(Outcome(e, True, f"held at {self.judged.get(n, 0)} points"
                                            if e.when is not None else "held"))
            elif n not in self.seen:
                outcomes.append(Outcome(e, False, f"the run ended before {e.at / self.rate:.4g} s"))
            else:
                tick, value = self.seen[n]
                ok = OPERATORS[e.op](value, e.value)
                outcomes.append(Outcome(e, ok, f"{e.slot} was {value!r} at {tick / self.rate:.4g} s"))
        return outcomes
