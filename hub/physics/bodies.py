"""The body table: every dynamic body of the world in body order, its fixed properties and its state as read per tick."""
from __future__ import annotations

from itertools import chain

import numpy as np

from hub.physics._quiet import quiet_stderr

with quiet_stderr():
    import pybullet


class Bodies:
    """The world's dynamic bodies (bottles), numbered in the order they were made: their
    pybullet ids, labels, masses, radii and half heights, and their state — positions,
    orientations, velocities, spins — as numpy arrays read once per tick.

    Not every body is read at every tick: a parked body (off stage) or one at rest (asleep in
    the engine, rest.py) keeps its row as it was, which is what the engine holds for it. The
    rows that are read (`live_rows`) and those in play (`play_rows`) are worked out again only
    after something changed them (`stale`); after a body was put somewhere by the plant, the next
    read takes every body (`full_read`). A body in free transport (transport.py) is not read
    either: the hub moves its row itself.
    """

    #: What changes as the world runs (hub/core/state.py); the properties and ids are structure.
    STATE = ("positions", "orientations", "velocities", "angular_velocities", "parked", "started", "full_read",
             "stale", "live_rows", "live_ids", "play_rows", "_in_play", "moved_rows", "free", "under", "fresh",
             "fresh_rows", "placed", "_state")

    def __init__(self, client: int, rest):
        self._client = client
        self._rest = rest
        self.ids: list[int] = []
        self.labels: list[str] = []
        self.masses = np.zeros(0)
        self.radii = np.zeros(0)
        self.half_heights = np.zeros(0)
        self.positions = np.zeros((0, 3))
        self.orientations = np.zeros((0, 4))
        self.velocities = np.zeros((0, 3))
        self.angular_velocities = np.zeros((0, 3))
        self.parked: set[int] = set()
        self.started = False
        self.full_read = True         # the next read takes every body (after a park or unpark)
        self.stale = True             # the row sets below need working out again
        self.live_rows = None         # rows read per tick: in play and awake (None: every body)
        self.live_ids: list[int] = []
        self.play_rows = None         # rows in play, not parked (None: every body)
        self._in_play = None          # the same, always as rows (in_play_rows), until a park or unpark
        self.moved_rows = None        # rows whose state changes per tick: read or in free transport (None: every body)
        self.free = None              # per body: in free transport, moved by the hub (transport.py), not read
        self.under = None             # the field under each live row at the last read (−1: none)
        # The rows the last read took that are in play, as one (n, 13) block, and which rows they
        # are (None: every body): what the watch tests, without indexing the state again.
        self.fresh = np.zeros((0, 13))
        self.fresh_rows = None
        # Bodies put into play since the last read, and where (their state arrays learn it at the
        # next read): a view drawing between the two shows them there, not off stage.
        self.placed: dict[int, tuple] = {}

    def check_open(self) -> None:
        """The body set is frozen at the first step (pybullet is deterministic only for an
        identical sequence of calls, so nothing is created inside the loop)."""
        if self.started:
            raise RuntimeError("bodies must be created before the first step")

    def add(self, body: int, label: str, mass: float, radius: float, half_height: float) -> int:
        self.ids.append(body)
        self._in_play = None
        self.labels.append(label)
        self.masses = np.append(self.masses, mass)
        self.radii = np.append(self.radii, radius)
        self.half_heights = np.append(self.half_heights, half_height)
        return len(self.ids) - 1

    def __len__(self) -> int:
        return len(self.ids)

    def read(self, fields) -> None:
        # One pose and one velocity query per body read: pybullet has no call for many bodies.
        # The arrays are built in one pass over the flattened tuples (half the cost of one
        # np.array per quantity), and positions, orientations and velocities are views of them.
        # Parked and resting bodies are not read (their pose stands); all are after a park or unpark.
        if not self.ids:
            return
        self.placed.clear()
        if self.stale:
            self.refresh()
        rows = None if self.full_read else self.live_rows
        self.full_read = False
        bodies = self.ids if rows is None else self.live_ids
        free = None if rows is not None or self.free is None or not self.free.any() else np.flatnonzero(self.free)
        if free is not None:
            kept = self._state[free].copy()   # a full read takes the engine's stale pose of a free body: not that
        if bodies:
            client, n = self._client, len(bodies)
            pose, velocity, flat = pybullet.getBasePositionAndOrientation, pybullet.getBaseVelocity, chain.from_iterable
            # Per body 13 numbers: position, orientation, velocity, spin — one row of `state`.
            read = np.fromiter(flat(flat([pose(b, client) + velocity(b, client) for b in bodies])), float, 13 * n)
            if rows is None:
                self._state = state = read.reshape(n, 13)
                self.positions, self.orientations = state[:, :3], state[:, 3:7]
                self.velocities, self.angular_velocities = state[:, 7:10], state[:, 10:]
                if free is not None:
                    state[free] = kept
                # A full read (rare: the first, or after a park) takes parked bodies too; off stage, not in play.
                play = self.play_rows
                self.fresh, self.fresh_rows = (state, None) if play is None else (state[play], play)
            else:
                self._state[rows] = self.fresh = read.reshape(n, 13)
                self.fresh_rows = rows
        else:
            self.fresh, self.fresh_rows = np.zeros((0, 13)), None
        # The field under every body read, once, for the belts' forces and the rest rule (free
        # transport looks its bottles' up itself).
        self.under = self.fields_under(fields, self.live_rows)

    def refresh(self) -> None:
        """Work out the bodies in play and those read per tick after a park, unpark, rest or wake."""
        play = np.ones(len(self.ids), bool)
        play[list(self.parked)] = False
        moved = play & ~self._rest.resting
        live = moved if self.free is None else moved & ~self.free
        self.play_rows = None if play.all() else np.flatnonzero(play)
        self.moved_rows = None if moved.all() else np.flatnonzero(moved)
        self.live_rows = None if live.all() else np.flatnonzero(live)
        self.live_ids = [] if self.live_rows is None else [self.ids[n] for n in self.live_rows.tolist()]
        self.stale = False
        self.under = None

    def moved(self) -> None:
        """A body was put somewhere by the plant (parked, unparked): read every body next tick."""
        self._in_play = None
        self.full_read = True
        self.stale = True
        self.under = None

    def fields_under(self, fields, rows) -> np.ndarray:
        return fields.which(self.positions if rows is None else self.positions[rows])

    def awake_rows(self) -> np.ndarray:
        if self.stale:
            self.refresh()
        return np.arange(len(self.ids)) if self.live_rows is None else self.live_rows

    def in_play_rows(self) -> np.ndarray:
        """The rows of the bodies in play (not parked), worked out again after a park or unpark
        (at every look of free transport's: a new array each time cost 8 µs)."""
        rows = self._in_play
        if rows is None:
            rows = self._in_play = np.array([n for n in range(len(self.ids)) if n not in self.parked], dtype=int)
        return rows
