"""Read and check a model's model.yaml: the single source of its variables, value references and state."""

import difflib
import hashlib
import json
import math
import re
import uuid
from dataclasses import dataclass
from pathlib import Path

import yaml

TYPES = ("real", "int", "bool", "string")
STATE_TYPES = ("real", "int32", "int64", "bool")

# causality -> (allowed variabilities, default for real, default for the other types)
VARIABILITIES = {
    "parameter": (("fixed", "tunable"), "fixed", "fixed"),
    "input": (("discrete", "continuous"), "continuous", "discrete"),
    "output": (("discrete", "continuous"), "continuous", "discrete"),
    "local": (("discrete", "continuous"), "continuous", "discrete"),
}

MODEL_KEYS = ("name", "description", "fmi_versions", "default_experiment", "variables", "state")
VARIABLE_KEYS = ("name", "type", "causality", "variability", "start", "description", "unit", "min", "max")
STATE_KEYS = ("name", "type", "description")
EXPERIMENT_KEYS = ("start_time", "stop_time", "step_size", "tolerance")

# Names become C struct members and VR_<NAME> enumerators.
C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while "
    "_Bool _Complex _Imaginary bool true false".split())
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


class DescriptionError(Exception):
    """Every problem found in model descriptions, one per line, each naming the file and line."""

    def __init__(self, problems):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


@dataclass(frozen=True)
class Variable:
    name: str
    type: str
    causality: str
    variability: str
    start: object  # None: initial="calculated", the model's initialize hook computes it
    description: str
    unit: str | None
    min: float | int | None
    max: float | int | None
    vr: int


@dataclass(frozen=True)
class StateField:
    name: str
    type: str
    description: str


@dataclass(frozen=True)
class Model:
    name: str
    description: str
    fmi_versions: tuple
    default_experiment: dict
    variables: tuple  # variables[vr]; variables[0] is time
    state: tuple
    token: str
    source: str


TIME = Variable("time", "real", "independent", "continuous", None, "Simulation time", "s", None, None, 0)


class _Entry(dict):
    """A YAML mapping that remembers the line it starts on."""

    line = 0


class _Loader(yaml.SafeLoader):
    pass


def _construct_entry(loader, node):
    keys = [loader.construct_object(key) for key, _ in node.value]
    for key in keys:
        if keys.count(key) > 1:
            # PyYAML would silently keep the last one, e.g. of two start: lines.
            raise yaml.constructor.ConstructorError(None, None, f"duplicate key '{key}'", node.start_mark)
    entry = _Entry(loader.construct_mapping(node, deep=True))
    entry.line = node.start_mark.line + 1
    return entry


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_entry)


def load(model_dir):
    """The checked description in model_dir/model.yaml; DescriptionError lists every problem."""
    path = Path(model_dir) / "model.yaml"
    try:
        raw = yaml.load(path.read_text(encoding="utf-8"), Loader=_Loader)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None) or getattr(error, "context_mark", None)
        reason = getattr(error, "problem", None) or str(error)
        raise DescriptionError([f"{path}:{mark.line + 1 if mark else 1}: not valid YAML: {reason}"]) from None
    problems = []
    fields = _check_model(raw, Path(model_dir).name, problems)
    if problems:
        raise DescriptionError(f"{path}:{line}: {text}" for line, text in problems)
    # Derived from the description, so the token changes exactly when the interface does
    # and rebuilding unchanged sources gives identical FMUs.
    digest = hashlib.sha256(json.dumps(raw, sort_keys=True, default=str).encode()).hexdigest()
    return Model(token="{" + str(uuid.UUID(digest[:32])) + "}", source=str(path), **fields)


def _unknown_keys(entry, allowed, what, problems):
    for key in entry:
        if key not in allowed:
            hint = difflib.get_close_matches(str(key), allowed, n=1)
            suffix = f"did you mean '{hint[0]}'?" if hint else f"allowed: {', '.join(allowed)}"
            problems.append((entry.line, f"{what}: unknown key '{key}' ({suffix})"))


def _choice(value, allowed, what, line, problems):
    if value in allowed:
        return True
    hint = difflib.get_close_matches(str(value), allowed, n=1)
    suffix = f"did you mean '{hint[0]}'?" if hint else f"expected one of {', '.join(allowed)}"
    problems.append((line, f"{what} is '{value}': {suffix}"))
    return False


def _check_identifier(name, what, line, problems):
    if not isinstance(name, str) or not IDENTIFIER.match(name) or name in C_KEYWORDS:
        problems.append((line, f"{what} '{name}' is not a C identifier or is a C keyword"))
        return False
    return True


