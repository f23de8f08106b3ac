"""`planthub describe`: the modules, and one module's parameters — each with its form, read from its schema, and an example for lists and mappings — and slots."""
from __future__ import annotations

import sys

import yaml

from hub.cli.exits import UsageError
from hub.core.registry import UnknownModule, default_registry

_NOUNS = {"number": ("a number", "numbers"), "integer": ("an integer", "integers"),
          "string": ("a string", "strings"), "boolean": ("true or false", "booleans (true or false)")}
_INDENT = " " * 17   # under the description column


def describe(module_name: str | None) -> int:
    registry = default_registry()
    if not module_name:
        for name in registry.names():
            doc = (registry.get(name).__doc__ or "").strip().splitlines()
            print(f"{name:<16} {doc[0] if doc else ''}")
        return 0
    try:
        module = registry.get(module_name)
    except UnknownModule as exc:
        raise UsageError(str(exc)) from None
    print(f"{module_name}: {(sys.modules[module.__module__].__doc__ or module.__doc__ or '').strip()}")
    print("\nparameters:")
    props = module.PARAMETERS.get("properties", {})
    required = set(module.PARAMETERS.get("required", []))
    for name, schema in props.items():
        default = "required" if name in required else f"default {schema['default']!r}" if "default" in schema else "optional"
        print(f"  {name:<14} {default:<18} {schema.get('description', '')}".rstrip())
        print(f"{_INDENT}form: {form(schema)}")
        if schema.get("type") in ("array", "object"):
            print(f"{_INDENT}e.g.  {name}: {as_yaml(example(schema))}")
    slots = module.reference_slots()
    if slots:
        print("\nslots:")
    for comp, slot in slots:
        kind = slot.type if isinstance(slot.type, str) else slot.type.value
        print(f"  {comp + '.' + slot.name:<22} {kind:<7} {slot.direction.value:<7} {slot.doc}")
    return 0


def form(schema: dict, plural: bool = False) -> str:
    """What a value of `schema` looks like, in words: `a list of 3 numbers > 0`."""
    if "enum" in schema:
        values = ", ".join(as_yaml(v) for v in schema["enum"])
        return f"{'each ' if plural else ''}one of {values}"
    kind = schema.get("type")
    if kind == "array":
        return _list_form(schema, plural)
    if kind == "object":
        return ("mappings " if plural else "a mapping ") + _mapping_form(schema)
    if kind not in _NOUNS:
        return "any YAML values" if plural else "any YAML value"
    noun = _NOUNS[kind][plural]
    if kind == "string":
        if schema.get("x-path"):
            return "file paths" if plural else "a file path, relative to the scenario file"
        if "x-object" in schema:
            modules = " or ".join(schema["x-object"])
            return f"names of {modules} objects" if plural else f"the name of a {modules} object declared before"
        if "pattern" in schema:
            return ("names" if plural else "a name") + " (letters, digits and _, not starting with a digit)"
        if schema.get("minLength"):
            return "non-empty strings" if plural else "a non-empty string"
    bounds = [f"{sign} {schema[key]:g}" for key, sign in (("minimum", "≥"), ("exclusiveMinimum", ">"),
                                                          ("maximum", "≤"), ("exclusiveMaximum", "<")) if key in schema]
    return noun + (" " + ", ".join(bounds) if bounds else "")


def _list_form(schema: dict, plural: bool) -> str:
    low, high = schema.get("minItems"), schema.get("maxItems")
    if low is not None and low == high:
        count = f"{low} "
    elif low and high:
        count = f"{low} to {high} "
    elif low == 1:
        count = "one or more "
    elif low:
        count = f"at least {low} "
    elif high:
        count = f"at most {high} "
    else:
        count = ""
    items = form(schema.get("items", {}), plural=True)
    each = ", each once" if schema.get("uniqueItems") else ""
    return f"{'lists' if plural else 'a list'} of {count}{items}{each}"


def _mapping_form(schema: dict) -> str:
    props = schema.get("properties")
    if props:
        required = set(schema.get("required", []))
        parts = [f"{k}: {form(v)}" + (" (required)" if k in required else "") for k, v in props.items()]
        return "{" + "; ".join(parts) + "}"
    values = schema.get("additionalProperties")
    if isinstance(values, dict):
        return f"of names to {form(values, plural=True)}"
    return "(any keys and values)"


def example(schema: dict):
    """A value that fits `schema`: its own `examples` (JSON Schema's annotation) first, then a
    default that shows something, else one made from the schema's form."""
    if schema.get("examples"):
        return schema["examples"][0]
    if schema.get("default") not in (None, [], {}, ""):
        return schema["default"]
    if "enum" in schema:
        return schema["enum"][0]
    kind = schema.get("type")
    if kind == "array":
        count = max(schema.get("minItems", 1), 1)
        return [example(schema.get("items", {})) for _ in range(count)]
    if kind == "object":
        if "properties" in schema:
            return {k: example(v) for k, v in schema["properties"].items()}
        values = schema.get("additionalProperties")
        return {"name": example(values) if isinstance(values, dict) else "value"}
    if kind in ("number", "integer"):
        low = schema.get("minimum", schema.get("exclusiveMinimum", 0))
        value = low + (1 if "exclusiveMinimum" in schema or low == 0 and kind == "integer" else 0)
        return int(value) if kind == "integer" else float(value)
    if kind == "boolean":
        return True
    return "name" if kind == "string" else None


def as_yaml(value) -> str:
    """A value as it is written in a scenario: YAML, on one line."""
    text = yaml.safe_dump(value, default_flow_style=True, sort_keys=False, allow_unicode=True, width=10**6).strip()
    return text.removesuffix("\n...").removesuffix(" ...")
