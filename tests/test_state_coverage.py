"""Every value that changes while a plant runs is one a checkpoint holds (hub/core/state.py).

Each shipped scenario (together every module type) runs a while; the object graph of the run is
walked before and after another while, and every attribute that changed must be covered: named
in its class's `STATE`, held by a class without one that saves itself (`save_state`: a logic
slave, tested with its own save), reached through an attribute saved whole, or listed below as
no part of the plant's state, with the reason. A test that a class's save misses nothing it names
is test_checkpoint.py's snapshot saved again after a restore.
"""
from __future__ import annotations

import collections
import enum
import io
import logging
import pickle
import types
from pathlib import Path

import numpy as np
import pytest

from hub.core import state
from hub.run.assembly import Run
from hub.scenario.checker import Scenario, load_scenario

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"

# (scenario, first look, second look, in s): windows in which each scene's parts act.
SCENES = [
    ("belt_bottle_sensor.yaml", 0.5, 1.5), ("belt_ramp_fmu.yaml", 0.5, 2.0), ("belt_ramp_participant.yaml", 0.5, 2.0),
    ("jam.yaml", 0.5, 2.0), ("pusher.yaml", 0.5, 2.0), ("robot.yaml", 2.0, 6.0), ("robot_logic.yaml", 2.0, 7.0),
    ("separator.yaml", 2.0, 6.0), ("separator_logic.yaml", 1.0, 4.0), ("source_sink.yaml", 1.0, 3.0),
    ("station.yaml", 1.0, 3.0), ("stop_at_barrier.yaml", 0.5, 2.0), ("stopper_queue.yaml", 1.0, 3.0),
    ("switch.yaml", 0.5, 1.5), ("switch_logic.yaml", 0.5, 1.5), ("two_drives_distributed.yaml", 0.5, 1.5),
    ("bottling_plant.yaml", 20.0, 30.0),
]

_SESSION = ("this bus session's exchange with a participant (step numbers, the message in flight, when it "
            "went): a resumed run opens its own session, and the participant's state goes over by save and restore")
# (class, attribute): what changes as a run goes but is no part of what the plant does next.
NOT_STATE = {
    ("hub.run.assembly.Run", "wall_seconds"): "wall-clock time spent, a figure of this process",
    ("hub.run.recorder.Recorder", "_flush_due"): "when the files are next flushed: output, not state",
    ("hub.bus.dataplane.DataPlane", "_next_poll"): "a wall-clock time to look at the bus again",
    ("hub.view.broadcast.Broadcast", "_next_poll"): "a wall-clock time to look at the bus again",
    ("hub.view.broadcast.Broadcast", "_tick"): "the last point sent to views, to send its figures again as the "
                                               "run ends: what views were told, set again at the next point",
    ("hub.physics.fields.ForceFields", "_regions"): "the belts' table (saved) with its grid, made from it when first "
                                                    "asked",
    ("hub.physics.triggers.VolumeTriggers", "_made"): "the triggers' grid, made from the boxes at the first tick "
                                                      "after a restore (hub/physics/triggers.py, _grid)",
    ("hub.physics.triggers.VolumeTriggers", "_mobile"): "which triggers moved, kept out of the grid so that it is not "
                                                        "made again at every tick: the grid's results are the same",
    ("hub.bus.lockstep.Lockstep", "tick"): _SESSION,
    ("hub.logic.remote.RemoteSlave", "sent"): _SESSION,
    **{("hub.bus.lockstep._Peer", name): _SESSION for name in ("from_tick", "pending", "result", "result_n", "sent_at")},
}

_OPAQUE = (types.ModuleType, types.FunctionType, types.BuiltinFunctionType, types.MethodType, type, logging.Logger,
           io.IOBase, Scenario)


def _plain(v) -> bool:
    """A value saved as it is (no object of the project's inside to walk into)."""
    if v is None or isinstance(v, (bool, int, float, str, bytes, complex, enum.Enum, np.generic)):
        return True
    if isinstance(v, np.ndarray):
        return v.dtype != object
    if isinstance(v, (list, tuple, set, frozenset, collections.deque)):
        return all(_plain(x) for x in v)
    if isinstance(v, dict):
        return all(_plain(k) and _plain(x) for k, x in v.items())
    return False


def _print(v):
    if isinstance(v, np.ndarray):
        return v.shape, v.dtype.str, v.tobytes()
    try:
        return pickle.dumps(v)
    except Exception:   # an unpicklable plain value is not one; its repr tells changes apart
        return repr(v)


def _ours(obj) -> bool:
    return type(obj).__module__.split(".")[0] in ("hub", "modules", "tests") and not isinstance(obj, _OPAQUE)


def _walk(run) -> dict:
    """(id, attribute) → (class name, path, print of its plain part, covered) over the run's objects."""
    out, seen, queue = {}, set(), collections.deque([(run, "run", False)])
    while queue:
        obj, path, covered = queue.popleft()
        if id(obj) in seen or not _ours(obj) or not hasattr(obj, "__dict__"):
            continue
        seen.add(id(obj))
        cls = type(obj)
        name = f"{cls.__module__}.{cls.__qualname__}"
        named = set(getattr(cls, "STATE", ()))
        # A class that saves itself still names what changes in STATE (hub/core/state.py); one
        # without STATE (a logic slave) is covered by its own save, which its tests check.
        whole = covered or cls in state._VALUES or (hasattr(obj, "save_state") and not named)
        for key, v in vars(obj).items():
            inside = whole or key in named
            # An attribute named in STATE is saved whole unless it is (or holds) parts walked into.
            below = whole or (key in named and not state._is_part(v))
            if _plain(v):
                out[id(obj), key] = (name, f"{path}.{key}", _print(v), inside)
                continue
            items = v.items() if isinstance(v, dict) else enumerate(v) if isinstance(
                v, (list, tuple, collections.deque)) else None
            if items is None:
                queue.append((v, f"{path}.{key}", below))
                continue
            kept = []
            for k, x in list(items):
                if _plain(x):
                    kept.append((repr(k), _print(x)))
                else:
                    queue.append((x, f"{path}.{key}[{k!r}]", below))
            out[id(obj), key] = (name, f"{path}.{key}", kept, inside)
    return out


@pytest.mark.parametrize("name, first, second", SCENES, ids=[s[0] for s in SCENES])
def test_what_changes_as_a_plant_runs_is_saved(name, first, second):
    scenario = load_scenario(SCENARIOS / name)
    rate = scenario.run.physics_rate
    with Run(scenario) as run:
        run.run(round(first * rate))
        before = _walk(run)
        run.run(round(second * rate))
        after = _walk(run)
    uncovered = sorted({f"{cls}.{key[1]} ({path})" for key, (cls, path, printed, covered) in after.items()
                        if not covered and (cls, key[1]) not in NOT_STATE
                        and (key not in before or before[key][2] != printed)})
    assert not uncovered, "changed as the run went, and no checkpoint holds it:\n" + "\n".join(uncovered)
