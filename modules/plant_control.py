"""Plant management (the paper's PLC/MES role) as a participant: routes each bottle by its id.

Each track switch i has an ID reader just before it. When reader i reads a bottle, the
destination looked up for its id (the reader's `destination` slot) decides: switch i turns into
its branch (MoveToWorkingPos) if the bottle is for that branch's lane, and back to base position
(MoveToBasePos) otherwise. `--lanes A,B,C` names the lane behind each switch's branch, in order;
their number is the number of reader/switch pairs, and the interface follows from it:

    inputs   r<i>_read (void), r<i>_destination (string)     for i = 1 … number of lanes
             r<i>_occupied (bool)                            with --occupied
             b327 (void)                                     with --separator
             b327 (void), b02_in (bool), b02_out (bool)      with --feed
    outputs  sw<i>_work (void), sw<i>_base (void)
             sep_b327 (void)                                 with --separator
             sep_b327 (void), b01_run (bool)                 with --feed

`--track` (with `--occupied`) also follows each bottle from reader to reader: the destination of
every bottle read at reader i − 1 and not for its lane is queued for reader i, and when reader
i sees a bottle arrive (`occupied` rises) without reading it, the head of that queue routes it.
A reader that reads nothing (a fault: hub/run/faults.py `reader_fault`) then misroutes nothing;
without `--track` the switch after it keeps whatever position it had (the shipped exercise
scenarios/exercise_reader_fault.yaml scores the one against the other).

`--separator` puts the management between the sensor B327 behind the separator and the
separator's logic: `b327` (its on_stay) is passed on as `sep_b327`. With `--stuck-after S` it
watches the sensor: seen at every step for longer than S (no bottle takes that long to leave
the section behind the separator, which lets one in at a time), it is taken as stuck and no
longer passed on, until it is clear for a step; the separator then relies on B321 and its
rearm delay. Without, a sensor stuck on holds the separator shut for good
(scenarios/exercise_separator_sensor.yaml).

`--feed` puts the management on the feed of the filler's belt b02: the separator (as
`--separator` does) and the belt b01 behind it (`b01_run`, true at every step); `b02_in` is a
light barrier at b02's start, `b02_out` the filler's exit barrier. With `--slow-after S` it
watches b02: a bottle crossing b02's start for longer than S (0.14 s at full speed) means b02
runs slow, and until a bottle crosses it in S again, b01 stands and the separator holds
(`sep_b327` on) while a bottle is on b02 before the filler's exit, so the filler sees one
bottle at a time. Without, bottles come as fast as ever onto a slow b02: they queue at the
filler's stopper touching, and the one behind a filled bottle slips through with it while the
stopper is open, unfilled, to be rejected (scenarios/exercise_belt_failure.yaml).

A scenario runs it as its own process on the bus (`python: [modules.plant_control, --lanes, …]`,
launched by the hub; or joined from anywhere with `python -m modules.plant_control --lanes …
--run RUN --name NAME --connect …`), or in the hub's process with `runs: hub`.
"""
import argparse

from hub.participant import Participant, add_options, check_options, serve


