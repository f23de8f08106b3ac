"""Test participants: the belt drive slowed down on alternate steps, stalling once, failing at a given
time, sending a wrongly typed output or NaN."""
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


class StallsOnce(BeltDrive):
    """Takes `stall` seconds over the step at `stall_at`: slow, but its connection stays alive."""

    parameters = {"ramp": 0.5, "stall_at": 1.0, "stall": 1.0}

    def step(self, t, h):
        if abs(t - self.stall_at) < h / 2:
            time.sleep(self.stall)
        super().step(t, h)


class SaysOneForTrue(BeltDrive):
    """Sends an integer where the slot is a bool: the hub names the output and the step."""

    def step(self, t, h):
        super().step(t, h)
        self.running = int(self.running)


class NanAt(BeltDrive):
    """Answers NaN for its speed from `nan_at` on: the hub must not let it reach the belt."""

    parameters = {"ramp": 0.5, "nan_at": 0.5}

    def step(self, t, h):
        super().step(t, h)
        if t >= self.nan_at:
            self.speed = float("nan")


KINDS = {"slow": SlowOnEvenSteps, "fails": FailsAt, "plain": BeltDrive, "ints": SaysOneForTrue,
         "stalls": StallsOnce, "nan": NanAt}


def participant(argv):
    """The logic for `runs: hub`: the kind named by the first argument."""
    return KINDS[argv[0]]()


if __name__ == "__main__":
    raise SystemExit(serve(KINDS[sys.argv.pop(1)]()))
