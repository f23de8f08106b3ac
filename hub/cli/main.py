"""Command line: `python -m hub run|validate|describe`."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import yaml

from hub.cli.bus import add_commands as add_bus_commands, add_run_options, bus_settings
from hub.core.errors import PlanthubError, Problem, ScenarioError
from hub.core.registry import UnknownModule, default_registry
from hub.scenario.checker import Scenario, load_scenario


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="planthub", description="Co-simulation hub for automation plants.")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run a scenario headless and record it")
    run.add_argument("scenario", type=Path)
    run.add_argument("--out", type=Path, help="folder for recording.csv and events.csv (default: runs/<name>)")
    _add_set(run)
    add_run_options(run)

    check = sub.add_parser("validate", help="check a scenario without running it")
    check.add_argument("scenario", type=Path)
    _add_set(check)

    test = sub.add_parser("test", help="run a scenario and judge its expectations (exit 1 if one fails)")
    test.add_argument("scenario", type=Path)
    test.add_argument("--junit", type=Path, metavar="FILE", help="also write the outcomes as JUnit XML")
    test.add_argument("--out", type=Path, help="also write recording.csv and events.csv here")
    _add_set(test)

    describe = sub.add_parser("describe", help="list a module's parameters and slots (no name: list modules)")
    describe.add_argument("module", nargs="?")

    check_fmu = sub.add_parser("check-fmu", help="check an FMU before a run: version, slots, validation")
    check_fmu.add_argument("fmu", type=Path)
    check_fmu.add_argument("--like", type=Path, metavar="REFERENCE.fmu",
                           help="also check it can replace this FMU (same inputs and outputs)")

    report = sub.add_parser("report", help="run a set of scenarios and write a markdown report with plots")
    report.add_argument("name", choices=["paper"], help="paper: the paper's three plausibility tests")
    report.add_argument("--out", type=Path, help="folder for report.md, its plots and runs (default: runs/report_<name>)")
    report.add_argument("--no-plots", action="store_true", help="write the numbers only (no matplotlib needed)")

    bus_commands = add_bus_commands(sub)

    args = parser.parse_args(argv)
    try:
        commands = {"run": _run, "validate": _validate, "describe": _describe, "check-fmu": _check_fmu, "test": _test,
                    "report": _report, **bus_commands}
        return commands[args.command](args)
    except ScenarioError as exc:
        print(f"planthub: {exc}", file=sys.stderr)
        return 2
    except PlanthubError as exc:
        print(f"planthub: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:   # output piped into `head` and the like
        sys.stderr.close()
        return 0


def _report(args) -> int:
    from importlib import import_module

    from hub.reports import REPORTS

    module, _, function = REPORTS[args.name].partition(":")
    out = args.out or Path("runs") / f"report_{args.name}"
    started = time.monotonic()
    path = getattr(import_module(module), function)(
        out, plots=not args.no_plots,
        progress=lambda step: print(f"  {time.monotonic() - started:6.1f} s  {step}", file=sys.stderr))
    print(f"planthub report {args.name}: {path}")
    return 0


def _add_set(parser) -> None:
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scenario value, e.g. --set run.physics_rate=1000 (value read as YAML)")


def _overrides(args) -> dict:
    out = {}
    for item in args.overrides:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ScenarioError([Problem("--set", None, "", f"expected KEY=VALUE, got {item!r}")])
        out[key] = yaml.safe_load(value)
    return out


def _load(args) -> Scenario:
    return load_scenario(args.scenario, _overrides(args))


def _validate(args) -> int:
    scenario = _load(args)
    run = scenario.run
    print(f"{args.scenario}: ok — {len(scenario.objects)} objects, {len(scenario.flows)} flows, "
          f"{len(scenario.record)} recorded slots, {run.end_tick / run.physics_rate:g} s at {run.physics_rate} Hz")
    return 0


def _run(args) -> int:
    from hub.bus.session import Bus
    from hub.run.assembly import Run
    from hub.run.pacing import Pacer

    scenario = _load(args)
    out = args.out or Path("runs") / (scenario.name + ("_replay" if args.replay else ""))
    if args.replay and out.resolve() == args.replay.resolve():
        raise PlanthubError(f"--out {out} is the run being replayed; write the replay elsewhere")
    if args.realtime is not None and not args.realtime > 0:
        raise PlanthubError(f"--realtime needs a positive factor, got {args.realtime:g}")
    settings = bus_settings(args, scenario)
    bus = Bus(settings) if settings is not None else None
    notice = lambda text: print(f"planthub: {text}", file=sys.stderr)
    pacer = Pacer(scenario.run.physics_rate, args.realtime) if args.realtime else None
    progress = [_Progress(scenario.run.end_tick)] if sys.stderr.isatty() else []
    try:
        with Run(scenario, out=out, bus=bus, replay=args.replay, pacer=pacer, observers=progress, log=notice) as run:
            result = run.run()
            run.close("the run reached its end" if not result.stopped_by else result.stopped_by)
            summary = run.summary()
            link = run.link
    finally:
        if bus is not None:
            bus.close()
    print("\n".join(summary.lines()))
    if result.stopped_by:
        print(f"  {'ended' if result.ended else 'stopped':<12} {result.stopped_by}")
    if pacer is not None:
        print(f"  pacing       {pacer.summary()}")
    if link is not None:
        count = len(link.lockstep.peers)
        print(f"  bus          {count} participant{'s' if count != 1 else ''}, "
              f"{link.dataplane.samples} data-plane samples")
    if (out / "commands.csv").is_file():
        print(f"  commands     {out / 'commands.csv'}")
    return 0


class _Progress:
    """A one-line progress display on a terminal, redrawn at most twice a second: an observer."""

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
            print(f"\r  {100 * tick / end:5.1f} %  {now - self.started:6.1f} s wall", end="", file=sys.stderr)
            if tick >= end:
                print(file=sys.stderr)


def _describe(args) -> int:
    registry = default_registry()
    if not args.module:
        for name in registry.names():
            doc = (registry.get(name).__doc__ or "").strip().splitlines()
            print(f"{name:<16} {doc[0] if doc else ''}")
        return 0
    try:
        module = registry.get(args.module)
    except UnknownModule as exc:
        print(f"planthub: {exc}", file=sys.stderr)
        return 2
    print(f"{args.module}: {(sys.modules[module.__module__].__doc__ or module.__doc__ or '').strip()}")
    print("\nparameters:")
    props = module.PARAMETERS.get("properties", {})
    required = set(module.PARAMETERS.get("required", []))
    for name, schema in props.items():
        default = "required" if name in required else f"default {schema['default']!r}" if "default" in schema else "optional"
        print(f"  {name:<14} {default:<18} {schema.get('description', '')}")
    slots = [(comp, slot) for comp, group in module.slots(module.with_defaults({})).items() for slot in group]
    if slots:
        print("\nslots:")
    for comp, slot in slots:
        print(f"  {comp + '.' + slot.name:<22} {slot.type.value:<7} {slot.direction.value:<7} {slot.doc}")
    return 0


def _check_fmu(args) -> int:
    from hub.logic.fmi import FmuError, compare, inspect_fmu, validate

    try:
        fmu = inspect_fmu(args.fmu)
        reference = inspect_fmu(args.like) if args.like else None
    except FmuError as exc:
        print(f"planthub: {exc}", file=sys.stderr)
        return 1
    print(f"{args.fmu}: FMI {fmu.fmi_version} co-simulation, model {fmu.model_name!r}")
    for causality, label in (("input", "target slots"), ("output", "source slots"), ("parameter", "parameters")):
        names = ", ".join(f"{v.name} ({v.type.value})" for v in fmu.of(causality)) or "none"
        print(f"  {label:<13} {names}")
    problems = [f"validation: {p}" for p in validate(args.fmu)]
    if reference is not None:
        problems += compare(fmu, reference)
    for problem in problems:
        print(f"  ✗ {problem}")
    if not problems:
        fits = f"; fits in place of {args.like}" if reference is not None else ""
        print(f"  ✓ passes fmpy's validation{fits}")
    return 1 if problems else 0


def _test(args) -> int:
    from hub.run.junit import write_junit
    from hub.run.simulation import Simulation

    started = time.perf_counter()
    with Simulation(args.scenario, _overrides(args), out=args.out) as sim:
        if not sim.scenario.expect:
            print(f"planthub: {args.scenario} has no `expect:` entries to judge", file=sys.stderr)
            return 2
        sim.run()
        outcomes = sim.check()
    seconds = time.perf_counter() - started
    print(f"planthub test {sim.scenario.name}  ({args.scenario}, {sim.time:g} s simulated)")
    for outcome in outcomes:
        print(f"  {'✓' if outcome.passed else '✗'} {outcome.expectation.name} — {outcome.message}")
    failed = sum(not o.passed for o in outcomes)
    print(f"{len(outcomes) - failed} passed, {failed} failed")
    if args.junit:
        write_junit(args.junit, sim.scenario.name, outcomes, seconds)
    return 1 if failed else 0
