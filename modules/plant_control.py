"""Plant management (the paper's PLC/MES role) as a participant: routes each bottle by its id.

Each track switch i has an ID reader just before it. When reader i reads a bottle, the
destination looked up for its id (the reader's `destination` slot) decides: switch i turns into
its branch (MoveToWorkingPos) if the bottle is for that branch's lane, and back to base position
(MoveToBasePos) otherwise. `--lanes A,B,C` names the lane behind each switch's branch, in order;
their number is the number of reader/switch pairs, and the interface follows from it:

    inputs   r<i>_read (void), r<i>_destination (string)     for i = 1 … number of lanes
    outputs  sw<i>_work (void), sw<i>_base (void)

A scenario runs it as its own process on the bus (`python: [modules.plant_control, --lanes, …]`,
launched by the hub; or joined from anywhere with `python -m modules.plant_control --lanes …
--run RUN --name NAME --connect …`), or in the hub's process with `runs: hub`.
"""
import argparse

from hub.participant import Participant, add_options, check_options, serve


class PlantControl(Participant):
    def __init__(self, lanes: list[str]):
        self.lanes = list(lanes)
        pairs = range(1, len(self.lanes) + 1)
        self.inputs = {**{f"r{i}_read": "void" for i in pairs}, **{f"r{i}_destination": "string" for i in pairs}}
        self.outputs = {**{f"sw{i}_work": "void" for i in pairs}, **{f"sw{i}_base": "void" for i in pairs}}
        self._pairs = [(f"r{i}_read", f"r{i}_destination", f"sw{i}_work", f"sw{i}_base", lane)
                       for i, lane in zip(pairs, self.lanes)]

    def step(self, t, h):
        for read, destination, work, base, lane in self._pairs:
            if getattr(self, read):
                ours = getattr(self, destination) == lane
                setattr(self, work, ours)
                setattr(self, base, not ours)


def _arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--lanes", required=True, type=_lanes,
                        help="comma-separated destination of each switch's branch, in the order of the switches")
    return parser


def _lanes(text: str) -> list[str]:
    lanes = [lane.strip() for lane in text.split(",")]
    if not all(lanes):
        raise argparse.ArgumentTypeError(f"an empty lane name in {text!r}")
    return lanes


def participant(argv: list[str]) -> PlantControl:
    """The logic from its arguments (`--lanes A,B,C`): what `runs: hub` runs."""
    return PlantControl(_arguments(argparse.ArgumentParser(prog="modules.plant_control")).parse_args(argv).lanes)


if __name__ == "__main__":
    parser = _arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]))
    add_options(parser)
    args = check_options(parser, parser.parse_args())
    raise SystemExit(serve(PlantControl(args.lanes), args=args))
