"""Reads YAML keeping the line of every value, and rejects duplicate keys instead of dropping one."""
from __future__ import annotations

from pathlib import Path

import yaml
from yaml.constructor import SafeConstructor

from hub.core.errors import Problem, format_path  # noqa: F401 (format_path: re-exported for the checker)

Lines = dict[tuple, int]


def load_yaml(path: Path) -> tuple[object, Lines, list[Problem]]:
    """Parse `path`; return the data, a map (path tuple → 1-based line) and any problems found.

    On a syntax error the data is None and the one problem names the line and column.
    """
    file = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        return None, {}, [Problem(file, None, "", f"cannot read the file: {exc.strerror}")]
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark else None
        where = f" (column {mark.column + 1})" if mark else ""
        return None, {}, [Problem(file, line, "", f"not valid YAML{where}: {exc.problem}")]
    if node is None:
        return None, {}, [Problem(file, 1, "", "the file is empty")]
    reader = _Reader(file)
    data = reader.value(node, ())
    return data, reader.lines, reader.problems


class _Reader:
    def __init__(self, file: str):
        self.file = file
        self.lines: Lines = {}
        self.problems: list[Problem] = []
        self._scalars = SafeConstructor()

    def value(self, node, path: tuple, line: int | None = None):
        # A mapping entry is placed at its key's line, which is where a reader looks for it.
        self.lines[path] = line or node.start_mark.line + 1
        if isinstance(node, yaml.MappingNode):
            out = {}
            for key_node, value_node in node.value:
                key = self._scalars.construct_object(key_node)
                if not isinstance(key, str) and isinstance(key_node, yaml.ScalarNode):
                    # Every key of a scenario is a name; YAML 1.1 reads `off`, `yes`, `null`, `12` otherwise.
                    self.problems.append(Problem(
                        self.file, key_node.start_mark.line + 1, format_path(path + (key_node.value,)),
                        f"YAML reads the name {key_node.value} as {_kind(key)} {key!r}: "
                        f"write it in quotes ('{key_node.value}')"))
                    key = key_node.value
                if key in out:
                    first = self.lines[path + (key,)]
                    self.problems.append(Problem(
                        self.file, key_node.start_mark.line + 1, format_path(path + (key,)),
                        f"duplicate name {key!r} (first defined at line {first})"))
                    continue
                out[key] = self.value(value_node, path + (key,), key_node.start_mark.line + 1)
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.value(item, path + (i,)) for i, item in enumerate(node.value)]
        return self._scalars.construct_object(node)


def _kind(value) -> str:
    if isinstance(value, bool):
        return "the boolean"
    if value is None:
        return "the empty value"
    return f"the {type(value).__name__}"


def line_of(lines: Lines, path: tuple) -> int | None:
    """The line of `path`, or of its nearest ancestor that has one."""
    path = tuple(path)
    while path not in lines and path:
        path = path[:-1]
    return lines.get(path)
