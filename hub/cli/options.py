"""The command line's shared options: how loud a command is (-v/-q), `--set`, and the one builder of what `run` and `test` both take."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from hub.scenario.yamlsource import read_value


def verbosity_parent() -> argparse.ArgumentParser:
    """-v/-q, for every subcommand (argparse's `parents=`)."""
    parent = argparse.ArgumentParser(add_help=False)
    loud = parent.add_argument_group("output")
    group = loud.add_mutually_exclusive_group()
    group.add_argument("-v", "--verbose", action="count", default=0,
                       help="more detail: the logic's events in the summary's table and debug notices; "
                            "-vv adds Zenoh's own log at info, -vvv at debug (RUST_LOG, when set, decides)")
    group.add_argument("-q", "--quiet", action="store_true",
                       help="only errors and what the command exists to print: no notices, no progress")
    return parent


def verbosity(args) -> int:
    """-1 quiet, 0 normal, 1 and up: as many -v as given."""
    return -1 if args.quiet else args.verbose


def add_set(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", type=_key_value,
                        help="override a scenario value for this run, e.g. --set run.physics_rate=1000 "
                             "(VALUE read as YAML: 0.5, true, [A, B], {file: x.fmu}); repeatable")


def overrides(args) -> dict:
    """The --set options (and --record-bodies) as a scenario's overrides: dotted key → value."""
    found = {key: value for key, value, _ in args.overrides}
    if getattr(args, "record_bodies", False):
        found.setdefault("run.record_bodies", True)
    return found


def set_texts(args) -> list[str]:
    """The --set options as given (KEY=VALUE), to report what a run was changed by."""
    return [text for _, _, text in args.overrides]


def _key_value(item: str) -> tuple[str, object, str]:
    key, sep, value = item.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {item!r}")
    try:
        return key, read_value(value), item   # YAML 1.2, as scenarios are read: 1e6 is a number, yes a string
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"{key}={value}: {exc}") from None


def number_type(unparsed: str, refused: str, accept):
    """An argparse `type` for a number: `unparsed` is the message for text that is no number
    ({text} in it), `refused` for a number `accept(value)` rejects ({text} or {value})."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(unparsed.format(text=repr(text))) from None
        if not accept(value):
            raise argparse.ArgumentTypeError(refused.format(text=repr(text), value=f"{value:g}"))
        return value
    return parse


_positive = number_type("expected a number, got {text}", "needs a positive factor, got {value}", lambda v: v > 0)
#: s, any finite time (`plot` and `compare`'s --from and --to)
seconds_argument = number_type("expected a time in seconds, got {text}", "expected a finite time in seconds, got {text}",
                               math.isfinite)


_positive_seconds = number_type("expected a time in seconds, got {text}", "needs a positive time in seconds, got {value}",
                                lambda v: v > 0 and math.isfinite(v))


def _times(text: str) -> tuple[float, ...]:
    """`--checkpoint-at 10,20.5`: finite times in seconds, not negative."""
    parse = number_type("expected times in seconds separated by commas, got {text}",
                        "expected times of 0 s or later, got {text}", lambda v: v >= 0 and math.isfinite(v))
    return tuple(parse(part.strip()) for part in text.split(","))


def add_run_arguments(parser: argparse.ArgumentParser, out_help: str) -> None:
    """The scenario and everything about running it: output folder, overrides, pacing, replay, bus.
    `run` and `test` both take these, so a run judged in CI can be set up as any other."""
    parser.add_argument("scenario", type=Path, help="the scenario file (YAML)")
    parser.add_argument("--out", type=Path, metavar="DIR", help=out_help)
    add_set(parser)
    parser.add_argument("--realtime", nargs="?", type=_positive, const=1.0, metavar="FACTOR",
                        help="pace the run to the wall clock (FACTOR× real time, default 1) and report overruns")
    parser.add_argument("--replay", type=Path, metavar="RUN_DIR",
                        help="apply the operator commands recorded in RUN_DIR/commands.csv at their ticks")
    parser.add_argument("--record-bodies", action="store_true",
                        help="record every body's pose at every point for playback (`planthub view RUN_DIR`; "
                             "as run.record_bodies: true)")
    saving = parser.add_argument_group("checkpoints (hub/run/checkpoint.py)")
    saving.add_argument("--checkpoint-at", type=_times, metavar="T[,T…]", default=(),
                        help="save the run's whole state at these times (s) to OUT/checkpoints/TICK.ckpt")
    saving.add_argument("--checkpoint-every", type=_positive_seconds, metavar="S",
                        help="save the run's whole state every S seconds to OUT/checkpoints/TICK.ckpt")
    saving.add_argument("--resume", type=Path, metavar="FILE",
                        help="continue from a checkpoint of this scenario to its end (--set may change the "
                             "duration, the logic's parameters and where logic runs)")
    bus = parser.add_argument_group("bus (any of these opens it; they override the scenario's run.bus)")
    bus.add_argument("--bus", action="store_true", help="open the bus even if the scenario has no run.bus")
    bus.add_argument("--listen", action="append", metavar="ENDPOINT", help="listen on, e.g. tcp/0.0.0.0:7447")
    bus.add_argument("--connect", action="append", metavar="ENDPOINT", help="connect to, e.g. tcp/10.0.0.2:7447")
    bus.add_argument("--mode", choices=["peer", "client", "router"], help="the hub's Zenoh mode")