class PlantControl(Participant):
    def __init__(self, lanes: list[str], occupied: bool = False, track: bool = False, separator: bool = False,
                 stuck_after: float | None = None, feed: bool = False, slow_after: float | None = None):
        self.lanes = list(lanes)
        pairs = range(1, len(self.lanes) + 1)
        self.inputs = {**{f"r{i}_read": "void" for i in pairs}, **{f"r{i}_destination": "string" for i in pairs},
                       **({f"r{i}_occupied": "bool" for i in pairs} if occupied else {})}
        self.outputs = {**{f"sw{i}_work": "void" for i in pairs}, **{f"sw{i}_base": "void" for i in pairs}}
        separator = separator or feed   # the feed is the separator and the belt b01 behind it
        if separator:
            self.inputs["b327"], self.outputs["sep_b327"] = "void", "void"
        self.separator, self.stuck_after = separator, stuck_after
        self.b327_since = None   # the time B327 has been seen at every step from; None: clear at the last
        if feed:
            self.inputs["b02_in"], self.inputs["b02_out"], self.outputs["b01_run"] = "bool", "bool", "bool"
            self.b01_run = True
        self.feed, self.slow_after = feed, slow_after
        self.b02_since = None    # the time b02_in has been occupied at every step from; None: clear at the last
        self.b02_slow = False    # whether the last bottle crossed b02's start slowly (or is still crossing)
        self.b02_holds = 0       # bottles past b02's start and not yet out of the filler
        self.b02_out_was = False  # the filler's exit barrier at the last step
        self._pairs = [(f"r{i}_read", f"r{i}_destination", f"sw{i}_work", f"sw{i}_base", lane)
                       for i, lane in zip(pairs, self.lanes)]
        self.track = track
        self.queues = [[] for _ in self.lanes]     # destinations on their way to each reader, in order
        self.seen = [False for _ in self.lanes]    # each reader's `occupied` at the last step

    def step(self, t, h):
        if self.separator:
            self._watch(t)
        if self.feed:
            self._hold(t)
            if not self.b01_run:
                self.sep_b327 = True   # the separator lets no bottle onto a standing b01
        for i, (read, destination, work, base, lane) in enumerate(self._pairs):
            arrived = False
            if self.track:
                now = getattr(self, f"r{i + 1}_occupied")
                arrived, self.seen[i] = now and not self.seen[i], now
            if getattr(self, read):
                found = getattr(self, destination)
                if self.track and self.queues[i]:
                    self.queues[i].pop(0)   # the bottle the reader before announced: read here itself
            elif arrived and self.queues[i]:
                found = self.queues[i].pop(0)   # arrived unread: the reader before said what it is
            else:
                continue
            ours = found == lane
            setattr(self, work, ours)
            setattr(self, base, not ours)
            if self.track and not ours and i + 1 < len(self.queues):
                self.queues[i + 1].append(found)


    def _watch(self, t):
        """Pass B327 on to the separator, unless it has been on for longer than stuck_after."""
        if not self.b327:
            self.b327_since = None
            self.sep_b327 = False
            return
        if self.b327_since is None:
            self.b327_since = t
        stuck = self.stuck_after is not None and t - self.b327_since > self.stuck_after
        self.sep_b327 = not stuck

    def _hold(self, t):
        """Run b01, unless b02 runs slow (a bottle crossed or is crossing its start in more than
        slow_after) and holds a bottle before the filler's exit."""
        if self.slow_after is None:
            return
        if self.b02_out_was and not self.b02_out:
            self.b02_holds = max(0, self.b02_holds - 1)
        self.b02_out_was = self.b02_out
        if self.b02_in:
            if self.b02_since is None:
                self.b02_since = t
            if t - self.b02_since > self.slow_after:
                self.b02_slow = True
        elif self.b02_since is not None:
            self.b02_slow = t - self.b02_since > self.slow_after
            self.b02_holds += 1
            self.b02_since = None
        self.b01_run = not (self.b02_slow and (self.b02_in or self.b02_holds))


def _arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("--lanes", required=True, type=_lanes,
                        help="comma-separated destination of each switch's branch, in the order of the switches")
    parser.add_argument("--occupied", action="store_true", help="take each reader's `occupied` (inputs r<i>_occupied)")
    parser.add_argument("--track", action="store_true",
                        help="route a bottle a reader did not read by what the reader before read (needs --occupied)")
    parser.add_argument("--separator", action="store_true",
                        help="pass the sensor B327 on to the separator's logic (input b327, output sep_b327)")
    parser.add_argument("--stuck-after", type=float, metavar="S",
                        help="with --separator: take B327 as stuck once seen for longer than S seconds on end")
    parser.add_argument("--feed", action="store_true",
                        help="run the feed of the filler's belt b02: the separator (as --separator) and the belt b01 "
                             "(inputs b02_in, b02_out: barriers at b02's start and the filler's exit; output b01_run)")
    parser.add_argument("--slow-after", type=float, metavar="S",
                        help="with --feed: a bottle crossing b02's start for longer than S seconds means b02 runs "
                             "slow: then feed one bottle at a time to the filler, until one crosses in S again")
    return parser


def _lanes(text: str) -> list[str]:
    lanes = [lane.strip() for lane in text.split(",")]
    if not all(lanes):
        raise argparse.ArgumentTypeError(f"an empty lane name in {text!r}")
    return lanes


def participant(argv: list[str]) -> PlantControl:
    """The logic from its arguments (`--lanes A,B,C`): what `runs: hub` runs."""
    return _made(_arguments(argparse.ArgumentParser(prog="modules.plant_control")).parse_args(argv))


def _made(args) -> PlantControl:
    if args.track and not args.occupied:
        raise SystemExit("modules.plant_control: --track follows bottles by the readers' `occupied`: give --occupied")
    if args.stuck_after is not None and not args.separator:
        raise SystemExit("modules.plant_control: --stuck-after watches the separator's sensor: give --separator")
    if args.slow_after is not None and not args.feed:
        raise SystemExit("modules.plant_control: --slow-after watches the start of b02: give --feed")
    return PlantControl(args.lanes, args.occupied, args.track, args.separator, args.stuck_after, args.feed,
                        args.slow_after)


if __name__ == "__main__":
    parser = _arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]))
    add_options(parser)
    args = check_options(parser, parser.parse_args())
    raise SystemExit(serve(_made(args), args=args))
