"""A scored exercise (`exercise:`): the task, its goals judged on the plant's figures after the run, and the score.

    exercise:
      task: Route every bottle to its lane although the reader r3 misreads from the 5th bottle on.
      goals:
        - {delivered: 40}              # at least 40 bottles delivered
        - {misrouted: 0, points: 2}    # none misrouted; counts twice
        - {rejected: 1}                # at most 1 bottle taken out at a reject sink
        - {longest_jam: 5}             # no jam longer than 5 s (0: none at all)
        - {recover_within: 20}         # after each fault's start, never 20 s without a delivery
        - {throughput: 10}             # at least 10 deliveries a minute over the run
      pass: 100                        # % of the points that passes (default 100: every goal)

Each goal is one of those keys, with an optional `name` and `points` (default 1). The score is
the points of the goals met over all points, in %; the exercise passes at `pass` % or more.
`planthub run` prints the goals and the score and writes them to summary.json (`exercise`);
`planthub test` judges each goal as a test case beside the expectations (JUnit, one case per
goal, and one for the score). Goals are judged on the plant summary (modules/plant/summary.py:
deliveries, misrouted and rejected bottles, jams) and on the times the faults started (hub/run/faults.py), so
a plant (sources, sinks) is needed.

Recovery from a fault: the plant's output is measured by its deliveries, so the time it takes to
recover from a fault is the longest stretch without a delivery from the fault's start to the
end of the run (a stretch still open at the end counts to the end). Within `recover_within` the
plant recovered: it kept delivering, or was delivering again that soon. A fault that never
started (its event never came) is not judged. Judged from the start, a fault before the first
delivery counts the line's filling as outage: a shipped exercise starts its faults later.
"""
from __future__ import annotations

from dataclasses import dataclass

GOALS = ("delivered", "misrouted", "rejected", "longest_jam", "recover_within", "throughput")
NO_PLANT = "an exercise's goals are judged on a plant, a scenario with a source or a sink; this one has neither"


@dataclass(frozen=True)
class Goal:
    """One goal: `key` (one of GOALS) with its `limit`, the points it counts, and a name."""

    key: str
    limit: float
    points: int
    name: str
    line: int | None = None

    def settled(self, met: bool) -> bool:
        """Whether the verdict stands if the run ends here (an interrupted run): a goal failed
        that the rest of the run could only make worse (misroutes, a jam's length), or one met that
        it could not undo (bottles delivered). The rest waits for the run's end."""
        return (not met and self.key in ("misrouted", "rejected", "longest_jam")) or (met and self.key == "delivered")

    def describe(self) -> str:
        return {"delivered": f"at least {self.limit:g} bottles delivered",
                "misrouted": "no bottle misrouted" if self.limit == 0 else f"at most {self.limit:g} misrouted",
                "rejected": "no bottle rejected" if self.limit == 0 else f"at most {self.limit:g} rejected",
                "longest_jam": "no jam" if self.limit == 0 else f"no jam longer than {self.limit:g} s",
                "recover_within": f"never {self.limit:g} s without a delivery after a fault",
                "throughput": f"at least {self.limit:g} deliveries a minute"}[self.key]


@dataclass(frozen=True)
class Exercise:
    task: str
    goals: tuple[Goal, ...]
    passing: float = 100.0   # % of the points
    line: int | None = None


@dataclass(frozen=True)
class Verdict:
    """How one goal came out: met or not, and what was measured."""

    goal: Goal
    met: bool
    message: str


