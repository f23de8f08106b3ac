"""Command line: `planthub run|validate|test|campaign|describe|check-fmu|report|plot|compare|serve-fmu|send|view|gateway` (also `python -m hub`)."""
from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from pathlib import Path

from hub.cli.bus import add_commands as add_bus_commands
from hub.cli.campaign import add_command as add_campaign_command
from hub.cli.compare import add_command as add_compare_command
from hub.cli.describe import describe
from hub.cli.exits import BAD_SCENARIO, FAILED, INTERRUPTED, OK, TABLE, USAGE, UsageError
from hub.cli.gateway import EXAMPLE as add_gateway_example
from hub.cli.gateway import add_arguments as add_gateway_arguments
from hub.cli.gateway import run as run_gateway
from hub.cli.logs import diagnostics
from hub.cli.options import add_run_arguments, add_set, overrides, verbosity, verbosity_parent
from hub.cli.plot import add_command as add_plot_command
from hub.cli.run_view import add_arguments as add_view_arguments
from hub.cli.running import run_command, test_command
from hub.cli.view import add_command as add_view_command
from hub.core.errors import PlanthubError, ScenarioError

_log = logging.getLogger(__name__)
_FORMAT = argparse.RawDescriptionHelpFormatter   # the examples and the exit-code table keep their lines

DESCRIPTION = """\
planthub: a co-simulation hub for automation plants. A scenario (YAML) names the plant's
objects — belts, bottles, sensors, actuators, sources, sinks, logic in FMUs or participant
processes — and the flows between their slots; the hub steps the physics and the logic
together and writes what happened."""

NOTES = """\
examples:
  planthub run scenarios/stop_at_barrier.yaml
  planthub test scenarios/switch_logic.yaml --junit reports/switch.xml
  planthub describe source

Every command takes -v (more detail; the run summary's table lists the logic's events too)
and -q (only errors and what the command prints). Zenoh's own log goes to stderr with -vv
(info) or -vvv (debug), or as RUST_LOG says in Zenoh's filter syntax (RUST_LOG=zenoh=debug);
a participant the hub launches logs into its captured output.

""" + TABLE


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("planthub")   # the installed distribution's, from pyproject.toml
    except PackageNotFoundError:
        return "(not installed: run it from an installed environment for its version)"


