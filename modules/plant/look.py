"""How a bottle looks in a view: filled, capped and where it is going, from the manifest (modules/manifest.py)."""
from __future__ import annotations

from modules.manifest import peek

FILLED, CAPPED = 1, 2   # bits of `flags` in the bodies message (schemas/scene.schema.json `bodies_message`)


class CargoLook:
    """A body look (hub/core/observer.py BodyLook) that sources, stations and bottles contribute."""

    def __init__(self, plant):
        self.world = plant.world
        # Row → its manifest entry, once it has one. An entry is made once (a source's at build, a
        # plain bottle's on first use) and then only changed in place, so it is looked up once:
        # `peek` per row (a weak-keyed table) was half of a bodies message's cost, 65 of 121 µs with
        # 90 bottles in play; 20 µs with the entries kept (tests/bench_view.py).
        self._entries: dict = {}

    def look(self, rows) -> dict:
        entries, world = self._entries, self.world
        found = []
        for row in rows:
            entry = entries.get(row)
            if entry is None:
                entry = peek(world, int(row))
                if entry is not None:
                    entries[int(row)] = entry
            found.append(entry)
        flags = bytes([0 if e is None else (FILLED if e.filled else 0) | (CAPPED if e.capped else 0) for e in found])
        return {"flags": flags, "destinations": ["" if e is None else e.destination for e in found]}
