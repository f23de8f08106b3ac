"""`planthub run` and `planthub test`: one scenario run, set up from the same options, printed as a summary or judged against its expectations."""
from __future__ import annotations

import logging
import socket
import sys
import time
from datetime import datetime
from pathlib import Path

from hub.cli.bus import bus_settings
from hub.cli.exits import FAILED, OK, UsageError
from hub.cli.options import overrides, set_texts, verbosity
from hub.core import scratch
from hub.core.errors import PlanthubError, ScenarioError
from hub.scenario.checker import load_scenario

_log = logging.getLogger(__name__)


def run_command(args) -> int:
    """`planthub run`: the summary on stdout, the files in --out (default runs/<name>)."""
    from hub.run.assembly import Run

    scratch.sweep()   # what a hub killed before its clean-up left in the temporary folder
    scenario = load_scenario(args.scenario, overrides(args))
    out = args.out or Path("runs") / (scenario.name + ("_replay" if args.replay else ""))
    _check_replay(args, out)
    bus, pacer = _bus(args, scenario), _pacer(args, scenario)
    progress = [_Progress(scenario.run.end_tick)] if sys.stderr.isatty() and verbosity(args) >= 0 else []
    view = _view(args, scenario)
    try:
        # signals: a Ctrl-C or SIGTERM ends the run at its next point, summary and files complete.
        run = Run(scenario, out=out, bus=bus, replay=args.replay, pacer=pacer, signals=True,
                  observers=progress + ([view] if view is not None else []), **_checkpointing(args, scenario))
        try:
            with run:
                _log.debug(f"running {scenario.name} to t = {scenario.run.end_tick / scenario.run.physics_rate:g} s, "
                           f"writing to {out}")
                if view is not None:
                    _start_view(view, run, bus)
                result = run.run()
                run.close(result.stopped_by or "the run reached its end")
        except KeyboardInterrupt:   # one that came outside the run's own handling (hub/run/interruption.py)
            _print_run(run, args)   # the figures so far; summary.json says it was interrupted
            raise
        except PlanthubError:   # a run that failed (a participant lost, a PLC that stopped answering):
            _print_run(run, args)   # its figures so far, as summary.json has them; the error follows
            raise
    finally:
        if view is not None:
            view.stop()   # the run closed it, unless the run failed before its master was made
        if bus is not None:
            bus.close()
    _print_run(run, args)
    return run.interruption.exit_status or OK   # 130 after a Ctrl-C, 143 after SIGTERM


def _print_run(run, args) -> None:
    print("\n".join(run.summary().lines(verbose=verbosity(args) > 0)))
    pacer, link, out = run.master.pacer, run.link, run.out
    if pacer is not None:
        print(f"  pacing       {pacer.summary()}")
    if link is not None and link.lockstep is not None:
        count = len(link.lockstep.peers)
        plane = link.dataplane
        skipped = f", {plane.skipped} points skipped by the data plane under load" if plane.skipped else ""
        lost = f", {plane.outbox.events_lost} events lost" if plane.outbox.events_lost else ""
        print(f"  bus          {count} participant{'s' if count != 1 else ''}, "
              f"{plane.samples} data-plane samples{skipped}{lost}")
    if out is not None and (out / "commands.csv").is_file():
        print(f"  commands     {out / 'commands.csv'}")


def test_command(args) -> int:
    """`planthub test`: a line per expectation and the tally; exit 1 if one failed. A SIGINT or
    SIGTERM ends the run at its next point; what ran is judged (the rest is "not judged"), the
    JUnit file says the run was interrupted, and the exit status is 130 or 143."""
    from hub.run.simulation import Simulation

    scratch.sweep()   # what a hub killed before its clean-up left in the temporary folder
    try:
        scenario = load_scenario(args.scenario, overrides(args))
    except ScenarioError as exc:
        # CI reads the XML: a scenario that does not load is an error there too, not a missing report.
        if args.junit:
            from hub.run.junit import write_junit

            write_junit(args.junit, Path(args.scenario).stem, [], 0.0, timestamp=datetime.now().replace(microsecond=0),
                        hostname=socket.gethostname(), properties=[("scenario", str(args.scenario))], error=str(exc))
        raise
    if not scenario.expect and scenario.exercise is None:
        raise UsageError(f"{args.scenario} has no `expect:` entries and no `exercise:` to judge")
    if args.out is not None:
        _check_replay(args, args.out)
    bus, pacer = _bus(args, scenario), _pacer(args, scenario)
    verdicts = _Verdicts(args, scenario)
    try:
        with Simulation(scenario, out=args.out, bus=bus, replay=args.replay,
                        pacer=pacer, signals=True, on_emergency=verdicts.emergency, every_source=False,
                        **_checkpointing(args, scenario)) as sim:
            sim.run()
            outcomes = sim.check()
            summary = sim.summary()
            interruption = sim.interruption
    except PlanthubError as exc:
        # CI reads the XML, not the exit code alone: a run that failed, so nothing could be judged,
        # is an error there (a bad scenario was found before the run, on loading: written above).
        if args.junit and not isinstance(exc, ScenarioError):
            verdicts.junit([], error=str(exc))
        raise
    finally:
        if bus is not None:
            bus.close()
    interrupted = summary.ended.reason if interruption.interrupted and summary.ended is not None else None
    failed = verdicts.report(summary, outcomes, interrupted)
    return interruption.exit_status or (FAILED if failed else OK)   # 130 after a Ctrl-C, 143 after SIGTERM


