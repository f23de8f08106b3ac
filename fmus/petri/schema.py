"""Check a net Document against schemas/net.schema.json and word each violation for a user."""

import json
from functools import lru_cache
from pathlib import Path

import jsonschema

from .problems import did_you_mean


def _find_schema() -> Path:
    """schemas/net.schema.json in the nearest folder above this package: the repository's top
    level, or wherever the package was copied with it (e.g. into an FMU's resources)."""
    for folder in Path(__file__).resolve().parents:
        if (folder / "schemas" / "net.schema.json").is_file():
            return folder / "schemas" / "net.schema.json"
    raise FileNotFoundError("schemas/net.schema.json not found above " + str(Path(__file__).parent))


SCHEMA_PATH = _find_schema()

_TYPE_WORDS = {"integer": "an integer", "number": "a number", "string": "a string", "object": "a mapping",
               "array": "a list", "boolean": "true or false"}


@lru_cache(maxsize=1)
def _validator():
    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def check(document, problems):
    """Add every schema violation of document to problems, each at the line of the entry it concerns."""
    errors = sorted(_validator().iter_errors(document.data), key=lambda e: [str(p) for p in e.absolute_path])
    for error in errors:
        for path, text in _explain(error):
            problems.add(document.line(path), text)


def where(path):
    """The entry at path in words: place 'B326', transition 'mtb': in, ..."""
    path = tuple(path)
    if not path:
        return "net"
    head = {"places": "place", "transitions": "transition"}.get(path[0])
    if head is None or len(path) == 1:
        return " ".join(str(p) for p in path)
    words = f"{head} '{path[1]}'"
    rest = path[2:]
    if len(rest) > 1 and rest[0] in ("in", "out", "inhibit") and isinstance(rest[1], str):
        return f"{words}: {rest[0]} arc to '{rest[1]}': weight"
    if rest:
        words += f": {rest[0]}"
    if len(rest) > 1:
        words += f"[{rest[1]}]"
    return words


def _explain(error):
    """[(path, text)] for one validation error."""
    path = tuple(error.absolute_path)
    if len(path) == 2 and path[0] == "places" and error.validator in ("minimum", "maximum"):
        path += ("marking",)  # the short form: the value is the marking
    if "propertyNames" in error.schema_path:
        # The instance is the offending key; point at the key's own line.
        kind = {"places": "place", "transitions": "transition"}.get(path[0] if path else None, "key")
        key_path = path + (error.instance,)
        if error.validator == "pattern":
            return [(key_path, f"{kind} name '{error.instance}' is not a C identifier (letters, digits and _, "
                               "not starting with a digit): it becomes part of the FMU's variable names")]
        return [(key_path, f"{kind} name '{error.instance}': {error.message}")]
    if error.validator == "additionalProperties":
        allowed = list(error.schema.get("properties", {}))
        unexpected = [key for key in error.instance if key not in allowed]
        return [(path + (key,), f"{where(path)}: unknown key '{key}'"
                 + (did_you_mean(key, allowed) or f" (allowed: {', '.join(allowed)})")) for key in unexpected]
    if error.validator == "required":
        return [(path, f"{where(path)}: {error.message.replace(' is a required property', ' is missing')}")]
    if error.validator == "uniqueItems":
        repeated = sorted({item for item in error.instance if error.instance.count(item) > 1})
        return [(path, f"{where(path)}: {', '.join(repr(r) for r in repeated)} listed more than once "
                       "(write a mapping place: weight for an arc that moves several tokens)")]
    if error.validator in ("oneOf", "anyOf") and error.context:
        # Each alternative that failed on the instance's own type says nothing useful; explain the others.
        relevant = [e for e in error.context if not (e.validator == "type" and not e.relative_path)]
        if relevant:
            return [item for e in relevant for item in _explain(e)]
        expected = [_TYPE_WORDS.get(e.validator_value, e.validator_value) for e in error.context]
        return [(path, f"{where(path)}: {error.instance!r} is neither {' nor '.join(expected)}")]
    if error.validator == "minimum":
        bound = error.validator_value
        text = "must not be negative" if bound == 0 else f"must be at least {bound}"
        return [(path, f"{where(path)} {text}, got {error.instance!r}")]
    if error.validator == "minProperties":
        return [(path, f"{where(path)}: the net needs at least one place")]
    if error.validator == "type":
        expected = _TYPE_WORDS.get(error.validator_value, error.validator_value)
        return [(path, f"{where(path)}: {error.instance!r} is not {expected}")]
    return [(path, f"{where(path)}: {error.message}")]