def _is_finite_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_model(raw, dir_name, problems):
    if not isinstance(raw, _Entry):
        problems.append((1, f"expected a mapping with the keys {', '.join(MODEL_KEYS)}"))
        return None
    _unknown_keys(raw, MODEL_KEYS, "model", problems)
    name = raw.get("name")
    if _check_identifier(name, "model name", raw.line, problems) and name != dir_name:
        problems.append((raw.line, f"model name '{name}' must equal its directory name '{dir_name}'"))
    versions = raw.get("fmi_versions", [2, 3])
    if not isinstance(versions, list) or not versions or any(v not in (2, 3) for v in versions):
        problems.append((raw.line, f"fmi_versions is {versions!r}: expected a non-empty list of 2 and/or 3"))
        versions = []
    experiment = raw.get("default_experiment", _Entry())
    if not isinstance(experiment, _Entry):
        problems.append((raw.line, "default_experiment must be a mapping"))
        experiment = _Entry()
    _unknown_keys(experiment, EXPERIMENT_KEYS, "default_experiment", problems)
    for key, value in experiment.items():
        if not _is_finite_number(value):
            problems.append((experiment.line, f"default_experiment: {key} must be a finite number"))
    return dict(name=name, description=str(raw.get("description", "")), fmi_versions=tuple(sorted(set(versions))),
                default_experiment=dict(experiment),
                variables=_check_variables(raw.get("variables"), raw.line, problems),
                state=_check_state(raw.get("state", []), raw.line, problems))


def _check_variables(entries, line, problems):
    """Time first, then the declared variables: the position is the value reference."""
    if not isinstance(entries, list) or not entries:
        problems.append((line, "variables must be a non-empty list"))
        return (TIME,)
    variables, taken = [TIME], {"TIME"}
    for entry in entries:
        if not isinstance(entry, _Entry):
            problems.append((line, f"each variable must be a mapping, got {entry!r}"))
            continue
        variable = _check_variable(entry, len(variables), problems)
        if variable is None:
            continue
        if variable.name.upper() in taken:  # VR_<NAME> must be unique too
            problems.append((entry.line, f"variable '{variable.name}' clashes with an earlier one or with 'time'"
                             " (names must differ in more than case)"))
            continue
        taken.add(variable.name.upper())
        variables.append(variable)
    return tuple(variables)


def _check_variable(entry, vr, problems):
    count = len(problems)
    name = entry.get("name")
    what = f"variable '{name}'"
    _unknown_keys(entry, VARIABLE_KEYS, what, problems)
    _check_identifier(name, "variable name", entry.line, problems)
    type_, causality = entry.get("type"), entry.get("causality")
    if not (_choice(type_, TYPES, f"{what}: type", entry.line, problems)
            and _choice(causality, tuple(VARIABILITIES), f"{what}: causality", entry.line, problems)):
        return None
    allowed, default_real, default_other = VARIABILITIES[causality]
    variability = entry.get("variability", default_real if type_ == "real" else default_other)
    if _choice(variability, allowed, f"{what}: variability", entry.line, problems):
        if variability == "continuous" and type_ != "real":
            problems.append((entry.line, f"{what}: only real variables can be continuous"))
    start = entry.get("start")
    if start is None and causality in ("parameter", "input"):
        problems.append((entry.line, f"{what}: a {causality} needs a start value"))
    elif start is not None:
        start = _check_value(start, type_, f"{what}: start", entry.line, problems)
    bounds = {}
    for key in ("min", "max"):
        if key in entry and type_ not in ("real", "int"):
            problems.append((entry.line, f"{what}: {key} is only allowed for real and int"))
        elif key in entry:
            bounds[key] = _check_value(entry[key], type_, f"{what}: {key}", entry.line, problems)
    low, high = bounds.get("min"), bounds.get("max")
    if low is not None and high is not None and low > high:
        problems.append((entry.line, f"{what}: min {low} is greater than max {high}"))
    if type_ in ("real", "int") and start is not None:
        if (low is not None and start < low) or (high is not None and start > high):
            problems.append((entry.line, f"{what}: start {start} is outside [{low}, {high}]"))
    unit = entry.get("unit")
    if unit is not None and (type_ != "real" or not isinstance(unit, str) or not unit):
        problems.append((entry.line, f"{what}: unit must be a non-empty string on a real variable"))
    if len(problems) > count:
        return None
    return Variable(name, type_, causality, variability, start, str(entry.get("description", "")), unit, low, high,
                    vr)


def _check_value(value, type_, what, line, problems):
    if type_ == "real" and _is_finite_number(value):
        return float(value)
    if type_ == "int" and isinstance(value, int) and not isinstance(value, bool):
        if INT32_MIN <= value <= INT32_MAX:
            return value
        problems.append((line, f"{what} {value} does not fit in 32 bits"))
        return None
    if (type_ == "bool" and isinstance(value, bool)) or (type_ == "string" and isinstance(value, str)):
        return value
    expected = {"real": "a finite number", "int": "an integer", "bool": "true or false", "string": "a string"}
    problems.append((line, f"{what} {value!r} is not {expected[type_]}"))
    return None


def _check_state(entries, line, problems):
    if not isinstance(entries, list):
        problems.append((line, "state must be a list"))
        return ()
    fields, seen = [], set()
    for entry in entries:
        if not isinstance(entry, _Entry):
            problems.append((line, f"each state field must be a mapping, got {entry!r}"))
            continue
        name, type_ = entry.get("name"), entry.get("type")
        _unknown_keys(entry, STATE_KEYS, f"state field '{name}'", problems)
        valid = _check_identifier(name, "state field name", entry.line, problems)
        valid = _choice(type_, STATE_TYPES, f"state field '{name}': type", entry.line, problems) and valid
        if valid and name in seen:
            problems.append((entry.line, f"state field '{name}' is declared twice"))
        elif valid:
            seen.add(name)
            fields.append(StateField(name, type_, str(entry.get("description", ""))))
    return tuple(fields)
