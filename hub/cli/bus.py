"""The command line's bus side: the hub's bus settings from the run options, `serve-fmu` and `send`."""
from __future__ import annotations

import argparse
import time
import uuid
from dataclasses import replace
from pathlib import Path

from hub.bus.settings import BusSettings
from hub.core.errors import PlanthubError
from hub.scenario.checker import Scenario


def add_commands(sub, parents=(), formatter=argparse.HelpFormatter, epilog: str = "") -> dict:
    """The bus subcommands (each with `parents`' options and `epilog` after its example); returns
    name → handler."""
    from hub.bus.participant import add_options, add_tls_options
    from hub.core.logic_spec import INTERFACES, SOLVERS

    serve = sub.add_parser(
        "serve-fmu", parents=parents, formatter_class=formatter,
        help="serve an FMU to a running plant over the bus (a lockstep participant)",
        description="Serve an FMU to a running plant over the bus: a lockstep participant for an `fmu` object "
                    "with `runs: bus` and `launch: false` (or one the hub launches).",
        epilog="example:\n  planthub serve-fmu build/fmus/belt_drive-fmi2.fmu --run belt_ramp_fmu --name drive "
               "\\\n      --connect tcp/192.168.1.5:7447 --event run --map speed=belt_speed\n\n" + epilog)
    serve.add_argument("fmu", type=Path, help="the FMU file (FMI 2.0 or 3.0, co-simulation or model exchange)")
    serve.add_argument("--event", action="append", default=[], metavar="VARIABLE",
                       help="a Boolean variable that is a void slot (the object's `events`)")
    serve.add_argument("--map", action="append", default=[], metavar="VARIABLE=SLOT",
                       help="a variable's slot name (the object's `map`)")
    serve.add_argument("--interface", choices=INTERFACES,
                       help="the interface to run (the object's `interface`; default: co-simulation where offered)")
    serve.add_argument("--solver", choices=SOLVERS, help="model exchange: the solver (the object's `solver`; "
                                                         "default cvode)")
    serve.add_argument("--max-step", type=float, metavar="S", help="model exchange: the solver's longest step, s")
    serve.add_argument("--tolerance", type=float, help="model exchange: cvode's relative tolerance (default 1e-6)")
    add_options(serve)
    serve.set_defaults(command_parser=serve)

    send = sub.add_parser(
        "send", parents=parents, formatter_class=formatter,
        help="send an operator command to a running plant",
        description="Send an operator command to a running plant and wait for the hub's answer (the tick it "
                    "applied it at).",
        epilog="example:\n  planthub send belt_ramp_participant force belt.drive.speed 0.2 --connect tcp/127.0.0.1:7447 "
               "--by alice\n\n" + epilog)
    send.add_argument("run", help="the run's name (the scenario's name)")
    send.add_argument("op", choices=["set", "force", "release", "stop", "pause", "resume", "step", "pace",
                                     "checkpoint", "rewind", "fault", "repair"],
                      help="set: the slot takes the value at the next point; force: at every point until release; "
                           "stop: the run ends after the next point; pause, resume; step N: N points while "
                           "paused; pace F: F × real time (a --realtime run); checkpoint: the run saved at the "
                           "next point into its folder's checkpoints/TICK.ckpt; rewind TICK: the run back to its "
                           "checkpoint at or before tick TICK, and on from there; fault PART MAP, repair PART "
                           "'{name: N}': an instructor's, sent on the instructor's key (schemas/README.md "
                           "\"Faults and exercises\")")
    send.add_argument("slot", nargs="?", default="",
                      help="object.component.slot (for set, force, release); for step, pace and rewind: the "
                           "number")
    send.add_argument("value", nargs="?", help="the value, read as YAML (0.2, true, [0, 0, 1]); for set and force")
    send.add_argument("--connect", action="append", required=True, metavar="ENDPOINT", help="the hub's endpoint")
    send.add_argument("--by", default="", help="who sends it (logged with the command)")
    send.add_argument("--timeout", type=float, default=5.0, help="s to wait for the hub's answer")
    add_tls_options(send)
    send.set_defaults(command_parser=send)
    return {"serve-fmu": lambda args: _serve_fmu(serve, args), "send": lambda args: _send(send, args)}


