"""The manifest: what the plant knows about each bottle beyond its body — id, destination, fill and cap state.

A bottle's body belongs to the physics world and its module; its cargo state is written by
sources (id, destination), stations (filled, capped) and read by ID readers and sinks. It lives
in one table per world (among the world's `tables`, saved with its state), keyed by the world's
body number, so that no module reaches into another's components and a bottle made by the
`bottle` module has a default entry (its id, no destination, empty, open) without knowing about
any of this.
"""
from __future__ import annotations

from dataclasses import dataclass

_TABLE = "manifest"


@dataclass
class Cargo:
    id: str
    destination: str = ""
    filled: bool = False
    capped: bool = False


def cargo(world, body: int) -> Cargo:
    """The entry of body number `body`, made from its world label on first use."""
    table = world.tables.setdefault(_TABLE, {})
    entry = table.get(body)
    if entry is None:
        entry = table[body] = Cargo(world.labels[body])
    return entry


def peek(world, body: int) -> Cargo | None:
    """The entry of body number `body` if it has one, without making it (a view looks)."""
    table = world.tables.get(_TABLE)
    return None if table is None else table.get(body)


def register(world, body: int, destination: str = "") -> Cargo:
    """Make a fresh entry for a body (a source does this for every bottle it makes)."""
    entry = world.tables.setdefault(_TABLE, {})[body] = Cargo(world.labels[body], destination)
    return entry