class _Verdicts:
    """What `planthub test` prints and writes for one run: the summary's first line, a line per
    expectation, the tally, and the JUnit file — once, from the main thread at the run's end or
    from the helper thread that ends a run a signal found stuck (hub/run/interruption.py)."""

    def __init__(self, args, scenario):
        self.args = args
        self.scenario = scenario
        self.stamp = datetime.now().replace(microsecond=0)
        self.started = time.perf_counter()
        self.properties = [("scenario", str(args.scenario)), ("seed", str(scenario.run.seed)),
                           *(("set", item) for item in set_texts(args))]
        self.reported = False

    def report(self, summary, outcomes, interrupted: str | None) -> int:
        """Print and write the verdicts; the number of expectations that failed (the run's
        interruption counts as one)."""
        if self.reported:
            return 0
        self.reported = True
        seconds = time.perf_counter() - self.started
        print(f"planthub test {summary.scenario}  ({self.args.scenario}, {summary.sim_seconds:g} s simulated)")
        if summary.ended is not None:
            print(summary.ended.line())
        marks = {(True, True): "✓", (True, False): "✗", (False, False): "?"}
        for outcome in outcomes:
            print(f"  {marks[outcome.judged, outcome.passed]} {outcome.expectation.name} — {outcome.message}")
        failed = sum(o.judged and not o.passed for o in outcomes)
        unjudged = sum(not o.judged for o in outcomes)
        print(f"{len(outcomes) - failed - unjudged} passed, {failed} failed"
              + (f", {unjudged} not judged" if unjudged else ""))
        sys.stdout.flush()   # the emergency path ends the process with os._exit, which flushes nothing
        if self.args.junit:
            ended = [("ended", summary.ended.reason)] if summary.ended is not None else []
            exercise = summary.section("exercise")   # an exercise's score, for CI's dashboards
            ended += [("score", f"{exercise.score:g}"), ("passed", str(exercise.passed).lower())] if exercise else []
            self.junit(outcomes, seconds, ended=ended, output="\n".join(summary.lines(verbose=True)) + "\n",
                       interrupted=interrupted)
        return failed + (interrupted is not None)

    def junit(self, outcomes, seconds: float | None = None, *, ended=(), **details) -> None:
        from hub.run.junit import write_junit

        seconds = time.perf_counter() - self.started if seconds is None else seconds
        write_junit(self.args.junit, self.scenario.name, outcomes, seconds, timestamp=self.stamp,
                    hostname=socket.gethostname(), properties=self.properties + list(ended), **details)

    def emergency(self, sim, reason: str) -> None:
        """The run was stuck when a signal came (or a second one came): judged on what it reached."""
        summary = sim.summary()
        self.report(summary, sim.check(), summary.ended.reason if summary.ended is not None else reason)


def _checkpointing(args, scenario) -> dict:
    """Run's `resume` and `checkpoints` from --resume, --checkpoint-at and --checkpoint-every."""
    from hub.run import checkpoint

    rate = scenario.run.physics_rate
    step = scenario.run.substeps
    ticks = []
    for seconds in args.checkpoint_at:
        tick = round(seconds * rate)
        if tick % step or tick > scenario.run.end_tick:
            raise UsageError(f"--checkpoint-at {seconds:g}: checkpoints are taken at communication points, every "
                             f"{step / rate:g} s from 0 to the run's end at {scenario.run.end_tick / rate:g} s")
        ticks.append(tick)
    every = None
    if args.checkpoint_every is not None:
        every = round(args.checkpoint_every * rate)
        if every < step or every % step:
            raise UsageError(f"--checkpoint-every {args.checkpoint_every:g}: a whole number of communication "
                             f"steps ({step / rate:g} s) is needed")
    found = {"checkpoints": (tuple(ticks), every)}
    if args.resume is not None:
        found["resume"] = (checkpoint.read(args.resume), str(args.resume))
    return found


def _check_replay(args, out: Path) -> None:
    if args.replay and out.resolve() == args.replay.resolve():
        raise UsageError(f"--out {out} is the run being replayed; write the replay elsewhere")


def _bus(args, scenario):
    settings = bus_settings(args, scenario)
    if settings is None:
        return None
    from hub.bus.session import Bus  # Zenoh is loaded only for a run on the bus

    return Bus(settings)


def _view(args, scenario):
    """With --view: the run's view, to be started once the run is (RunView); None without --view."""
    if not getattr(args, "view", False):
        return None
    from hub.cli.run_view import RunView

    if not args.realtime:
        _log.warning("planthub run: note: --view without --realtime: the run goes as fast as it can, and its view "
                     "ends with it")
    return RunView(scenario.name, port=args.view_port)


def _start_view(view, run, bus) -> None:
    """The run started (its scene answered on the bus), then its view, once it serves the page; its
    address printed."""
    run.start()
    view.start(bus)
    url = view.wait()   # a PlanthubError ends the run before its first step; the run closes the view
    print(f"planthub run: the view of run {run.scenario.name!r} at {url}  (open it in a browser; pid {view.pid}, "
          "it ends with the run)", flush=True)


def _pacer(args, scenario):
    if not args.realtime:
        return None
    from hub.run.pacing import Pacer

    return Pacer(scenario.run.physics_rate, args.realtime)


class _Progress:
    """A one-line progress display on a terminal, redrawn at most twice a second: an observer.
    Drawn straight on stderr, not logged: it redraws one line in place and is no diagnostic."""

    def __init__(self, end: int):
        self.end = end
        self.shown = self.started = time.monotonic()

    def close(self, reason: str) -> None:
        """The line ends with the run."""

    def observe(self, tick: int, signals, events) -> None:
        end = self.end
        now = time.monotonic()
        if now - self.shown >= 0.5 or tick >= end:
            self.shown = now
            sys.stderr.write(f"\r  {100 * tick / end:5.1f} %  {now - self.started:6.1f} s wall")
            if tick >= end:
                sys.stderr.write("\n")
            sys.stderr.flush()
