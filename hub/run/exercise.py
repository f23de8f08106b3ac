"""The run summary's faults and exercise: which faults ran when, each goal judged and the score (hub/scenario/exercise.py says the rules)."""
from __future__ import annotations

from dataclasses import dataclass

from hub.scenario.exercise import Exercise, Verdict, judge
from hub.scenario.expectations import Outcome

SCORE = "the score"   # the name of the test case the score is judged as (JUnit)


@dataclass(frozen=True)
class FaultsSection:
    """The faults that began in a run: a SummarySection (hub/core/observer.py), key `faults`."""

    started: tuple   # hub/run/faults.py Started
    rate: int
    key = "faults"

    def lines(self) -> list[str]:
        if not self.started:
            return ["  faults       none began"]
        out = [f"  faults       {len(self.started)}"]
        for f in self.started:
            until = f"to {f.end / self.rate:.3f} s" if f.end is not None else "to the end"
            out.append(f"    {f.name}: {f.kind} at {f.target} from {f.start / self.rate:.3f} s {until}")
        return out

    def as_dict(self) -> dict:
        return {"started": [{"name": f.name, "kind": f.kind, "target": f.target, "start": f.start / self.rate,
                             "end": None if f.end is None else f.end / self.rate} for f in self.started]}


@dataclass(frozen=True)
class ExerciseSection:
    """The exercise's task, each goal's verdict and the score: a SummarySection, key `exercise`."""

    exercise: Exercise
    verdicts: tuple[Verdict, ...]
    key = "exercise"

    @property
    def points(self) -> int:
        return sum(v.goal.points for v in self.verdicts if v.met)

    @property
    def total(self) -> int:
        return sum(g.points for g in self.exercise.goals)

    @property
    def score(self) -> float:
        return 100.0 * self.points / self.total

    @property
    def passed(self) -> bool:
        return self.score >= self.exercise.passing

    def score_line(self) -> str:
        return (f"{self.score:.0f} % ({self.points} of {self.total} points): "
                + ("passed" if self.passed else "failed") + f" (passes at {self.exercise.passing:g} %)")

    def lines(self) -> list[str]:
        task = self.exercise.task.strip().splitlines()
        out = [f"  exercise     {task[0]}", *(f"               {t}" for t in task[1:])]
        for v in self.verdicts:
            points = f"  ({v.goal.points} points)" if v.goal.points != 1 else ""
            out.append(f"    {'✓' if v.met else '✗'} {v.goal.name} — {v.message}{points}")
        out.append(f"  score        {self.score_line()}")
        return out

    def as_dict(self) -> dict:
        return {"task": self.exercise.task,
                "goals": [{"name": v.goal.name, "goal": v.goal.key, "limit": v.goal.limit, "points": v.goal.points,
                           "met": v.met, "measured": v.message} for v in self.verdicts],
                "points": self.points, "total": self.total, "score": self.score,
                "pass": self.exercise.passing, "passed": self.passed}


class FaultsFigure:
    """Contributes the faults section to the run summary (the run assembly plugs it in when the
    scenario has faults or replays some)."""

    def __init__(self, book, rate: int):
        self.book = book
        self.rate = rate

    def section(self) -> FaultsSection:
        return FaultsSection(tuple(self.book.log), self.rate)


class Score:
    """Judges a scenario's exercise on the plant's figures and the faults that began: contributes
    the summary's `exercise` section and, to `planthub test`, an outcome per goal and one for the
    score (Simulation.check)."""

    def __init__(self, exercise: Exercise, figures: list, book, rate: int):
        self.exercise = exercise
        self.figures = figures   # the run's contributed figures: the plant's tally among them
        self.book = book
        self.rate = rate

    def section(self) -> ExerciseSection:
        plant = next(s for f in self.figures if f is not self and hasattr(f, "section")
                     and (s := f.section()).key == "plant")
        faults = [(f.name, f.start / self.rate) for f in self.book.log]
        return ExerciseSection(self.exercise, tuple(judge(g, plant, faults) for g in self.exercise.goals))

    def outcomes(self, tick: int) -> list[Outcome]:
        section = self.section()
        out = [Outcome(v.goal, v.met, v.message) for v in section.verdicts]
        out.append(Outcome(_ScoreCase(SCORE, section.exercise.passing, self.exercise.line), section.passed,
                           section.score_line()))
        return out


@dataclass(frozen=True)
class _ScoreCase:
    """The score as a judged case: it passes at the exercise's `pass` %."""

    name: str
    passing: float
    line: int | None = None

    def describe(self) -> str:
        return f"a score of at least {self.passing:g} %"

    def settled(self, passed: bool) -> bool:
        """An interrupted run's score is not judged: the rest of the run could change it."""
        return False
