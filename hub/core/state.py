"""The state contract: what changes during a run is saved and put back through one small protocol; structure stays as built.

A plant is built from its scenario in a fixed order, so two builds have the same structure: the
same bodies, slots, flows, components and observers, each in the same place. Everything that
changes while the plant runs lives in the attributes a class names in `STATE`, or behind its
own `save_state`/`restore_state` (Drake keeps all state in one Context; here each owner keeps
its own, and one walk collects it):

    class Rest:
        STATE = ("still", "resting", "extents", "fields", "_at_rest")

    class PhysicsWorld:
        STATE = ("tick", "engine", "bodies", "transport", …)    # its parts are walked into

`save(owner)` gives plain data (numbers, strings, numpy arrays, lists, dicts, tuples, frozen
dataclasses and enums) that `dumps` turns into bytes; `restore(owner, state)` puts it back into
an owner of the same structure, in place: a list, dict, set or array the owner already holds
keeps its identity (another part may hold it too: a flow's closure holds the signals' lists),
its contents replaced. An attribute that holds another owner, or a list, tuple or dict of
them, is walked into rather than copied; a class marked `@value` (a trigger's latch, a joint
motion: replaced whole, or held only at times) is saved whole instead.

An owner that keeps something made from its state (a grid of its boxes) writes `restored()`,
called once its state is back, to drop it.

A class that talks to something outside Python (the engine, an FMU, a participant) writes
`save_state() -> object` and `restore_state(state)`; its `STATE` still names the attributes of
its own those cover, so that a reader sees in one place what changes while it runs.
"""
from __future__ import annotations

import collections
import enum
import io
import pickle
from typing import Any

import numpy as np

from hub.core.errors import CheckpointError

_VALUES: set[type] = set()


def value(cls: type) -> type:
    """Class decorator: instances of `cls` are plain values in a snapshot, saved and put back whole
    (a robot's joint motion, a part's travel: made anew at each move, never changed in place)."""
    _VALUES.add(cls)
    return cls


def is_stateful(obj) -> bool:
    return hasattr(type(obj), "STATE") or hasattr(obj, "save_state")


def _is_part(obj) -> bool:
    """Walked into and put back in place: an owner of state that is not a value (one an owner
    replaces, or holds only at times, is saved whole: a trigger's latch, a box set)."""
    return type(obj) not in _VALUES and is_stateful(obj)


def save(owner) -> Any:
    """The owner's state as plain data (the live containers themselves: `dumps` copies them)."""
    custom = getattr(owner, "save_state", None)
    if custom is not None:
        return custom()
    return {name: _saved(getattr(owner, name)) for name in type(owner).STATE}


def restore(owner, state, where: str = "") -> None:
    """Put `state` (from `save` of an owner of the same structure) back into `owner`, in place."""
    where = where or type(owner).__name__
    custom = getattr(owner, "restore_state", None)
    if custom is not None:
        custom(state)
        return
    names = type(owner).STATE
    if not isinstance(state, dict) or set(state) != set(names):
        raise CheckpointError(f"{where}: the snapshot holds {_keys(state)} but this plant's "
                              f"{type(owner).__name__} has {sorted(names)}")
    for name in names:
        _put(owner, name, state[name], f"{where}.{name}")
    restored = getattr(owner, "restored", None)
    if restored is not None:
        restored()


def _saved(value):
    if _is_part(value):
        return save(value)
    if isinstance(value, (list, tuple)) and value and all(_is_part(v) for v in value):
        return [save(v) for v in value]
    if isinstance(value, dict) and value and all(_is_part(v) for v in value.values()):
        return {k: save(v) for k, v in value.items()}
    return value


def _put(owner, name: str, saved, where: str) -> None:
    current = getattr(owner, name)
    if _is_part(current):
        restore(current, saved, where)
    elif isinstance(current, (list, tuple)) and current and all(_is_part(v) for v in current):
        if len(saved) != len(current):
            raise CheckpointError(f"{where}: the snapshot has {len(saved)} parts, this plant {len(current)}")
        for k, (part, state) in enumerate(zip(current, saved)):
            restore(part, state, f"{where}[{k}]")
    elif isinstance(current, dict) and current and all(_is_part(v) for v in current.values()):
        if set(saved) != set(current):
            raise CheckpointError(f"{where}: the snapshot has parts {sorted(saved)}, this plant {sorted(current)}")
        for key, part in current.items():
            restore(part, saved[key], f"{where}[{key!r}]")
    else:
        setattr(owner, name, into(current, saved))


def into(current, saved):
    """`saved` put into `current` where `current` is a container of the same kind (its identity
    kept), else `saved` itself."""
    if isinstance(current, np.ndarray) and isinstance(saved, np.ndarray) \
            and current.shape == saved.shape and current.dtype == saved.dtype and current.flags.writeable:
        current[...] = saved
        return current
    if type(current) is list and type(saved) is list:
        current[:] = saved
        return current
    if type(current) is dict and type(saved) is dict:
        current.clear()
        current.update(saved)
        return current
    if type(current) is set and type(saved) is set:
        current.clear()
        current.update(saved)
        return current
    if type(current) is collections.deque and type(saved) is collections.deque and current.maxlen == saved.maxlen:
        current.clear()
        current.extend(saved)
        return current
    return saved


def _keys(state) -> str:
    return str(sorted(state)) if isinstance(state, dict) else type(state).__name__


# --- bytes ------------------------------------------------------------------------------------
#: What a snapshot may hold: plain data, numpy arrays and the project's own plain classes. Any
#: other global a pickle names is refused, so that loading a checkpoint runs no foreign code.
_ALLOWED_MODULES = ("hub.", "modules.")
_ALLOWED = {
    ("builtins", n) for n in ("set", "frozenset", "complex", "slice", "range", "bytearray")
} | {
    ("collections", "deque"), ("collections", "OrderedDict"), ("collections", "defaultdict"),
    ("copyreg", "_reconstructor"), ("builtins", "object"),
    ("numpy", "dtype"), ("numpy", "ndarray"), ("numpy.core.multiarray", "_reconstruct"),
    ("numpy._core.multiarray", "_reconstruct"), ("numpy.core.multiarray", "scalar"),
    ("numpy._core.multiarray", "scalar"), ("numpy._core.numeric", "_frombuffer"),
    ("numpy.core.numeric", "_frombuffer"),
}


class _Unpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        if (module, name) in _ALLOWED or module.startswith(_ALLOWED_MODULES):
            found = super().find_class(module, name)
            if module.startswith(_ALLOWED_MODULES) and not (isinstance(found, type) and (
                    found in _VALUES or issubclass(found, enum.Enum) or hasattr(found, "__dataclass_fields__")
                    or issubclass(found, tuple))):
                raise pickle.UnpicklingError(f"{module}.{name} is not plain data")
            return found
        raise pickle.UnpicklingError(f"{module}.{name} is not allowed in a snapshot")


def dumps(state) -> bytes:
    try:
        return pickle.dumps(state, protocol=5)
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise CheckpointError(f"the state holds something that is not plain data: {exc}") from None


def loads(data: bytes, where: str):
    """The state in `data`; anything wrong with it is a CheckpointError naming `where`."""
    try:
        return _Unpickler(io.BytesIO(data)).load()
    except Exception as exc:   # a decoder of outside bytes raises only the project's errors
        raise CheckpointError(f"{where}: the saved state cannot be read ({type(exc).__name__}: {exc})") from None
