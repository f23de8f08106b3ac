"""Test participants with state of their own (a counter, a queue, a random generator) for save and restore; one that cannot save, one from before save and restore."""
import collections
import random
import sys
import threading

from hub.bus import participant as library
from hub.participant import Participant, serve

INPUTS = {"x": "real", "push": "void", "label": "string"}
OUTPUTS = {"count": "int", "total": "real", "head": "real", "popped": "void", "where": "vec3", "note": "string"}


class Counter(Participant):
    """Counts its steps, queues a value at every `push` and pops the oldest beyond `keep`: its
    outputs depend on everything it has seen, so a restore that misses any of it shows."""

    inputs = INPUTS
    outputs = OUTPUTS
    parameters = {"keep": 3}

    def start(self):
        self.queue = collections.deque()
        self.seen = []
        self.alias = self.seen   # two names for one list: a restore keeps them one
        self.rng = random.Random(7)

    def step(self, t, h):
        self.count += 1
        if self.push:
            self.queue.append(self.x * 1.1 + self.rng.random())
        if len(self.queue) > self.keep:
            self.head = self.queue.popleft()
            self.popped = True
        self.total += self.x / 3.0
        self.alias.append(self.label)
        self.where = (self.total, t, float(len(self.queue)))
        self.note = f"{self.count}:{len(self.queue)}:{len(self.seen)}:{self.label}"


class Unsaveable(Counter):
    """Holds a lock: pickle cannot take it, so the default save names it."""

    def start(self):
        super().start()
        self.guard = threading.Lock()


class FromBefore(Counter):
    """Served by a library from before save and restore: the request is never answered."""


KINDS = {"counter": Counter, "unsaveable": Unsaveable, "old": FromBefore}


def participant(argv):
    """The logic for the hub's process: the kind named by the first argument."""
    return KINDS[argv[0]]()


if __name__ == "__main__":
    kind = sys.argv.pop(1)
    if kind == "old":   # the protocol loop of an older library: it does not know the message
        library._Link._checkpoint = lambda link, payload: None
    raise SystemExit(serve(KINDS[kind]()))
