"""A net description as plain data in the YAML form's shape, with the source line of every entry.

Both readers produce one: the YAML reader directly, the PNML reader by
translation. The schema and the net checks then run on it, so a fault is
worded the same whichever format it was written in."""

from dataclasses import dataclass, field


@dataclass
class Document:
    data: object
    lines: dict = field(default_factory=dict)  # path tuple, e.g. ("places", "B326", "marking") -> line
    # Entries a reader dropped parts of after reporting them, e.g. a transition whose only arc was malformed:
    # later checks must not report the consequence ("has no arcs") as a second problem.
    reported: set = field(default_factory=set)

    def line(self, path):
        """The line of path, or of its nearest ancestor that has one."""
        path = tuple(path)
        while path and path not in self.lines:
            path = path[:-1]
        return self.lines.get(path, 1)
