"""How a bottle looks in a view: filled, capped and where it is going, from the manifest (modules/manifest.py)."""
from __future__ import annotations

from modules.manifest import peek

FILLED, CAPPED = 1, 2   # bits of `flags` in the bodies message (schemas/scene.schema.json `bodies_message`)


class CargoLook:
    """A body look (hub/core/observer.py BodyLook) that sources, stations and bottles contribute."""

    def __init__(self, plant):
        self.world = plant.world

    def look(self, rows) -> dict:
        flags, destinations = bytearray(len(rows)), []
        for i, row in enumerate(rows):
            entry = peek(self.world, int(row))
            if entry is None:
                destinations.append("")
                continue
            flags[i] = (FILLED if entry.filled else 0) | (CAPPED if entry.capped else 0)
            destinations.append(entry.destination)
        return {"flags": bytes(flags), "destinations": destinations}
