"""Real-time pacing with a fake clock: sleeps to each point's wall-clock time, counts late points."""
import pytest

from hub.run.pacing import Pacer


class FakeClock:
    def __init__(self):
        self.now = 100.0
        self.slept = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.slept.append(round(seconds, 9))
        self.now += seconds


def pacer(factor=1.0, rate=100):
    clock = FakeClock()
    return Pacer(rate, factor, clock=clock, sleep=clock.sleep), clock


def test_points_on_time_are_held_until_their_wall_clock_time():
    p, clock = pacer()
    p.start(0)
    for tick in (10, 20, 30):
        clock.now += 0.004          # the work of one point takes 4 ms of its 10 ms
        p.wait(tick)
    assert clock.slept == [0.096, 0.096, 0.096] and p.overruns == 0


def test_a_factor_speeds_the_schedule_up():
    p, clock = pacer(factor=4.0)
    p.start(0)
    p.wait(100)                     # 1 s simulated is due after 0.25 s
    assert clock.slept == [0.25]


def test_a_late_point_is_an_overrun_and_the_schedule_restarts_from_it():
    p, clock = pacer()
    p.start(0)
    clock.now += 0.030              # point at tick 1 (due at 10 ms) comes 20 ms late
    p.wait(1)
    clock.now += 0.002
    p.wait(2)                       # due 10 ms after the late point, not at 20 ms from the start
    assert (p.overruns, round(p.worst, 9), clock.slept) == (1, 0.02, [0.008])
    assert p.summary() == "paced at 1× real time, 1 of 2 points late (worst 20.0 ms)"


def test_lateness_within_the_tolerance_is_on_time():
    p, clock = pacer()
    p.start(0)
    clock.now += 0.0105
    p.wait(1)
    assert p.overruns == 0 and p.summary() == "paced at 1× real time, no overruns in 1 point"


def test_a_factor_must_be_positive():
    with pytest.raises(ValueError, match="a real-time factor must be positive, got 0"):
        Pacer(100, 0)
