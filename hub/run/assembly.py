"""The one place a run is put together — scenario, plant, recorder, bus side, contributed figures, master — for the CLI, the Python API, reports, tests and benchmarks."""
from __future__ import annotations

import logging
from pathlib import Path

from hub.core.errors import SimulationError
from hub.core.observer import Observer, StopCondition
from hub.core.registry import load_entry
from hub.logic.watchdog import WATCHDOG
from hub.run.bus_link import BusLink
from hub.run.checkpoint import Checkpointer, Taken, by_kind, held_parts
from hub.run.checkpoint import apply as put_back
from hub.run.ending import ending
from hub.run.hold import Hold
from hub.run.interruption import Interruption
from hub.run.master import Master, RunResult
from hub.run.plant import Plant
from hub.run.recorder import Recorder
from hub.run.rewind import Rewinder, hand_over_participants
from hub.run.summary import RunSummary, logic_components
from hub.scenario.checker import Scenario
from hub.scenario.expectations import Expectation, Watcher


class Run:
    """One scenario built into a run, ready at its first communication point once started.

        with Run(scenario, out=Path("runs/x")) as run:
            result = run.run()
            print("\\n".join(run.summary().lines()))

    - `out`: the folder for recording.csv, events.csv (and commands.csv, bus_log.csv); with it,
      `close` writes summary.json. Without, nothing is written.
    - `bus`: an open hub.bus.session.Bus to run on (the CLI's --listen/--bus); without one, a bus
      is opened only when logic is served over it.
    - `replay`: operator commands to apply again (hub.bus.commands.load_commands), instead of
      live ones from the bus.
    - `pacer`: holds each point until its wall-clock time (hub/run/pacing.py).
    - `every_source`: every source slot is computed, not only those something reads (the Python
      API reads any slot at any time).
    - `observers`, `stops`: more observers and stop conditions (hub/core/observer.py), after
      the recorder, the bus side and what the scenario's modules contribute.
    - `signals`: SIGINT and SIGTERM end the run at the next point (hub/run/interruption.py; the
      CLI's runs), their status in `interruption.exit_status`.
    - `log`: a function for notices (a participant lost, where the bus listens); default: the
      `hub.run` logger at INFO (the CLI shows them unless `-q`).
    - `resume`: a checkpoint's bytes (hub/run/checkpoint.py) and where they came from: `start`
      puts the run at its communication point, and the run goes on from there.
    - `checkpoints`: (ticks, every) — save the run at those ticks and every `every` ticks into
      `out/checkpoints/TICK.ckpt`. A run with a folder may be rewound to one of its checkpoints
      (`rewind TICK`, hub/run/rewind.py): `replant` puts the plant built again in the old one's place.
    """

    def __init__(self, scenario: Scenario, *, out: Path | None = None, bus=None, replay=None, pacer=None,
                 every_source: bool = False, observers: list[Observer] = (), stops: list[StopCondition] = (),
                 log=None, signals: bool = False, resume: tuple[bytes, str] | None = None,
                 checkpoints: tuple = ((), None)):
        self.scenario = scenario
        self.out = Path(out) if out is not None else None
        self.log = log or logging.getLogger(__name__).info
        self.link = None
        self.failure = None       # what ended the run with an error (the `with` block's exception)
        self.resume = resume
        self.resumed = None       # the checkpoint's header once it is put back (hub/run/checkpoint.py)
        self.wall_seconds = 0.0   # spent in run (and in Simulation.run_until)
        self._started = self._closed = False
        self.every_source = every_source
        self.plant = Plant(scenario, every_source=every_source)
        try:
            plant = self.plant
            rate = scenario.run.physics_rate
            columns = [(ref, kind, plant.index[ref]) for ref, kind in scenario.record]
            self.recorder = Recorder(columns, rate, self.out)
            self._hang = WATCHDOG.on_hang(self._emergency)
            self.interruption = Interruption(rate, self._emergency).install() if signals else None
            if self.interruption is not None:
                stops = [self.interruption, *stops]
            # Imported here: replaying needs the bus package's command parser, not a bus.
            from hub.bus.commands import Commands, load_commands
            from hub.run.faults import FAULTS_PART, Board, FaultBook, FaultSchedule
            # Faults begin and end as commands (hub/run/faults.py): the scenario's schedule gives
            # them to a Commands of their own; a replay's recorded commands hold them instead.
            self.faults = FaultBook(plant)
            recorded = load_commands(replay, plant, self.faults) if replay is not None else None
            commands = Commands(plant, self.recorder, recorded) if recorded is not None else None
            self.commands = commands
            manipulators, schedule = [commands] if commands is not None else [], None
            slaves = [s for c in plant.components if getattr(s := getattr(c, "slave", None), "on_bus", False)]
            # A run on the bus may take live faults from an instructor: the live commands take the
            # scheduled ones' place once the bus is joined (start), and the schedule ends a live
            # fault given a duration.
            live = commands is None and (bus is not None or bool(slaves))
            self.scheduled = None
            if commands is not None:
                self.faults.attach(commands)
            elif scenario.faults or live:
                self.scheduled = scheduled = Commands(plant, self.recorder)
                self.faults.attach(scheduled)
                schedule = FaultSchedule(plant, scenario.faults, scheduled)
                manipulators = [schedule, scheduled]
            self.schedule = schedule
            self._live = live
            # With the faults' parts if there may be faults to save: scheduled, recorded, or in
            # the checkpoint to resume from (a live fault's).
            faulted = bool(scenario.faults) or any(c.op == "fault" for _, c in recorded or ()) or (
                resume is not None and FAULTS_PART in held_parts(*resume))
            self.contributed = self._contribute(plant, faulted)
            self.bodies = None   # the body recording, for playback (run.record_bodies)
            if self.out is not None and scenario.run.record_bodies:
                from hub.view.bodies_file import BodyRecorder  # pyarrow is loaded only for it
                from hub.view.scene import scene_bytes
                self.bodies = BodyRecorder(self.out, plant.world, scene_bytes(plant, scenario.name),
                                           every=scenario.run.record_bodies, looks=self.contributed)
            if bus is not None or slaves:
                self.link = BusLink(plant, self.recorder, slaves, bus, commands, log=self.log,
                                    looks=self.contributed, figures=lambda: self.figures,
                                    faults=Board(self.faults, schedule), timeline=lambda: self.checkpointer,
                                    logs=self.out)   # what launched participants said: beside the run's files
            # The scenario's expectations are watched in every run, so that a checkpoint carries
            # what they saw whichever command took it and whichever resumes it.
            self.watcher = Watcher([e for e in scenario.expect if isinstance(e, Expectation)], plant.index, rate)
            watchers = [*self.contributed, self.watcher, *observers]
            ticks, every = checkpoints
            self.checkpointer = self.rewinder = None
            if (ticks or every) and self.out is None:
                raise SimulationError("checkpoints are written into the run's folder: give it one (--out)")
            # A replay keeps in memory the checkpoints its recorded rewinds went back to.
            keep = {c.value for _, c in recorded or () if c.op == "rewind"}
            if self.out is not None or keep:   # at given ticks, and when an operator asks (`checkpoint`)
                # Last of the observers: a checkpoint holds what every other one made of its point.
                self.checkpointer = Checkpointer(self, self.out / "checkpoints" if self.out is not None else None,
                                                 ticks, every, log=self.log, keep=keep)
                watchers.append(self.checkpointer)
                self.rewinder = Rewinder(self)
                if commands is not None:
                    commands.rewinds = self.rewinder
            self.master = Master(
                plant,
                observers=[self.recorder, *([self.bodies] if self.bodies else []), *([self.link] if self.link else []),
                           *[c for c in watchers if isinstance(c, Observer)]],
                stops=[*[c for c in self.contributed if isinstance(c, StopCondition)], *stops],
                manipulators=manipulators,
                pacer=pacer)
        except BaseException:
            self._close_parts("the run could not be built")
            raise

    def start(self) -> None:
        """Join the bus and launch and await the participants (once; `run` starts a run that is
        not started). The first communication point is the master's first `communicate`."""
        if self._started:
            return
        self._started = True
        try:
            if self.link is not None:
                live = self.link.start()
                if live is not None:
                    self.commands = live
                    if self.scheduled is not None:   # faults, scheduled and live, go through the live commands
                        self.faults.attach(live)
                        self.faults.timed = True
                        self.schedule.commands = live
                        at = self.master.manipulators.index(self.scheduled)
                        self.master.manipulators[at:at + 1] = []
                        self.scheduled = None
                    live.on_checkpoint = self.checkpointer.request if self.checkpointer is not None else None
                    live.rewinds = self.rewinder
                    self.master.manipulators.append(live)
                    self.master.hold = Hold(live, pacer=self.master.pacer, state=self.link.lockstep.publish_state,
                                            idle=self.link.idle)
            if self.commands is not None:   # an operator's stop, live or replayed
                self.master.stops.append(self.commands)
            if self.resume is not None:   # participants are on the bus by now: their state goes to them
                data, where = self.resume
                self.resumed = put_back(self, data, where)
                if self.checkpointer is not None:   # a rewind may go back to where the run resumed
                    self.checkpointer.add(Taken(self.resumed.tick, None, data, self.recorder.marks()))
        except BaseException:
            self.master.close("the run failed")
            raise

    def run(self, until_tick: int | None = None) -> RunResult:
        """Run to `until_tick` (default: the scenario's end, or until a stop condition holds)."""
        self.start()
        result = self.master.run(until_tick)
        self.wall_seconds += result.wall_seconds
        return result

    def _contribute(self, plant, faulted: bool) -> list:
        """The observers and stop conditions of `plant` that the scenario's modules contribute, then
        the faults' figures and state (`faulted`; or from the first live fault on, in a run that
        may take one) and the exercise's score."""
        from hub.run.exercise import FaultsFigure, Score  # the faults that began, the exercise's score
        from hub.run.faults import FaultsState

        scenario, rate = self.scenario, self.scenario.run.physics_rate
        contributed = _contributions(scenario, plant)
        faults = [FaultsFigure(self.faults, rate), FaultsState(self.faults, self.schedule)]
        if faulted:
            contributed += faults
        elif self._live:   # in the summary and a checkpoint from the first live fault on: a run without
            # one keeps the files, summary and checkpoints of a run that could take none
            self.faults.on_first = lambda: self.contributed.extend(faults)
        if scenario.exercise is not None:
            contributed.append(Score(scenario.exercise, contributed, self.faults, rate))
        return contributed

    def replant(self, plant: Plant, faulted: bool) -> Plant:
        """A rewind's (hub/run/rewind.py): `plant`, built again from the scenario, takes the old
        plant's place, with the faults' book and schedule and the contributed observers made anew
        for it (`faulted`: with the faults' parts, as the checkpoint to put in has them); the live
        commands, the bus link and the master work on it from now on. The participants on the bus
        stay (hand_over_participants). Returns the old plant, for the caller to close."""
        from hub.run.faults import Board, FaultBook, FaultSchedule

        old, book, schedule = self.plant, self.faults, self.schedule
        hand_over_participants(old, plant)
        self.plant = plant
        self.faults = FaultBook(plant)
        self.faults.timed = book.timed
        if book.commands is not None:
            self.faults.attach(book.commands)
        replaced = {}
        if schedule is not None:
            self.schedule = FaultSchedule(plant, self.scenario.faults, schedule.commands)
            replaced[id(schedule)] = self.schedule
        for commands in {id(c): c for c in (self.commands, self.scheduled, book.commands) if c is not None}.values():
            commands.rebind(plant)
        before = self.contributed
        self.contributed = self._contribute(plant, faulted)
        made = by_kind(self.contributed)
        for key, part in by_kind(before).items():
            replaced[id(part)] = made.get(key)
        self.master.rebind(plant, replaced)
        if self.link is not None:
            self.link.rebind(plant, looks=self.contributed, faults=Board(self.faults, self.schedule))
        return old

    @property
    def tick(self) -> int:
        return self.master.tick

    @property
    def stopped_by(self) -> str:
        return self.master.stopped.reason if self.master.stopped is not None else ""

    @property
    def dataplane(self):
        return self.link.dataplane if self.link is not None else None

    @property
    def lockstep(self):
        return self.link.lockstep if self.link is not None else None

    @property
    def figures(self) -> list:
        """The contributed observers that add a section to the summary (the plant's tally)."""
        return [c for c in self.contributed if hasattr(c, "section")]

    def summary(self) -> RunSummary:
        """The run summary now: what `planthub run` prints and writes to summary.json."""
        run = self.scenario.run
        return RunSummary(self.scenario.name, self.scenario.path, self.master.tick, run.physics_rate, run.substeps,
                          self.wall_seconds, self.recorder.stats, len(self.scenario.record), self.out,
                          tuple(f.section() for f in self.figures),
                          ending(self.master.stopped, self.master.tick, run.end_tick, run.physics_rate,
                                 closed=self._closed, failure=self.failure),
                          logic_components(self.plant.components),
                          tuple(r for c in self.plant.components for r in getattr(getattr(c, "slave", None),
                                                                                  "restarts", ())))

    def close(self, reason: str = "closed") -> None:
        """End the run (participants told, files closed), write summary.json when there is a folder,
        release the plant."""
        if self._closed:
            return
        self._closed = True
        try:
            self.master.close(reason)
            if self.out is not None:
                self.summary().write(self.out / "summary.json")
        finally:
            self._close_parts(reason)

    def _emergency(self, message: str) -> None:
        """The process is about to end from another thread (an FMU in the hub's process hangs, a
        signal found the run stuck): the recording and event log are closed complete, summary.json
        says why. The stuck main thread is inside a call and touches neither."""
        self.failure = SimulationError(message)
        self.recorder.close(message)
        if self.bodies is not None:
            self.bodies.close(message)
        if self.out is not None:
            self.summary().write(self.out / "summary.json")
        for peer in (self.link.lockstep.peers.values() if self.link and self.link.lockstep else ()):
            if peer.process is not None:
                peer.process.log.unlink(missing_ok=True)   # the kernel kills the process itself (die_with_parent)

    def _close_parts(self, reason: str) -> None:
        WATCHDOG.forget(getattr(self, "_hang", None))
        if getattr(self, "interruption", None) is not None:
            self.interruption.close(reason)
        try:
            for part in (getattr(self, "link", None), getattr(self, "bodies", None), getattr(self, "recorder", None)):
                if part is not None:
                    part.close(reason)
        finally:
            self.plant.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.failure = exc[1]
        self.close("the run failed" if exc[0] is not None else "closed")


def _contributions(scenario: Scenario, plant) -> list:
    """The observers and stop conditions the scenario's modules contribute (Module.CONTRIBUTES):
    each distinct factory once, in the order the objects are declared."""
    entries = []
    for spec in scenario.objects:
        for entry in spec.module.CONTRIBUTES:
            if entry not in entries:
                entries.append(entry)
    made = (load_entry(entry)(plant) for entry in entries)
    return [m for m in made if m is not None]
