"""An operator's hold on the run: pause, resume, single steps and the pace of a paced run, at communication points."""
from __future__ import annotations

POLL = 0.1   # s: while held, the longest wait for a command before looking at the stop conditions again


class Hold:
    """The run's control (hub/bus/commands.py `pause`, `resume`, `step N`, `pace F`).

    A pause holds the run after a point, before the physics goes on: the master asks `holding`
    after every point and then `wait`s here, where commands are taken at once, the views and the
    participants' lockstep kept alive (`idle`), and a stop condition (an operator's `stop`, a
    signal) ends the hold (an operator's stop at the next point, where it is recorded). `step N` lets N more points run, then holds again. `pace F` sets a
    paced run's factor of real time. None of it changes what the points compute.
    """

    def __init__(self, commands, *, pacer=None, state=lambda state, reason="": None, idle=lambda: None):
        self.commands = commands
        self.pacer = pacer
        self.state = state          # (state, reason): the run's state for viewers (schemas/wire.md)
        self.idle = idle            # called while held: keep the bus side going
        self.paused = False
        self.steps = 0              # points still to run before holding again
        commands.control = self

    def refuse(self, command) -> str | None:
        """Why a control command cannot be taken, or None."""
        if command.op == "pace" and self.pacer is None:
            return "this run is not paced: start it with --realtime to set its pace"
        if command.op == "step" and not self.paused:
            return "step: the run is not paused (pause it first)"
        return None

    def apply(self, command) -> None:
        op = command.op
        if op == "pause":
            self.paused, self.steps = True, 0
        elif op == "resume":
            self.paused, self.steps = False, 0
        elif op == "step":
            self.steps += command.value
        elif op == "pace":
            self.pacer.set_factor(command.value)

    def holding(self) -> bool:
        """After a point: whether the run waits here. A single step's point is counted off."""
        if not self.paused:
            return False
        if self.steps:
            self.steps -= 1
            return self.steps == 0   # the last point of the steps asked for: hold here again
        return True

    def wait(self, tick: int, stopped) -> None:
        """Hold the run at `tick` until it is resumed or stepped, or `stopped()` gives a stop."""
        rate = self.commands.rate
        self.state("paused", f"paused by an operator at t = {tick / rate:.9g} s")
        while self.paused and not self.steps and stopped() is None and not self.commands.stop_pending:
            self.commands.wait(tick, POLL)
            self.idle()
        if stopped() is None:
            self.state("running")
        if self.pacer is not None:
            self.pacer.start(tick)   # the time held is no lateness
