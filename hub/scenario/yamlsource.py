"""Reads YAML as YAML 1.2 reads it, keeping the line of every value; duplicate keys, bad bytes, unknown tags, deep nesting and alias bombs become problems, not tracebacks."""
from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import yaml
from yaml.constructor import ConstructorError, SafeConstructor

from hub.core.errors import Problem, format_path  # noqa: F401 (format_path: re-exported for the checker)

Lines = dict[tuple, int]

#: Nesting deeper than this is refused: PyYAML composes recursively, and no scenario nests
#: more than about 8 levels.
MAX_DEPTH = 64
#: Values read, counting each alias expansion: a 508-byte file of nested aliases expands to
#: 43 million values; the bottling plant, the largest scenario that ships, has about 2 000.
MAX_VALUES = 200_000


class _Resolver(yaml.resolver.BaseResolver):
    """YAML 1.2's core schema: `yes`, `no`, `on`, `off` are strings, `1e6` is a number, a date is
    a string; `true`/`false`, `null`/`~`, decimal, 0o octal and 0x hex integers, floats with
    `.inf` and `.nan`."""


_Resolver.add_implicit_resolver("tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
                                list("tTfF"))
_Resolver.add_implicit_resolver("tag:yaml.org,2002:null", re.compile(r"^(?:~|null|Null|NULL|)$"), ["~", "n", "N", ""])
_Resolver.add_implicit_resolver("tag:yaml.org,2002:int", re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"),
                                list("-+0123456789"))
_Resolver.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+0123456789."))


class _Constructor(SafeConstructor):
    """Scalars of the core schema (no timestamps, no sexagesimal or 0b numbers, no merge keys)."""

    def construct_yaml_int(self, node):
        text = self.construct_scalar(node)
        if text.startswith("0o"):
            return int(text[2:], 8)
        if text.startswith("0x"):
            return int(text[2:], 16)
        return int(text)

    def construct_yaml_float(self, node):
        text = self.construct_scalar(node).lower()
        if text.endswith(".inf"):
            return -math.inf if text.startswith("-") else math.inf
        if text == ".nan":
            return math.nan
        return float(text)


_Constructor.add_constructor("tag:yaml.org,2002:int", _Constructor.construct_yaml_int)
_Constructor.add_constructor("tag:yaml.org,2002:float", _Constructor.construct_yaml_float)
_Constructor.yaml_constructors = {tag: fn for tag, fn in _Constructor.yaml_constructors.items()
                                  if tag not in ("tag:yaml.org,2002:timestamp", "tag:yaml.org,2002:binary",
                                                 "tag:yaml.org,2002:set", "tag:yaml.org,2002:omap",
                                                 "tag:yaml.org,2002:pairs")}


