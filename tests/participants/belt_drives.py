"""Test participants: the belt drive slowed down on alternate steps, or failing at a given time."""
import sys
import time

from hub.participant import serve
from modules.belt_drive_logic import BeltDrive


class SlowOnEvenSteps(BeltDrive):
    """Answers late on every other step, so two such participants answer in changing order."""

    parameters = {"ramp": 0.5, "delay": 0.003, "odd": False}

    def step(self, t, h):
        if (round(t / h) % 2 == 1) == self.odd:
            time.sleep(self.delay)
        super().step(t, h)


class FailsAt(BeltDrive):
    parameters = {"ramp": 0.5, "fail_at": 0.1}

    def step(self, t, h):
        if t >= self.fail_at:
            raise ZeroDivisionError(f"asked to fail at t = {t:g} s")
        super().step(t, h)


if __name__ == "__main__":
    kind = {"slow": SlowOnEvenSteps, "fails": FailsAt, "plain": BeltDrive}[sys.argv.pop(1)]
    raise SystemExit(serve(kind()))