def bus_settings(args, scenario: Scenario) -> BusSettings | None:
    """The hub's bus settings: the scenario's `run.bus` with the command line's overrides, or None."""
    settings = scenario.run.bus
    flags = args.bus or args.listen or args.connect or args.mode or getattr(args, "view", False)   # --view: --bus
    if settings is None and not flags:
        return None
    settings = settings or BusSettings()
    if args.listen:
        settings = replace(settings, listen=tuple(args.listen))
    if args.connect:
        settings = replace(settings, connect=tuple(args.connect))
    if args.mode:
        settings = replace(settings, mode=args.mode)
    return settings


def _serve_fmu(parser, args) -> int:
    from hub.bus.participant import check_options, serve
    from hub.logic.fmi_me import Integration
    from hub.logic.served import FmuParticipant

    check_options(parser, args)
    rename = {}
    for item in args.map:
        variable, sep, slot = item.partition("=")
        if not sep:
            parser.error(f"--map expects VARIABLE=SLOT, got {item!r}")
        rename[variable] = slot
    if args.solver == "euler" and args.max_step is None:
        parser.error("--solver euler needs --max-step")
    given = {"solver": args.solver, "max_step": args.max_step, "tolerance": args.tolerance}
    integration = Integration(args.interface, **{k: v for k, v in given.items() if v is not None})
    logic = FmuParticipant(str(args.fmu), args.event, rename, instance=args.name,
                           integration=integration)   # an FmuError: exit 1
    return serve(logic, args=args)


def _send(parser, args) -> int:
    import yaml

    from hub.bus import wire
    from hub.bus.commands import command_message
    from hub.bus.participant import tls_settings
    from hub.bus.session import Bus, Inbox

    tls = tls_settings(parser, args)
    value = yaml.safe_load(args.value) if args.value is not None else None
    if args.op in ("step", "pace", "rewind"):   # `planthub send RUN step 3`: the number stands where a slot would
        value, args.slot = (yaml.safe_load(args.slot) if args.slot else None), ""
    ident = uuid.uuid4().hex
    inbox = Inbox()
    with Bus(BusSettings(connect=tuple(args.connect), tls=tls), listen=False) as bus:
        bus.watch_tokens(wire.hub_token(args.run), lambda m: inbox.put(("hub", m.alive)))
        bus.subscribe(wire.control_key(args.run, "command", "result"), lambda m: inbox.put(("result", m.payload)))
        bus.subscribe(wire.instructor_key(args.run, "command", "result"), lambda m: inbox.put(("result", m.payload)))
        # A fault is an instructor's: on the instructor's key (under access control, a certificate in access.instructor).
        key = wire.instructor_key(args.run, "command") if args.op in ("fault", "repair") else \
            wire.control_key(args.run, "command")
        deadline = time.monotonic() + args.timeout
        sent = False
        while time.monotonic() < deadline:
            item = inbox.get(deadline - time.monotonic())
            if item is None:
                break
            kind, payload = item
            if kind == "hub" and payload and not sent:
                bus.put(key, command_message(args.op, args.slot, value, args.by, ident), wire.MSGPACK)
                sent = True
            elif kind == "result":
                result = wire.unpack(payload)
                if result.get("id") != ident:
                    continue
                if not result.get("ok"):
                    raise PlanthubError(f"the hub refused the command: {result.get('error')}")
                print(f"{args.op} {args.slot} applied at tick {result['tick']}".replace("  ", " "))
                return 0
    what = "no answer from its hub" if sent else "no hub seen"
    raise PlanthubError(f"run {args.run!r}: {what} within {args.timeout:g} s ({', '.join(args.connect)})")
