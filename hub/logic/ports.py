"""An FMU's slots: one rule for the `fmu` module and for an FMU served on the bus, so both sides agree."""
from __future__ import annotations

from hub.core.slots import Slot
from hub.logic.fmi import FmuInterface


def fmu_ports(fmu: FmuInterface, events=(), rename: dict | None = None) -> list[tuple[Slot, str]]:
    """(slot, variable name) for every input, then every output, in the FMU's order: Booleans
    named in `events` become void slots, `rename` maps a variable to its slot name."""
    out = []
    events, names = set(events), rename or {}
    for causality, make in (("input", Slot.target), ("output", Slot.source)):
        for v in fmu.of(causality):
            kind = "void" if v.name in events else v.type.value
            out.append((make(names.get(v.name, v.name), kind, v.description), v.name))
    return out