class _Loader(yaml.reader.Reader, yaml.scanner.Scanner, yaml.parser.Parser, yaml.composer.Composer,
              _Constructor, _Resolver):
    """Composes node trees at most MAX_DEPTH deep."""

    def __init__(self, stream):
        yaml.reader.Reader.__init__(self, stream)
        yaml.scanner.Scanner.__init__(self)
        yaml.parser.Parser.__init__(self)
        yaml.composer.Composer.__init__(self)
        _Constructor.__init__(self)
        _Resolver.__init__(self)
        self._depth = 0

    def compose_node(self, parent, index):
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise yaml.composer.ComposerError(None, None, f"the document nests deeper than {MAX_DEPTH} levels",
                                                  self.peek_event().start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


class _TooMany(Exception):
    pass


@functools.lru_cache(maxsize=32)
def _compose(text: str):
    """The node tree of one YAML document (None: empty); YAMLError if it is not one. The tree is
    only read (values are made from it afresh each time), so a text composed once serves every
    later read of the same text: the second load of a scenario in one process, and each case a
    campaign's zygote forks after its warm-up (PyYAML's composer is pure Python)."""
    loader = _Loader(text)
    try:
        return loader.get_single_node()
    finally:
        loader.dispose()


def read_value(text: str):
    """One value written as YAML 1.2 (a `--set KEY=VALUE` value): `1e6` is a number, `yes` a string.
    Raises ValueError naming the cause."""
    try:
        node = _compose(text)
    except yaml.YAMLError as exc:
        raise ValueError(f"not valid YAML: {getattr(exc, 'problem', None) or exc}") from None
    if node is None:
        return None
    reader = _Reader("--set")
    try:
        value = reader.value(node, ())
    except _TooMany:
        raise ValueError(f"the value expands to more than {MAX_VALUES} values (aliases of aliases?)") from None
    if reader.problems:
        raise ValueError(reader.problems[0].message)
    return value


def load_yaml(path: Path) -> tuple[object, Lines, list[Problem]]:
    """Parse `path`; return the data, a map (path tuple → 1-based line) and any problems found.

    On a syntax error the data is None and the one problem names the line and column.
    """
    file = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        return None, {}, [Problem(file, None, "", f"cannot read the file: {exc.strerror}")]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        return None, {}, [Problem(file, line, "", f"not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset {exc.start}")]
    try:
        node = _compose(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark else None
        where = f" (column {mark.column + 1})" if mark else ""
        return None, {}, [Problem(file, line, "", f"not valid YAML{where}: {exc.problem}")]
    except yaml.reader.ReaderError as exc:   # a control character, a NUL
        line = text[:exc.position].count("\n") + 1
        return None, {}, [Problem(file, line, "", f"not valid YAML: {_character(exc.character)} "
                                                  "is not allowed in a YAML file")]
    except yaml.YAMLError as exc:
        return None, {}, [Problem(file, None, "", f"not valid YAML: {exc}")]
    if node is None:
        return None, {}, [Problem(file, 1, "", "the file is empty")]
    reader = _Reader(file)
    try:
        data = reader.value(node, ())
    except _TooMany:
        return None, {}, [Problem(file, None, "", f"the document expands to more than {MAX_VALUES} values "
                                                  "(aliases of aliases?); a scenario needs far fewer")]
    return data, reader.lines, reader.problems


def _character(char) -> str:
    code = ord(char) if isinstance(char, str) else char   # PyYAML gives the code point
    return f"the character U+{code:04X}"


class _Reader:
    def __init__(self, file: str):
        self.file = file
        self.lines: Lines = {}
        self.problems: list[Problem] = []
        self._scalars = _Constructor()
        self._count = 0
        self._open: set[int] = set()   # the nodes being read (an alias back into one is a loop)

    def value(self, node, path: tuple, line: int | None = None):
        self._count += 1
        if self._count > MAX_VALUES:
            raise _TooMany
        # A mapping entry is placed at its key's line, which is where a reader looks for it.
        self.lines[path] = line or node.start_mark.line + 1
        if isinstance(node, (yaml.MappingNode, yaml.SequenceNode)):
            if id(node) in self._open:
                self.problems.append(Problem(
                    self.file, self.lines[path], format_path(path),
                    f"an alias refers to a value that holds it (defined at line {node.start_mark.line + 1}): "
                    "a scenario is a tree, so an alias may only repeat a value defined before and outside it"))
                return None
            self._open.add(id(node))
            try:
                return self._collection(node, path)
            finally:
                self._open.discard(id(node))
        return self.scalar(node, path)

    def _collection(self, node, path: tuple):
        if isinstance(node, yaml.MappingNode):
            out = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    self.problems.append(Problem(
                        self.file, key_node.start_mark.line + 1, format_path(path),
                        "a key must be a name, not a list or a mapping (a YAML `? ` complex key)"))
                    continue
                key = self.scalar(key_node, path)
                if not isinstance(key, str):
                    # Every key of a scenario is a name; YAML reads `true`, `null`, `12` otherwise.
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
        return [self.value(item, path + (i,)) for i, item in enumerate(node.value)]

    def scalar(self, node, path: tuple):
        try:
            return self._scalars.construct_object(node)
        except (ConstructorError, ValueError) as exc:   # an unknown tag (`!custom`), a malformed number
            problem = getattr(exc, "problem", None) or str(exc)
            self.problems.append(Problem(self.file, node.start_mark.line + 1, format_path(path),
                                         f"cannot read {node.value!r}: {problem}"))
            return node.value if isinstance(node.value, str) else None


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
