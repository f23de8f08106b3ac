"""The saved state of a participant slave, the same bytes in the hub's process and over the bus."""
from __future__ import annotations

from hub.bus import wire
from hub.bus.lockstep import RemoteSpec
from hub.core.errors import CheckpointError

#: Names the layout below; a later one gets another.
FORMAT = "planthub.participant-slave/1"


def pack_state(spec: RemoteSpec, inputs: list | None, outputs: list, state: bytes) -> bytes:
    """A participant slave's state: the participant's own bytes (from its save_state, opaque here),
    beside what the slave holds for it — the inputs of its last step and the outputs that step gave
    (events included: the participant has reset them), both in the scenario's order. Both
    transports write and read exactly this, so a state saved with the logic in the hub can be
    restored with it on the bus, and back."""
    values = lambda pairs, given: [wire.to_wire(kind, value) for (_, kind), value in zip(pairs, given)]
    return wire.pack({"format": FORMAT, "name": spec.name, "inputs": values(spec.inputs, inputs or []),
                      "outputs": values(spec.outputs, outputs), "state": bytes(state)})


def read_state(spec: RemoteSpec, data: bytes, where: str) -> tuple[list, list, bytes]:
    """(inputs, outputs, participant bytes) of a state `pack_state` made for this object: values
    canonical as the bus makes them; CheckpointError naming `where` for anything else."""
    try:
        if not isinstance(data, (bytes, bytearray)):
            raise wire.WireError(f"expected bytes, got {type(data).__name__}")
        saved = wire.unpack(bytes(data), wire.MAX_STATE + wire.MAX_MESSAGE)
        if not (isinstance(saved, dict) and saved.get("format") == FORMAT):
            raise wire.WireError(f"not a participant's saved state ({FORMAT})")
        if saved.get("name") != spec.name:
            raise wire.WireError(f"it is the state of participant {saved.get('name')!r}")
        state, inputs, outputs = saved.get("state"), saved.get("inputs"), saved.get("outputs")
        if not isinstance(state, bytes):
            raise wire.WireError("it holds no participant bytes")
        if not (isinstance(inputs, list) and len(inputs) in (0, len(spec.inputs))):
            raise wire.WireError(f"it holds {_count(inputs)} inputs, the scenario gives {len(spec.inputs)}")
        if not (isinstance(outputs, list) and len(outputs) == len(spec.outputs)):
            raise wire.WireError(f"it holds {_count(outputs)} outputs, the scenario gives {len(spec.outputs)}")
        inputs = [wire.from_wire(kind, value, f"input {name!r}") for (name, kind), value in zip(spec.inputs, inputs)]
        outputs = [wire.from_wire(kind, value, f"output {name!r}") for (name, kind), value in zip(spec.outputs, outputs)]
    except wire.WireError as exc:
        raise CheckpointError(f"{where}: the saved state does not fit: {exc}") from None
    return inputs, outputs, state


def _count(values) -> str:
    return str(len(values)) if isinstance(values, list) else "no list of"