def parser() -> tuple[argparse.ArgumentParser, dict]:
    """The command line's parser and its handlers, name → function(args) → exit code."""
    top = argparse.ArgumentParser(prog="planthub", description=DESCRIPTION, epilog=NOTES, formatter_class=_FORMAT)
    top.add_argument("--version", action="version", version=f"planthub {_version()}")
    sub = top.add_subparsers(dest="command", required=True, metavar="COMMAND",
                             title="commands (planthub COMMAND --help: its options and an example)")
    loud = [verbosity_parent()]

    def command(name: str, help: str, example: str, description: str = ""):
        made = sub.add_parser(name, help=help, description=description or help[0].upper() + help[1:] + ".",
                              epilog=f"example:\n  {example}\n\n{TABLE}", parents=loud, formatter_class=_FORMAT)
        made.set_defaults(command_parser=made)
        return made

    run = command("run", "run a scenario headless: print its summary, write its recording and event log",
                  "planthub run scenarios/stop_at_barrier.yaml --set run.duration=3 --out runs/short",
                  "Run a scenario headless. Prints the run summary — how the run ended, the plant's\n"
                  "figures, time, events — and writes recording.csv, events.csv and summary.json.")
    add_run_arguments(run, "folder for recording.csv, events.csv and summary.json (default: runs/<name>)")
    add_view_arguments(run)

    check = command("validate", "check a scenario without running it",
                    "planthub validate my_plant.yaml --set run.physics_rate=1000")
    check.add_argument("scenario", type=Path, help="the scenario file (YAML)")
    add_set(check)

    test = command("test", "run a scenario and judge its expectations (`expect:`); exit 1 if one fails",
                   "planthub test scenarios/switch_logic.yaml --junit reports/switch.xml \\\n"
                   "      --set 'objects.sw.logic={file: my_switch_logic.fmu}'",
                   "Run a scenario and judge its expectations (`expect:`): a line per expectation, then\n"
                   "N passed, M failed. Takes every option of `run`; writes files only with --out.")
    add_run_arguments(test, "also write recording.csv, events.csv and summary.json here (default: nothing written)")
    test.add_argument("--junit", type=Path, metavar="FILE",
                      help="also write the outcomes as JUnit XML (a case per expectation; seed, --set and the "
                           "summary inside)")

    describe_ = command("describe", "list the modules, or one module's parameters (form, example) and slots",
                        "planthub describe source")
    describe_.add_argument("module", nargs="?", help="a module's name (conveyor, source, …); without: list them all")
    describe_.add_argument("--reference", type=Path, metavar="FILE",
                           help="write every module's reference (parameters, slots, docstring) as markdown to FILE: "
                                "modules/README.md is written so")

    check_fmu = command("check-fmu", "check an FMU before a run: version, slots, fmpy's validation",
                        "planthub check-fmu my_switch.fmu --like build/fmus/track_switch-fmi2.fmu")
    check_fmu.add_argument("fmu", type=Path, help="the FMU file to check")
    check_fmu.add_argument("--like", type=Path, metavar="REFERENCE.fmu",
                           help="also check it can replace this FMU (same inputs and outputs)")

    report = command("report", "run a set of scenarios and write a markdown report with plots",
                     "planthub report paper --out runs/report_paper")
    report.add_argument("name", choices=["paper"], help="paper: the paper's three plausibility tests")
    report.add_argument("--out", type=Path, metavar="DIR",
                        help="folder for report.md, its plots and runs (default: runs/report_<name>)")
    report.add_argument("--no-plots", action="store_true", help="write the numbers only (no matplotlib needed)")

    gateway = command("gateway", "serve a participant object to a PLC or SCADA client over OPC UA or Modbus TCP",
                      add_gateway_example,
                      "Serve a scenario's participant object to a PLC or SCADA client: an OPC UA or Modbus TCP\n"
                      "server whose tags (generated from the object's slots, see --export-tags) are the plant's\n"
                      "sensors and the actuators' commands; it joins the run as that participant.")
    add_gateway_arguments(gateway)

    handlers = {"run": run_command, "gateway": run_gateway, "validate": _validate, "test": test_command,
                "describe": _describe, "check-fmu": _check_fmu, "report": _report,
                **add_bus_commands(sub, parents=loud, formatter=_FORMAT, epilog=TABLE),
                "view": add_view_command(sub, parents=loud, formatter=_FORMAT, epilog=TABLE),
                "campaign": add_campaign_command(sub, parents=loud, formatter=_FORMAT, epilog=TABLE),
                "plot": add_plot_command(sub, parents=loud, formatter=_FORMAT, epilog=TABLE),
                "compare": add_compare_command(sub, parents=loud, formatter=_FORMAT, epilog=TABLE)}
    return top, handlers


def main(argv=None) -> int:
    top, handlers = parser()
    args, unknown = top.parse_known_args(argv)   # a usage error exits here, with code 2 (USAGE)
    if unknown:   # told by the subcommand, with its usage, not by `planthub` with the list of commands
        getattr(args, "command_parser", top).error(f"unrecognized arguments: {' '.join(unknown)}")
    with diagnostics(verbosity(args)):
        try:
            return handlers[args.command](args)
        except UsageError as exc:
            _log.error(str(exc))
            return USAGE
        except ScenarioError as exc:
            _log.error(str(exc))
            return BAD_SCENARIO
        except PlanthubError as exc:
            _log.error(str(exc))
            return FAILED
        except KeyboardInterrupt:
            _log.error("interrupted (Ctrl-C)")
            return INTERRUPTED
        except BrokenPipeError:   # output piped into `head` and the like: the reader has what it wanted
            # Python's own advice: point stdout at /dev/null, so the flush at exit does not fail again.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return OK


def _describe(args) -> int:
    if args.reference is None:
        return describe(args.module)
    if args.module:
        raise UsageError("--reference writes every module's reference: give no module name")
    from hub.cli.reference import write_reference
    from hub.core.registry import default_registry

    write_reference(default_registry(), args.reference)
    return 0


