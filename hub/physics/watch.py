"""The physics watch: a body whose state turns non-finite, moves faster than any scene could
move it, or leaves the world's box is a run gone wrong — stopped, or taken out, and named."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

POLICIES = ("stop", "remove")


class Watch:
    """Tests, at every tick, the rows the world just read (bodies in play and awake; parked and
    resting ones are not read, so not tested) against a speed bound and the world's box.

    Without it a bottle the engine flings at 50 m/s leaves the rails and falls for ever, and the
    recording says nothing. The test runs on the arrays already read: a comparison catches
    NaN too (NaN ≤ bound is False), so one pass covers non-finite, too fast and out of the box.

    The box is the static geometry's bounding box and the bodies' places at the start, widened by
    MARGIN (a bottle that fell off a belt's end is below every floor by then) and by ABOVE
    upwards (an arm lifts a bottle over the belts). The default speed bound is FACTOR times the
    fastest belt (at least MIN_BELT) plus the speed of a free fall over the box's height: no
    belt, gate or fall in the scene can move a bottle faster; a set `max_speed` replaces it.
    """

    MARGIN = 0.5     # m beside and below the scene
    ABOVE = 2.0      # m above its highest static geometry
    FACTOR = 4.0
    MIN_BELT = 1.0   # m/s: a scene whose belts all stand still at the start may start them

    #: hub/core/state.py: the bound follows the belts' speeds; the box is fixed when the world starts.
    STATE = ("enabled", "lo", "hi", "_fall", "bound", "_bound2", "removed", "_scale", "_shift")

    def __init__(self, gravity: float, max_speed: float | None = None, policy: str = "stop"):
        if policy not in POLICIES:
            raise ValueError(f"watch policy {policy!r}: one of {', '.join(POLICIES)}")
        self.gravity = gravity
        self.max_speed = max_speed
        self.policy = policy
        self.enabled = False   # until configured: a scenario's plant always is (hub/run/plant.py)
        self.lo = np.full(3, -math.inf)
        self.hi = np.full(3, math.inf)
        self.bound = math.inf
        self._bound2 = math.inf
        self._fall = 0.0
        self._columns()
        self.removed: list[tuple[int, int, str]] = []   # (tick, body, cause) taken out by the `remove` policy

    def configure(self, max_speed: float | None, policy: str) -> None:
        """Turn the watch on, before the world starts. A bare PhysicsWorld (tests, benchmarks of
        the engine) is unwatched unless it asks: some tip bottles off a table on purpose."""
        self.__init__(self.gravity, max_speed, policy)
        self.enabled = True

    def arm(self, static_lo, static_hi, positions: np.ndarray, fastest_belt: float) -> None:
        """Fix the box and the bound when the world starts."""
        lo, hi = np.asarray(static_lo, float), np.asarray(static_hi, float)
        if len(positions):
            lo, hi = np.minimum(lo, positions.min(0)), np.maximum(hi, positions.max(0))
        if not np.isfinite(lo).all():   # no static geometry and no body: no box, only a stated bound
            if self.max_speed is not None:
                self.belt_speed(fastest_belt)
            return
        self.lo = lo - self.MARGIN
        self.hi = hi + np.array([self.MARGIN, self.MARGIN, self.ABOVE])
        self._fall = math.sqrt(2.0 * self.gravity * float(self.hi[2] - self.lo[2]))
        self.belt_speed(fastest_belt)

    def belt_speed(self, speed: float) -> None:
        """A belt runs at `speed`: the default bound grows with the fastest belt (deterministic: it
        only follows the scenario's own speeds)."""
        if self.max_speed is not None:
            bound = self.max_speed
        else:
            bound = max(self.bound if math.isfinite(self.bound) else 0.0,
                        self.FACTOR * max(abs(speed), self.MIN_BELT) + self._fall)
        self.bound, self._bound2 = bound, bound * bound
        self._columns()

    def check(self, state: np.ndarray, rows: np.ndarray | None) -> np.ndarray | None:
        """The rows that break a rule, or None (the usual case). `state`: the (n, 13) block just
        read — position, orientation, velocity, spin per row; `rows`: which rows (None: 0…n−1).

        The usual case is one compiled loop (`_within`): an affine map of every column onto [−1, 1]
        where it is allowed (the box for positions; ±bound/√3 per velocity component, which implies
        the bound). Orientation and spin are mapped by 0, which keeps only NaN or ±inf
        (0·inf is NaN). Anything that fails it gets the exact test (the speed's norm)."""
        if _within(state, self._scale, self._shift):
            return None
        p, v = state[:, :3], state[:, 7:10]
        ok = np.isfinite(state).all(1)
        ok &= (p >= self.lo).all(1) & (p <= self.hi).all(1)
        ok &= np.einsum("ij,ij->i", v, v) <= self._bound2
        if ok.all():
            return None
        bad = np.flatnonzero(~ok)
        return bad if rows is None else rows[bad]

    def _columns(self) -> None:
        """The affine map of `check`'s usual case, after the box or the bound changed."""
        scale, shift = np.zeros(13), np.zeros(13)
        if np.isfinite(self.lo).all():
            half, mid = (self.hi - self.lo) / 2.0, (self.hi + self.lo) / 2.0
            scale[:3], shift[:3] = 1.0 / half, -mid / half
        if math.isfinite(self.bound):
            scale[7:10] = math.sqrt(3.0) / self.bound
        self._scale, self._shift = scale, shift

    def cause(self, position: np.ndarray, velocity: np.ndarray, rest=()) -> str:
        """Why one body broke the rules, in words with its numbers (`rest`: orientation and spin)."""
        p, v = ", ".join(f"{x:.3f}" for x in position), ", ".join(f"{x:.3f}" for x in velocity)
        if not (np.isfinite(position).all() and np.isfinite(velocity).all() and np.isfinite(rest).all()):
            o = ", ".join(f"{x:.3f}" for x in rest)
            return f"its state is not finite (position ({p}) m, velocity ({v}) m/s, orientation and spin ({o}))"
        speed = float(np.linalg.norm(velocity))
        if speed * speed > self._bound2:
            where = "run.watch.max_speed" if self.max_speed is not None else "the default bound, from the fastest belt"
            return f"it moves at {speed:.2f} m/s, above {self.bound:.2f} m/s ({where}); position ({p}) m"
        if position[2] < self.lo[2]:
            return (f"it fell below the floor: z = {position[2]:.3f} m, the world's box ends at "
                    f"z = {self.lo[2]:.3f} m (velocity ({v}) m/s)")
        lo, hi = ", ".join(f"{x:.3f}" for x in self.lo), ", ".join(f"{x:.3f}" for x in self.hi)
        return f"it left the world's box ({lo})–({hi}) m at ({p}) m (velocity ({v}) m/s)"


@njit(cache=True)
def _within(state, scale, shift):
    """Whether every value of `state` maps into [−1, 1] (Watch.check's usual case; NaN does not)."""
    for i in range(state.shape[0]):
        for j in range(state.shape[1]):
            if not abs(state[i, j] * scale[j] + shift[j]) <= 1.0:
                return False
    return True
