"""A scenario that extends another (`extends: FILE`): one document, each value with the file and line it was written at.

The extending file's keys are laid over the scenario it names:

- a mapping merges key by key — `objects` by name, an object's parameters one by one, `run` key
  by key — and a key given `null` is taken out (`objects: {robot: null}`: the base's robot is not
  in the plant);
- the lists `flows`, `record`, `expect` and `faults` add to the base's, after them, and an item
  `{remove: ITEM}` takes the base's item equal to ITEM out (`{remove: {from: a.x.y, to: b.u.v}}`);
  any other list (a position, a participant's command) replaces the base's;
- `name` and `description` are the file's own: a scenario that gives no `name` is named after its
  file, not after its base.

The base is a scenario in the same folder, so that what its values name by relative path (an FMU,
a certificate) is found the same from either file. A base may extend another (at most
MAX_CHAIN deep); a file that comes back to itself is a problem naming the chain. Every problem
of the merged scenario names the file and line where its value was written.
"""
from __future__ import annotations

from pathlib import Path

from hub.core.errors import Problem
from hub.scenario.yamlsource import Lines, line_of, load_yaml

#: The lists an extending scenario adds to rather than replaces.
ADDED = ("flows", "record", "expect", "faults")
#: The scenario's own keys: never taken from the base.
OWN = ("name", "description", "extends")
#: Files in one chain of `extends`, the scenario's own included.
MAX_CHAIN = 8

#: Where each value was written: path tuple → (file, line).
Origins = dict[tuple, tuple[str, int]]


class Document:
    """A scenario file's data read whole, its bases merged in: `lines` and `files` give each
    path's line and file (the nearest ancestor's where a path has none of its own)."""

    def __init__(self, data, origins: Origins, file: str):
        self.data = data
        self.file = file
        self.lines: Lines = {path: line for path, (_, line) in origins.items()}
        self._files = {path: name for path, (name, _) in origins.items() if name != file}

    def file_at(self, path: tuple) -> str:
        path = tuple(path)
        while path not in self.lines and path:
            path = path[:-1]
        return self._files.get(path, self.file)


def read_document(path: Path) -> tuple[Document | None, list[Problem]]:
    """The scenario at `path` with the scenarios it extends merged in; None with the problems when
    a file of the chain cannot be read as YAML or its `extends` does not name a base that can."""
    data, origins, problems = _read(Path(path), ())
    return (None if data is None else Document(data, origins, str(path))), problems


def _read(path: Path, chain: tuple[Path, ...]) -> tuple[object, Origins, list[Problem]]:
    file = str(path)
    data, lines, problems = load_yaml(path)
    if data is None:
        return None, {}, problems
    origins = {p: (file, line) for p, line in lines.items()}
    if not isinstance(data, dict) or "extends" not in data:
        return data, origins, problems
    at = ("extends",)

    def refused(message: str):
        return None, {}, problems + [Problem(file, line_of(lines, at), "extends", message)]

    named = data["extends"]
    if not isinstance(named, str) or not named:
        return refused(f"{named!r}: give the file name of a scenario in this folder")
    base_path = path.parent / named
    here = path.resolve()
    try:
        beside = base_path.resolve().parent == here.parent
        found = beside and base_path.is_file()
    except (OSError, ValueError) as exc:   # a NUL byte, a name too long
        return refused(f"{named!r} is not a file name ({exc})")
    if not beside:
        return refused(f"{named!r} is not in this file's folder: a base is a scenario beside the one that "
                       f"extends it, so that the relative paths it holds are read from the same folder")
    if not found:
        return refused(f"no scenario file {named!r} (looked for {base_path})")
    seen = chain + (here,)
    if base_path.resolve() in seen:
        names = " → ".join(p.name for p in seen + (base_path.resolve(),))
        return refused(f"the scenarios extend each other in a ring: {names}")
    if len(seen) >= MAX_CHAIN:
        return refused(f"more than {MAX_CHAIN} scenarios in one chain of `extends`")
    base, base_origins, base_problems = _read(base_path, seen)
    problems += base_problems
    if base is None:
        return None, {}, problems
    if not isinstance(base, dict):
        return refused(f"{named!r} is not a scenario (its top level is not a mapping)")
    for key in OWN:
        if key in base:
            base = {k: v for k, v in base.items() if k != key}
            base_origins = _without(base_origins, (key,))
    own = {k: v for k, v in data.items() if k != "extends"}
    merged, merged_origins = _merge(base, base_origins, own, _without(origins, at), (), problems)
    merged_origins[()] = origins.get((), (file, 1))
    return merged, merged_origins, problems


def _merge(base, base_origins: Origins, child, child_origins: Origins, path: tuple, problems: list[Problem]):
    """`child` laid over `base` at `path`: the value and the origins of everything under `path`
    (origins elsewhere are carried through from both)."""
    if isinstance(base, dict) and isinstance(child, dict):
        out, origins = dict(base), dict(base_origins)
        for key, value in child.items():
            place = path + (key,)
            if value is None:
                out.pop(key, None)
                origins = _without(origins, place)
            elif key in base:
                out[key], sub = _merge(base[key], _under(base_origins, place), value, _under(child_origins, place),
                                       place, problems)
                origins = _without(origins, place)
                origins.update(sub)
            else:
                out[key] = value
                origins.update(_under(child_origins, place))
        if path in child_origins:
            origins[path] = child_origins[path]
        return out, origins
    if len(path) == 1 and path[0] in ADDED and isinstance(base, list) and isinstance(child, list):
        return _added(base, base_origins, child, child_origins, path, problems)
    return child, dict(child_origins)


def _added(base: list, base_origins: Origins, child: list, child_origins: Origins, path: tuple,
           problems: list[Problem]):
    """The base's items, then the child's; a child item `{remove: ITEM}` takes the base's item
    equal to ITEM out instead (a problem if the base has none)."""
    n = len(path)

    def items(values, origins):
        return [(v, {sub[n + 1:]: o for sub, o in origins.items() if len(sub) > n and sub[n] == i})
                for i, v in enumerate(values)]

    kept = items(base, base_origins)
    for value, origins in items(child, child_origins):
        if isinstance(value, dict) and set(value) == {"remove"}:
            found = [k for k, (v, _) in enumerate(kept) if v == value["remove"]]
            if found:
                del kept[found[0]]
            else:
                file, line = origins.get((), next(iter(origins.values()), ("", None)))
                problems.append(Problem(file, line, path[0], f"removes nothing: the base's {path[0]} hold no "
                                                             f"{value['remove']!r}"))
            continue
        kept.append((value, origins))
    out = {path: child_origins.get(path) or base_origins[path]} if path in child_origins or path in base_origins else {}
    for i, (_, origins) in enumerate(kept):
        out.update({path + (i,) + sub: o for sub, o in origins.items()})
    return [v for v, _ in kept], out


def _under(origins: Origins, path: tuple) -> Origins:
    n = len(path)
    return {p: o for p, o in origins.items() if p[:n] == path}


def _without(origins: Origins, path: tuple) -> Origins:
    n = len(path)
    return {p: o for p, o in origins.items() if p[:n] != path}
