"""Read the compact YAML form of a net (*.net.yaml) into a Document."""

import re

import yaml

from .document import Document

_BOOL_TAG = "tag:yaml.org,2002:bool"


class _Loader(yaml.SafeLoader):
    """YAML 1.2 booleans: only true/false. Under YAML 1.1 a place named On, Off, Yes or No would turn into a bool."""


_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != _BOOL_TAG]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver(_BOOL_TAG, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF"))


def read(path, problems):
    """The Document of the YAML net at path, or None if it is not readable YAML (the cause is in problems)."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        problems.add(1, f"cannot read the file: {error}")
        return None
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            problems.add(1, "the file is empty: expected a mapping with 'places' and 'transitions'")
            return None
        document = Document(None)
        document.data = _convert(loader, node, (), document.lines, problems)
        return document
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None) or getattr(error, "context_mark", None)
        reason = getattr(error, "problem", None) or str(error)
        problems.add(mark.line + 1 if mark else 1, f"not valid YAML: {reason}")
        return None
    finally:
        loader.dispose()


def _convert(loader, node, path, lines, problems):
    lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        result, first_line = {}, {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                problems.add(key_node.start_mark.line + 1, "a key must be a plain name")
                continue
            # Keys are names here: keep them as written (a place called 1 or null stays a string).
            key, line = key_node.value, key_node.start_mark.line + 1
            if key in result:
                # PyYAML would silently keep the last one: a second place of the same name would vanish.
                problems.add(line, f"duplicate key '{key}' (first at line {first_line[key]})")
                continue
            first_line[key] = line
            lines[path + (key,)] = line
            result[key] = _convert(loader, value_node, path + (key,), lines, problems)
        return result
    if isinstance(node, yaml.SequenceNode):
        return [_convert(loader, item, path + (index,), lines, problems) for index, item in enumerate(node.value)]
    return loader.construct_object(node)