def _validate(args) -> int:
    from hub.scenario.checker import load_scenario

    scenario = load_scenario(args.scenario, overrides(args))
    run = scenario.run
    print(f"{args.scenario}: ok — {len(scenario.objects)} objects, {len(scenario.flows)} flows, "
          f"{len(scenario.record)} recorded slots, {run.end_tick / run.physics_rate:g} s at {run.physics_rate} Hz")
    for fault in scenario.faults:   # when each starts, a drawn time too (hub/scenario/faults.py)
        print(f"  fault     {fault.describe(run.physics_rate)}")
    if scenario.exercise is not None:
        goals = scenario.exercise.goals
        print(f"  exercise  {len(goals)} goal{'s' * (len(goals) != 1)} ({', '.join(g.name for g in goals)}), "
              f"passes at {scenario.exercise.passing:g} %")
    for obj in scenario.objects:   # what the run can live with, said before anyone runs it
        for module, params, where in ((obj.module, obj.params, obj.name), (obj.logic_module, obj.logic, f"{obj.name}.logic")):
            for place, note in (module.notes(params) if module is not None and params is not None else ()):
                _log.warning("planthub: warning: objects.%s: %s", ".".join((where, *map(str, place))), note)
    if run.bus is not None:
        from hub.bus.settings import exposure

        for warning in exposure(run.bus):   # said out loud before anyone runs it
            _log.warning("planthub: warning: %s", warning)
    return OK


def _report(args) -> int:
    from importlib import import_module

    from hub.reports import REPORTS

    module, _, function = REPORTS[args.name].partition(":")
    out = args.out or Path("runs") / f"report_{args.name}"
    started = time.monotonic()
    path = getattr(import_module(module), function)(
        out, plots=not args.no_plots,
        progress=lambda step: _log.info(f"{time.monotonic() - started:6.1f} s  {step}"))
    print(f"planthub report {args.name}: {path}")
    return OK


def _interfaces(fmu) -> str:
    """How the hub runs each interface the FMU offers, the one it runs unless told first."""
    said = {"co-simulation": "co-simulation" + (" with event mode (its events handled as they come)"
                                                if fmu.event_mode else ""),
            "model-exchange": "model exchange (integrated by planthub: `solver:` cvode or euler)"}
    first, *others = fmu.interfaces
    return said[first] + "".join(f"; also {said[k]} (`interface: {k}`)" for k in others)


def _check_fmu(args) -> int:
    """Blockers (it cannot load, has neither co-simulation nor model exchange, no binary for this platform, or
    cannot replace --like's FMU) → ✗ and exit 1; findings the hub can live with (fmpy's
    validation notes, variables without a slot) → ! warnings, exit 0."""
    from hub.logic.fmi import compare, inspect_fmu, validate
    from hub.logic.isolated import probe

    fmu = inspect_fmu(args.fmu)   # an FmuError (no such file, no FMU, no interface, no binary): exit 1
    reference = inspect_fmu(args.like) if args.like else None
    print(f"{args.fmu}: FMI {fmu.fmi_version} {_interfaces(fmu)}, model {fmu.model_name!r}")
    settable = [v for v in fmu.variables.values() if v.causality != "input" and v.settable() is None]
    for label, variables in (("target slots", fmu.of("input")), ("source slots", fmu.of("output")),
                             ("settable", settable)):
        print(f"  {label:<13} {', '.join(v.summary() for v in variables) or 'none'}")
    if fmu.of("input"):
        print("  (an input no flow feeds keeps its start value; `parameters:` sets inputs too)")
    warnings = [f"not mapped: {name}: {why}" for name, why in fmu.unmapped]
    warnings += [f"validation: {p}" for p in validate(args.fmu)]
    if not fmu.of("input") and not fmu.of("output"):
        warnings.append("no inputs or outputs: nothing a flow can connect")
    blockers = []
    failed = probe(fmu)
    if failed is not None:
        blockers.append(f"cannot load: {failed}")
    if reference is not None:
        blockers += compare(fmu, reference)
    for warning in warnings:
        print(f"  ! {warning}")
    for blocker in blockers:
        print(f"  ✗ {blocker}")
    if blockers:
        return FAILED
    fits = f"; fits in place of {args.like}" if reference is not None else ""
    if warnings:
        count = f"{len(warnings)} warning{'s' if len(warnings) > 1 else ''}"
        print(f"  ✓ usable, with {count} (above){fits}")
    else:
        print(f"  ✓ passes fmpy's validation{fits}")
    return OK
