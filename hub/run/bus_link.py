"""The bus side of one run: the lockstep with its participants, the data plane, the view feed and live operator commands."""
from __future__ import annotations

import logging
from pathlib import Path

from hub.bus import wire
from hub.bus.commands import Commands
from hub.bus.dataplane import DataPlane
from hub.bus.lockstep import Lockstep
from hub.bus.session import Bus, local_endpoint
from hub.bus.settings import BusSettings, exposure
from hub.bus.wire import check_run_name
from hub.view.broadcast import Broadcast

_log = logging.getLogger(__name__)


class BusLink:
    """Joins a run to the bus: an observer (hub/core/observer.py) that publishes each point to
    its subscribers and keeps the participants' lockstep alive, and, unless the run replays
    recorded commands, the source of live operator commands.

    `bus` is an open Bus, or None: then one is opened from the scenario's `run.bus` (or the
    defaults) and closed with the link. `logs` is the folder where what launched participants
    said is kept (the run's), or None. `start` launches and awaits the participants, before
    the first point.
    """

    def __init__(self, plant, recorder, slaves: list, bus: Bus | None = None, commands: Commands | None = None,
                 log=None, looks=(), figures=lambda: [], logs: Path | None = None, faults=None, timeline=None):
        scenario = plant.scenario
        self.plant = plant
        self.recorder = recorder
        self.log = log or (lambda text: None)
        self.own_bus = bus is None
        self.bus = bus if bus is not None else Bus(scenario.run.bus or BusSettings())
        self.slaves = slaves
        self.commands = commands
        self.dataplane = self.lockstep = self.view = None
        self.looks, self.figures = looks, figures
        self.faults = faults   # () → the instructor's board (hub/run/faults.py FaultBook.board), or None
        self.logs = logs
        # () → the run's Checkpointer (the checkpoints a rewind may go back to: hub/run/rewind.py), or None
        self.timeline = timeline or (lambda: None)
        self._timeline_version = None
        self._timeline_pub = None
        self._timeline_bytes = b""
        self._closed = False

    def start(self) -> Commands | None:
        """Declare the data plane and the command queue, then launch and await the participants.
        Returns the live commands (None when the run replays its commands)."""
        settings, plant = self.bus.settings, self.plant
        run = check_run_name(plant.scenario.name)
        where = ", ".join(local_endpoint(e) for e in self.bus.endpoints) or ", ".join(settings.connect)
        self.log(f"run {run!r} on the bus ({settings.mode}, {where}): plant/{run}/**")
        for warning in exposure(settings):
            _log.warning("planthub: warning: %s", warning)
        # Everything that listens is declared before the hub's liveliness token, which tells others
        # the hub is there: a put made before a subscription is known goes nowhere.
        self.dataplane = DataPlane(self.bus, run, plant, settings)
        self.view = Broadcast(self.bus, run, plant, looks=self.looks, figures=self.figures, faults=self.faults)
        live = None
        if self.commands is None:
            live = self.commands = Commands(plant, self.recorder)
            live.listen(self.bus, run)
        self.lockstep = Lockstep(self.bus, run, self.slaves, lease=settings.lease, on_loss=settings.on_loss,
                                 rate=plant.world.rate, log=self._notice, warn=self.log, logs=self.logs)
        self._timeline_pub = self.bus.publisher(wire.control_key(run, "checkpoints"), wire.MSGPACK)
        self._send_timeline(plant.world.tick)
        self.bus.answer(wire.control_key(run, "checkpoints"), lambda: self._timeline_bytes, wire.MSGPACK)
        self.lockstep.start(plant.world.tick)
        return live

    def _send_timeline(self, tick: int) -> None:
        """The checkpoints a rewind may go back to, when they changed (schemas/wire.md `checkpoints`)."""
        checkpoints = self.timeline()
        version = None if checkpoints is None else checkpoints.version
        if version == self._timeline_version and self._timeline_bytes:
            return
        self._timeline_version = version
        rate = self.plant.world.rate
        self._timeline_bytes = wire.pack({"tick": tick, "time": tick / rate, "rate": rate,
                                          "checkpoints": [] if checkpoints is None else sorted(checkpoints.taken)})
        self._timeline_pub.put(self._timeline_bytes)

    def rebind(self, plant, looks, faults) -> None:
        """Serve `plant`, built again by a rewind (hub/run/rewind.py), with its contributed `looks`
        and the instructor's board `faults`: the same keys, viewers and participants."""
        self.plant, self.looks, self.faults = plant, looks, faults
        if self.dataplane is not None:
            self.dataplane.rebind(plant)
        if self.view is not None:
            self.view.rebind(plant, looks=looks, faults=faults)

    def _notice(self, text: str) -> None:
        self.recorder.notice(self.plant.world.tick, text)
        self.log(text)

    def observe(self, tick: int, signals, events) -> None:
        self.dataplane.publish(tick, signals)
        self.view.observe(tick, signals, events)
        self._send_timeline(tick)
        self.lockstep.poll()

    def idle(self) -> None:
        """While the run is held (an operator's pause): participants' news taken in, views kept fresh."""
        self.lockstep.poll()
        self.view.idle(self.plant.world.tick)
        self._send_timeline(self.plant.world.tick)

    def close(self, reason: str = "closed") -> None:
        """Tell participants the run is over, stop the processes it launched, close a bus it opened."""
        if self._closed:
            return
        self._closed = True
        try:
            try:
                if self._timeline_pub is not None:   # a checkpoint at the last point, taken after this link observed it
                    self._send_timeline(self.plant.world.tick)
                if self.view is not None:   # the final figures (an exercise's score) before the state says stopped
                    self.view.close(reason)
                if self.dataplane is not None:   # the last values go out before the run's state says stopped
                    self.dataplane.close()
            finally:
                if self.lockstep is not None:
                    self.lockstep.close(reason)
        finally:
            if self.own_bus:
                self.bus.close()
