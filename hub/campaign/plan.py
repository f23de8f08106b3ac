"""A campaign file read and checked, every problem with file and line, and expanded into its cases."""
from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, replace
from pathlib import Path

import jsonschema

from hub.core.errors import CheckpointError, Problem, ScenarioError, format_path
from hub.core.registry import did_you_mean
from hub.core.resources import SCHEMAS
from hub.run import checkpoint
from hub.scenario.checker import load_scenario
from hub.scenario.extends import read_document
from hub.scenario.yamlsource import line_of, load_yaml

DEFAULT_TIME_LIMIT = 600.0   # s: the schema's default; no case waits without a limit


class CampaignError(ScenarioError):
    """A campaign file, or a case it makes, does not pass its checks; every problem listed."""

    def __init__(self, problems: list[Problem]):
        super().__init__(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        count = len(self.problems)
        self.args = (f"{count} problem{'s' if count != 1 else ''} in campaign:\n{lines}",)


@dataclass(frozen=True)
class Case:
    """One run of a campaign: a scenario with its `--set` values. `index` orders the cases the same
    way for every number of workers; `label` names it by its parameters (JUnit, the table)."""

    index: int
    scenario: Path                           # absolute
    scenario_name: str
    parameters: tuple[tuple[str, object], ...]   # (key, value), as --set gives them, run.seed last
    expect: tuple                            # the scenario's own entries and the campaign's, as YAML data
    time_limit: float
    resume: Path | None

    @property
    def label(self) -> str:
        inner = ", ".join(f"{key}={json.dumps(value)}" for key, value in self.parameters)
        return f"{self.scenario_name}[{inner}]"

    @property
    def folder(self) -> str:
        """The case's run folder under the campaign's, by index: names by parameters get long."""
        return f"cases/{self.index:03d}-{self.scenario_name}"

    def overrides(self) -> dict:
        found = dict(self.parameters)
        if self.expect:
            found["expect"] = list(self.expect)
        return found


@dataclass(frozen=True)
class Campaign:
    path: Path
    name: str
    cases: tuple[Case, ...]


def load_campaign(path) -> Campaign:
    """Read and check a campaign file and every case it makes (each scenario loaded with the
    case's values); a ScenarioError lists every problem at once."""
    path = Path(path)
    data, lines, problems = load_yaml(path)
    if data is None:
        raise CampaignError(problems)
    checker = _Checker(path, lines, problems)
    schema = json.loads((SCHEMAS / "campaign.schema.json").read_text())
    checker.validate(data, schema)
    if not isinstance(data, dict) or checker.problems:
        raise CampaignError(checker.problems)
    return checker.expand(data)


class _Checker:
    def __init__(self, path: Path, lines, problems: list[Problem]):
        self.path = path
        self.file = str(path)
        self.lines = lines
        self.problems = list(problems)

    def problem(self, at: tuple, message: str) -> None:
        found = Problem(self.file, line_of(self.lines, at), format_path(at), message)
        if found not in self.problems:   # one wrong value is found in every case that uses it
            self.problems.append(found)

    def validate(self, data, schema: dict) -> None:
        validator = jsonschema.Draft202012Validator(schema)
        for error in sorted(validator.iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path]):
            at = tuple(error.absolute_path)
            if error.validator == "additionalProperties" and "properties" in error.schema:
                known = error.schema["properties"]
                for key in sorted(set(error.instance) - set(known)):
                    self.problem(at + (key,), f"unknown key {key!r}{did_you_mean(key, known)}")
            elif error.validator == "required":
                self.problem(at, error.message.replace("is a required property", "is missing"))
            elif "propertyNames" in error.schema_path:
                self.problem(at + (error.instance,), f"{error.instance!r} is not a dotted key of a scenario "
                                                     "(as --set takes it, e.g. objects.belt.speed)")
            elif error.validator == "oneOf" and at == ("seeds",):
                self.problem(at, "expected a number of seeds (1 or more) or a list of different seeds (0 or more)")
            else:
                self.problem(at, error.message)

    def expand(self, data: dict) -> Campaign:
        self.data = data
        base = self.path.parent
        matrix, zipped = data.get("matrix", {}), data.get("zip", {})
        for key in sorted(set(matrix) & set(zipped)):
            self.problem(("zip", key), f"{key} is in `matrix` too: give its values in one of them")
        lengths = {key: len(values) for key, values in zipped.items()}
        if len(set(lengths.values())) > 1:
            said = ", ".join(f"{key}: {n}" for key, n in lengths.items())
            self.problem(("zip",), f"the lists of `zip` are taken pairwise and need one length; they have {said}")
        if "seeds" in data and "run.seed" in {*matrix, *zipped}:
            where = "matrix" if "run.seed" in matrix else "zip"
            self.problem((where, "run.seed"), "run.seed is given by `seeds` too: give the seeds in one place")
        if self.problems:   # cases of a matrix that does not hold together would only repeat it
            raise CampaignError(self.problems)
        resume = self.checkpoint = None
        if "from" in data:
            resume = (base / data["from"]).resolve()
            if not resume.is_file():
                self.problem(("from",), f"no checkpoint file {data['from']!r} (looked for {resume})")
            else:
                try:
                    self.checkpoint, _ = checkpoint.header(checkpoint.read(resume), data["from"])
                except CheckpointError as exc:
                    self.problem(("from",), str(exc))
        seeds = data.get("seeds")
        seeds = list(range(seeds)) if isinstance(seeds, int) else seeds
        combos = self.combinations(matrix, zipped)
        time_limit = float(data.get("time_limit", DEFAULT_TIME_LIMIT))
        cases = []
        for n, entry in enumerate(data["scenarios"]):
            scenario = (base / entry).resolve()
            if not scenario.is_file():
                self.problem(("scenarios", n), f"no scenario file {entry!r} (looked for {scenario})")
                continue
            own, _ = read_document(scenario)
            own_expect = own.data.get("expect", []) if own is not None and isinstance(own.data, dict) else []
            for combo in combos:
                for seed in seeds or [None]:
                    parameters = tuple(combo) + ((("run.seed", seed),) if seed is not None else ())
                    expect = tuple(own_expect if isinstance(own_expect, list) else []) + tuple(data.get("expect", []))
                    case = Case(len(cases), scenario, scenario.stem, parameters, expect, time_limit, resume)
                    name = self.check_case(case, n, entry, len(own_expect) if isinstance(own_expect, list) else 0)
                    cases.append(replace(case, scenario_name=name))
        if self.problems:
            raise CampaignError(self.problems)
        return Campaign(self.path, data.get("name", self.path.stem), tuple(cases))

    @staticmethod
    def combinations(matrix: dict, zipped: dict) -> list[list[tuple[str, object]]]:
        """Every combination of the matrix (full product, in file order) with every pair of `zip`."""
        product = [list(zip(matrix, values)) for values in itertools.product(*matrix.values())]
        count = min((len(v) for v in zipped.values()), default=1)
        pairs = [[(key, values[i]) for key, values in zipped.items()] for i in range(count)]
        return [m + z for m in product for z in pairs]

    def check_case(self, case: Case, n: int, entry: str, own_count: int) -> str:
        """Load the case's scenario with its values; its problems reported at the campaign's line
        that caused them (a matrix value, an expectation) where one did. The scenario's name."""
        try:
            scenario = load_scenario(case.scenario, case.overrides(), blame=False)
        except ScenarioError as exc:
            for problem in exc.problems:
                self.problem(*self.cause(problem, case, n, entry, own_count))
            return case.scenario.stem
        if self.checkpoint is not None and checkpoint.fingerprint(scenario) != self.checkpoint.fingerprint:
            self.misfit(case)
        return scenario.name

    def misfit(self, case: Case) -> None:
        """A case whose plant is not the one `from:`'s checkpoint was taken of: named at the values
        that change it, each tried alone on the scenario."""
        head = self.checkpoint
        fixed = (f"the checkpoint `from:` was taken of {head.scenario!r} as it was (only the duration, the "
                 "expectations, the recording, the logic's parameters and where logic runs may differ)")
        culprits = [(key, value) for key, value in case.parameters if self.changes(case.scenario, key, value)]
        for key, value in culprits:
            self.problem(self.value_place(key, value), f"{key}={json.dumps(value)} changes the plant: {fixed}")
        if not culprits:
            self.problem(("from",), f"{case.label} is another plant: {fixed}")

    def changes(self, scenario: Path, key: str, value) -> bool:
        """Whether `key: value` alone gives `scenario` another fingerprint than the checkpoint's."""
        try:
            alone = load_scenario(scenario, {key: value})
        except ScenarioError:   # reported with the case that has it
            return False
        return checkpoint.fingerprint(alone) != self.checkpoint.fingerprint

    def cause(self, problem: Problem, case: Case, n: int, entry: str, own_count: int) -> tuple[tuple, str]:
        where = f"in {entry}: "
        for key, value in case.parameters:
            if problem.path == key or problem.path.startswith((key + ".", key + "[")):
                place = self.value_place(key, value)
                return place, f"{where}{problem.path}: {problem.message}"
        if problem.path.startswith("expect["):
            k = int(problem.path[len("expect["):problem.path.index("]")])
            if k >= own_count:   # one of the campaign's, after the scenario's own
                return ("expect", k - own_count), f"{where}{problem.path}: {problem.message}"
        return ("scenarios", n), f"{where}{problem}"

    def value_place(self, key: str, value) -> tuple:
        """Where a case's value of `key` is written in the campaign file: its place in `matrix` or
        `zip`, else `seeds`."""
        for section in ("matrix", "zip"):
            values = self.data.get(section, {}).get(key)
            if values is not None:
                return (section, key, values.index(value)) if value in values else (section, key)
        return ("seeds",) if key == "run.seed" else ("scenarios",)
