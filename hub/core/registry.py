"""The module registry: module names → lazily imported classes, with "did you mean" on a miss.

The kernel never imports a module type: the element modules are found by name, through the
catalogues installed packages declare (entry points of the group `planthub.catalogues`, each a
mapping of module name → "package.file:Class"; planthub's own is `modules:CATALOGUE`)."""
from __future__ import annotations

import difflib
import importlib
import re
from importlib import metadata

from hub.core.module import Module


class UnknownModule(LookupError):
    """No module of that name; the message carries the nearest names."""


class Registry:
    """Maps module names to entry points `"package.file:Class"`, imported on first use."""

    def __init__(self, entries: dict[str, str]):
        self._entries = dict(entries)
        self._loaded: dict[str, type[Module]] = {}

    def names(self) -> list[str]:
        return sorted(self._entries)

    def __contains__(self, name: str) -> bool:
        return name in self._entries

    def register(self, name: str, entry_point: str) -> None:
        if name in self._entries:
            raise ValueError(f"module {name!r} is already registered as {self._entries[name]}")
        self._entries[name] = entry_point

    def get(self, name: str) -> type[Module]:
        if name not in self._entries:
            raise UnknownModule(f"unknown module {name!r}{self.suggest(name)}")
        if name not in self._loaded:
            self._loaded[name] = load_entry(self._entries[name])
        return self._loaded[name]

    def suggest(self, name: str) -> str:
        """` (did you mean 'x'?)` for the closest name; else for the modules whose one-line
        description names the thing in its first words (a `belt` is a conveyor, a curve, …); else
        the names there are."""
        close = did_you_mean(name, self._entries)
        if close.startswith(" (did you mean") or not isinstance(name, str) or not name.isidentifier():
            return close
        word = re.compile(rf"\b{re.escape(name.replace('_', ' '))}s?\b", re.IGNORECASE)
        described = []
        for module in sorted(self._entries):
            try:
                lines = (self.get(module).__doc__ or "").strip().splitlines()
            except Exception:   # a catalogue entry that does not import is no suggestion
                continue
            if lines and word.search(" ".join(lines[0].split()[:5])):
                described.append(module)
        if described:
            return f" (did you mean {' or '.join(repr(m) for m in described[:4])}? their descriptions say {name!r})"
        return f" (known: {', '.join(sorted(self._entries))})"


def did_you_mean(name: str, choices) -> str:
    """` (did you mean 'x'?)` for the closest choice, or a list of what exists when few do."""
    choices = sorted(choices)
    close = difflib.get_close_matches(name, choices, n=1, cutoff=0.6)
    if close:
        return f" (did you mean {close[0]!r}?)"
    if 0 < len(choices) <= 8:
        return " (known: " + ", ".join(choices) + ")"
    return ""


def load_entry(entry: str):
    """The object an entry point "package.file:name" (or "…:Class.attribute") names, imported now."""
    path, _, attr = entry.partition(":")
    found = importlib.import_module(path)
    for part in attr.split("."):
        found = getattr(found, part)
    return found


CATALOGUES = "planthub.catalogues"


def default_registry() -> Registry:
    """Every element module the installed catalogues declare (planthub's own: modules/__init__.py)."""
    entries: dict[str, str] = {}
    for point in sorted(metadata.entry_points(group=CATALOGUES), key=lambda p: p.name):
        for name, entry in point.load().items():
            entries.setdefault(name, entry)
    return Registry(entries)