def check_exercise(checker, spec, plant: bool) -> Exercise | None:
    """The `exercise:` section's meaning (its shape is the schema's), problems noted on `checker`:
    each goal the schema took is judged, and the exercise is made only when all of it is sound."""
    from hub.scenario.yamlsource import line_of

    if not isinstance(spec, dict):
        return None
    if not plant:
        checker.problem(("exercise",), NO_PLANT)
        return None
    listed = spec.get("goals") if isinstance(spec.get("goals"), list) else []
    goals, names = [], set()
    for i, goal in enumerate(listed):
        at = ("exercise", "goals", i)
        if not isinstance(goal, dict) or not checker.intact(at):
            continue
        keys = [k for k in GOALS if k in goal]
        if len(keys) != 1:
            checker.problem(at, f"give exactly one goal of {', '.join(GOALS)}"
                                + (f", not {' and '.join(keys)}" if keys else ""))
            continue
        key = keys[0]
        made = Goal(key, goal[key], goal.get("points", 1), "", line_of(checker.lines, at))
        name = goal.get("name") or made.describe()
        if name in names:
            checker.problem(at, f"two goals are named {name!r}: name them apart")
            continue
        names.add(name)
        goals.append(Goal(key, goal[key], made.points, name, made.line))
    if len(goals) != len(listed) or not checker.intact(("exercise",)):
        return None
    return Exercise(spec["task"], tuple(goals), float(spec.get("pass", 100)), line_of(checker.lines, ("exercise",)))


def _at_most(goal: Goal, bottles, word: str, name, unjudged: str) -> Verdict:
    """At most `goal.limit` of `bottles` (None: the plant cannot tell, for the reason `unjudged`),
    the first five named."""
    if bottles is None:
        return Verdict(goal, False, f"not judged: {unjudged}")
    named = "; ".join(name(b) for b in bottles[:5])
    return Verdict(goal, len(bottles) <= goal.limit, f"{len(bottles)} {word}" + (f": {named}" if named else ""))


def judge(goal: Goal, plant, faults: list[tuple[str, float]]) -> Verdict:
    """A goal judged on the plant summary (PlantSummary: delivered, misrouted, jams, per_minute,
    delivery_times, end) and the faults that started, as (name, start s)."""
    if goal.key == "delivered":
        return Verdict(goal, plant.delivered >= goal.limit, f"{plant.delivered} delivered")
    if goal.key == "misrouted":
        return _at_most(goal, plant.misrouted, "misrouted", lambda m: f"{m.bottle} (for {m.destination}) at {m.sink}",
                        "no sink says which destinations its lane is for (`accepts`)")
    if goal.key == "rejected":
        return _at_most(goal, plant.rejected, "rejected", lambda r: f"{r.bottle} (for {r.destination})",
                        "no sink takes rejects (`rejects: true`)")
    if goal.key == "longest_jam":
        if not plant.jams:
            return Verdict(goal, True, "no jam")
        worst = max(plant.jams, key=lambda j: j.seconds(plant.end))
        seconds = worst.seconds(plant.end)
        still = " (still jammed at the end)" if worst.until is None else ""
        return Verdict(goal, seconds <= goal.limit if goal.limit > 0 else False,
                       f"{len(plant.jams)} jam{'s' * (len(plant.jams) != 1)}, the longest {worst.bottle} on "
                       f"{worst.belt} from {worst.since:.3f} s for {seconds:.2f} s{still}")
    if goal.key == "throughput":
        return Verdict(goal, plant.per_minute >= goal.limit, f"{plant.per_minute:.2f} a minute")
    # recover_within
    if not faults:
        return Verdict(goal, True, "no fault started")
    found, met = [], True
    for name, start in faults:
        since, seconds = outage(start, plant)
        open_ = "" if since + seconds < plant.end else " to the end"
        found.append(f"{name}: at most {seconds:.2f} s without a delivery (from {since:.3f} s{open_})")
        met &= seconds <= goal.limit
    return Verdict(goal, met, "; ".join(found))


def outage(start: float, plant) -> tuple[float, float]:
    """The longest stretch without a delivery from `start` to the end of the run: (from, seconds)."""
    times = [t for t in plant.delivery_times if t > start]
    edges = [start, *times, plant.end]
    return max(((a, b - a) for a, b in zip(edges, edges[1:])), key=lambda x: x[1])
