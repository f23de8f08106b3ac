"""Rewind a running plant to a checkpoint it took earlier in the run, and go on from there (`planthub send RUN rewind TICK`).

The engine takes a checkpoint only into a freshly built world (hub/physics/engine.py
`_renumber`), so a rewind builds the plant again from the same scenario, hands it what is the
run's rather than the plant's — the bus session, the participants on it and their lockstep, the
live commands, the recorder's files, the expectations' watcher, the observers given to the run —
and puts the checkpoint in (hub/run/checkpoint.py `apply`: the hub's parts through
hub/core/state.py, participants through the bus's restore message, the faults in effect at the
checkpoint with their forces). The old plant is closed after. The run then goes on from the
checkpoint's point as a run resumed from it (`planthub run --resume`) does, bit for bit.

What the run folder keeps of it:

- commands.csv: `rewind` at the tick it was taken at, its value the tick of the checkpoint it
  went back to; a replay (`planthub run --replay`) keeps that checkpoint in memory as it passes
  it and rewinds at the same point, so it gives the same files;
- recording.csv and events.csv: cut back to the checkpoint's point, and the rows cut (those the
  abandoned branch made after it) written beside in recording.branchN.csv and events.branchN.csv
  (N counts the run's rewinds), each under its file's header; then an event row `@run` at the
  checkpoint's tick saying the rewind and where the branch went;
- checkpoints/: those taken after the point (the abandoned branch's) moved to checkpoints/branchN/;
- bus_log.csv: a notice at the tick the rewind was taken at.
"""
from __future__ import annotations

from hub.core.errors import CheckpointError, SimulationError
from hub.run import checkpoint
from hub.run.plant import Plant


class Rewinder:
    """Goes back to one of the run's checkpoints (hub/run/checkpoint.py Checkpointer.taken): the
    rewind's hook of the run's commands (hub/bus/commands.py Commands.rewinds)."""

    def __init__(self, run):
        self.run = run
        self.branches = 0      # rewinds so far: the last abandoned branch's number
        self._to = None        # (checkpoint, tick taken at, command) of the rewind asked at this point

    def refuse(self, tick: int, target: int) -> str | None:
        """Why a rewind to `target` asked at `tick` cannot be done, or None."""
        run, rate = self.run, self.run.scenario.run.physics_rate
        if run.bodies is not None:
            return ("rewind: this run records its bodies for playback (run.record_bodies), a file a rewind "
                    "does not cut back")
        if target > tick:
            return (f"rewind {target}: tick {target} (t = {target / rate:g} s) is in the future: the run is at "
                    f"tick {tick} (t = {tick / rate:g} s)")
        taken = run.checkpointer.at_or_before(target)
        if taken is None:
            have = sorted(run.checkpointer.taken)
            return (f"rewind {target}: no checkpoint at or before tick {target} (t = {target / rate:g} s); "
                    + (f"this run has checkpoints at ticks {', '.join(map(str, have))}" if have else
                       "this run has taken none yet (planthub run --checkpoint-at, --checkpoint-every, or "
                       "planthub send RUN checkpoint)"))
        if taken.path is not None and not taken.path.is_file():
            return f"rewind {target}: its checkpoint {taken.path} is gone"
        return None

    def request(self, tick: int, command, now: bool) -> int:
        """Rewind to the checkpoint at or before `command.value`: once the point at `tick` is complete
        (the master's `then`), or `now` (the run is held at a complete point). Returns the tick of
        the checkpoint it goes back to."""
        refused = self.refuse(tick, command.value)
        if refused:   # a live one was refused already: this is a replay that cannot do what its run did
            raise SimulationError(f"the rewind at tick {tick}: {refused}")
        taken = self.run.checkpointer.at_or_before(command.value)
        self._to = (taken, tick, command)
        if now:
            self.rewind()
        else:
            self.run.master.then = self.rewind
        return taken.tick

    def rewind(self) -> None:
        taken, tick, command = self._to
        self._to = None
        run = self.run
        scenario, rate = run.scenario, run.scenario.run.physics_rate
        data = taken.bytes()
        from hub.run.faults import FAULTS_PART
        try:
            faulted = FAULTS_PART in checkpoint.held_parts(data, taken.where)
        except (CheckpointError, KeyError, TypeError) as exc:
            raise SimulationError(f"the rewind at tick {tick} to tick {taken.tick}: {exc}") from None
        plant = Plant(scenario, every_source=run.every_source)
        try:
            old = run.replant(plant, faulted)
        except BaseException:
            plant.close()
            raise
        try:
            checkpoint.apply(run, data, taken.where)
        finally:
            old.close()
        self.branches += 1
        n = self.branches
        beside = run.recorder.cut(taken.marks, n)
        moved = run.checkpointer.forget_after(taken.tick, n)
        if run.master.pacer is not None:
            run.master.pacer.start(taken.tick)
        # The event row says only what a replay does alike: not the tick asked for (a replay asks for
        # the checkpoint's), nor which checkpoint files there were.
        detail = (f"rewind to t = {taken.tick / rate:g} s from t = {tick / rate:g} s"
                  + (f" by {command.by}" if command.by else "")
                  + (f"; the branch left: {', '.join(p.name for p in beside)}" if beside else ""))
        run.recorder.event(taken.tick, "@run", detail)
        run.log(detail + (f"; its checkpoints: {moved[0].parent}" if moved else ""))


def hand_over_participants(old: Plant, new: Plant) -> None:
    """The participants on the bus stay with the run: each logic component of the new plant takes
    the old one's slave (linked to the run's lockstep, its step count going on), and the old
    component the new, unlinked one (closed with the old plant)."""
    for was, now in zip(old.components, new.components):
        slave = getattr(was, "slave", None)
        if getattr(slave, "on_bus", False):
            was.slave, now.slave = now.slave, slave
