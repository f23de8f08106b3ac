"""The internal model of a place/transition net, whichever format it was written in."""

from dataclasses import dataclass


@dataclass(frozen=True)
class Place:
    name: str
    marking: int  # initial marking
    description: str
    line: int  # in the net file, for messages and comments in the generated C


@dataclass(frozen=True)
class Transition:
    """A transition and its arcs, each a (place, weight) pair in declaration order."""

    name: str
    inputs: tuple
    outputs: tuple
    inhibitors: tuple  # disabled while the place holds at least weight tokens
    delay: float | None  # seconds it must stay enabled before it fires; None: immediate, no parameter
    description: str
    line: int

    @property
    def takes(self):
        """(place, tokens) this transition removes when it fires.

        The net change of its arcs: a place that is both input and output
        (a self-loop) is only tested, so that it cannot restore a token that a
        conflicting transition took in the same step."""
        outputs = dict(self.outputs)
        return tuple((p, w - outputs.get(p, 0)) for p, w in self.inputs if w > outputs.get(p, 0))

    @property
    def gives(self):
        """(place, tokens) this transition adds when it fires: the net change, like takes."""
        inputs = dict(self.inputs)
        return tuple((p, w - inputs.get(p, 0)) for p, w in self.outputs if w > inputs.get(p, 0))


@dataclass(frozen=True)
class Net:
    name: str  # the FMU's model identifier: the file name without .pnml / .net.yaml
    description: str
    places: tuple
    transitions: tuple
    source: str  # the file it was read from

    @property
    def delayed(self):
        """The transitions with a delay, in declaration order; each gets a <name>_delay parameter."""
        return tuple(t for t in self.transitions if t.delay is not None)

    def structure(self):
        """Everything but file and lines: equal for the same net written in PNML and in YAML."""
        return (self.name, self.description,
                tuple((p.name, p.marking, p.description) for p in self.places),
                tuple((t.name, t.inputs, t.outputs, t.inhibitors, t.delay, t.description) for t in self.transitions))
