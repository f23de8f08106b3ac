"""`planthub view`: a browser's window on a plant — join a running one over the bus, or play a recorded run back from its folder — and serve the page."""
from __future__ import annotations

import argparse
import asyncio
import importlib.util
import logging
import signal
from pathlib import Path

from hub.cli.exits import UsageError
from hub.core.errors import PlanthubError

_log = logging.getLogger("planthub.view")


def add_command(sub, parents=(), formatter=argparse.HelpFormatter, epilog: str = ""):
    """The `view` subcommand; returns its handler."""
    from hub.bus.participant import add_tls_options

    view = sub.add_parser(
        "view", parents=parents, formatter_class=formatter,
        help="watch and operate a running plant in the browser (3D scene, operator panel, figures), "
             "or play a recorded run back",
        description="Join a running plant over the bus as a live participant and serve its view to the browser:\n"
                    "the plant in 3D with its bottles moving, an operator panel (stop and start belts, force\n"
                    "sensors and switches, pause and step the run), the plant's figures and event log. Prints\n"
                    "the address to open. The run must be on the bus: `planthub run SCENARIO --listen ENDPOINT`.\n\n"
                    "Given a run folder instead (what `planthub run --record-bodies --out DIR` wrote), play that\n"
                    "run back on the same page: play, pause, speed, a time slider, its events, figures and\n"
                    "recorded slots; nothing to operate.",
        epilog="example:\n  planthub view bottling_plant --connect tcp/127.0.0.1:7447 --open\n"
               "      (beside `planthub run scenarios/bottling_plant.yaml --realtime --listen tcp/127.0.0.1:7447`)\n"
               "  planthub view runs/bottling_plant --open\n"
               "      (after `planthub run scenarios/bottling_plant.yaml --record-bodies`)\n\n"
               + epilog)
    view.add_argument("run", metavar="RUN|RUN_DIR",
                      help="the run's name (its scenario's name), as `planthub run` printed it; or a recorded "
                           "run's folder, to play it back")
    view.add_argument("--connect", action="append", metavar="ENDPOINT",
                      help="the hub's endpoint (its --listen), e.g. tcp/127.0.0.1:7447; repeatable (a running "
                           "plant only)")
    view.add_argument("--mode", default="peer", choices=["peer", "client"],
                      help="peer: connect to the hub itself; client: through a Zenoh router (or a router hub)")
    view.add_argument("--port", type=port_number, default=8765, help="the web port (default 8765; 0: any free one)")
    view.add_argument("--host", default="127.0.0.1",
                      help="the address to serve on (default 127.0.0.1: this machine only; the view has no login, "
                           "whoever reaches it can command the plant)")
    view.add_argument("--open", action="store_true", help="open the page in the default browser")
    view.add_argument("--name", metavar="NAME",
                      help="this view's name on the bus, logged as the sender of its commands (default view-<random>)")
    view.add_argument("--no-control", action="store_true",
                      help="only watch: the page's operator panel is disabled and no command is sent")
    view.add_argument("--role", choices=["instructor", "trainee"],
                      help="instructor: the page also shows the faults and injects them; trainee: the plant and the "
                           "exercise only (default: instructor when the run has no access control and the view "
                           "serves this machine only, or its certificate is in run.bus.access.instructor)")
    view.add_argument("--timeout", type=float, default=30.0, metavar="S",
                      help="s to wait for the hub to answer (default 30)")
    view.add_argument("--bundle", type=Path, metavar="DIR",
                      help="the built front-end (default: build/view/, made by `make view-assets`)")
    add_tls_options(view)
    view.set_defaults(command_parser=view)
    return lambda args: _view(view, args)


def _play(args, folder: Path) -> int:
    """Play the recorded run in `folder` back in the browser, until SIGINT or SIGTERM."""
    given = [f"--{name.replace('_', '-')}" for name, default in _LIVE_ONLY.items() if getattr(args, name) != default]
    if given:
        raise UsageError(f"{', '.join(given)}: for joining a running plant; {folder} is a recorded run, played "
                         "back from its files")
    if not (folder / "bodies.arrows").is_file():
        from hub.view.bodies_file import BodyRecording

        try:
            BodyRecording(folder)
        except PlanthubError as exc:   # its own message, which says how to record one: but a usage error
            raise UsageError(str(exc)) from None
    if importlib.util.find_spec("aiohttp") is None:
        raise UsageError("planthub view needs aiohttp: pip install -r requirements.txt")

    from hub.view.http import is_loopback
    from hub.view.run_folder import RecordedRun

    recorded = RecordedRun(folder)   # a broken file: PlanthubError, exit 1
    for note in recorded.notes:
        _log.warning("planthub view: note: %s", note)
    if not is_loopback(args.host):
        _log.warning("planthub view: warning: serving on %s, beyond this machine: whoever reaches that address "
                     "can watch the recorded run", args.host)

    def announce(url: str) -> None:
        print(f"planthub view: recorded run {recorded.run!r} ({folder}, {recorded.start:g} to {recorded.end:g} s) "
              f"at {url}  (open it in a browser; Ctrl-C ends the view)", flush=True)

    signal.signal(signal.SIGTERM, _terminated)
    return asyncio.run(_serve_recording(recorded, args, announce))


async def _serve_recording(recorded, args, announce) -> int:
    from hub.view.http import BUNDLE, serve_page, signal_stop
    from hub.view.playback import Playback

    opened = None
    if args.open:
        import webbrowser

        opened = webbrowser.open
    with signal_stop(asyncio.get_running_loop()) as stop:
        return await serve_page(Playback(recorded), stop, host=args.host, port=args.port,
                                bundle=args.bundle or BUNDLE, announce=announce, opened=opened)


def _terminated(signum, frame):
    raise SystemExit(128 + signum)


def port_number(text: str) -> int:
    """An argparse type: a TCP port, 0 for any free one."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"a port is from 0 to 65535, got {port}")
    return port


#: options that only joining a running plant takes, and their defaults (the --tls-* ones may come from
#: the environment, so they are not checked)
_LIVE_ONLY = {"mode": "peer", "name": None, "no_control": False, "timeout": 30.0, "role": None}


def _view(parser, args) -> int:
    from hub.bus.participant import tls_settings
    from hub.bus.wire import WireError, check_run_name

    folder = Path(args.run)
    if args.connect is None:
        if folder.is_dir():
            return _play(args, folder)
        if "/" in args.run or folder.exists():
            raise UsageError(f"{args.run}: no such run folder (give the folder `planthub run --record-bodies "
                             "--out DIR` wrote, or join a running plant: `planthub view RUN --connect ENDPOINT`)")
        raise UsageError(f"{args.run}: no such run folder, and no --connect: join a running plant with "
                         f"`planthub view {args.run} --connect ENDPOINT` (the hub's --listen), or play a recorded "
                         "run with `planthub view RUN_DIR`")
    if folder.is_dir() or "/" in args.run:
        raise UsageError(f"{args.run} names a folder, and --connect joins a running plant by its run's name "
                         "(`planthub view bottling_plant --connect tcp/127.0.0.1:7447`); to play the recorded run "
                         f"back, leave out --connect: `planthub view {args.run}`")
    try:
        check_run_name(args.run)
        if args.name:
            check_run_name(args.name)
    except WireError as exc:
        raise UsageError(str(exc)) from None
    if not args.timeout > 0:
        parser.error(f"--timeout needs a positive number of seconds, got {args.timeout:g}")
    tls = tls_settings(parser, args)
    if importlib.util.find_spec("aiohttp") is None:   # said here, not as a traceback in the middle of joining
        raise UsageError("planthub view needs aiohttp: pip install -r requirements.txt")

    from hub.view.http import BUNDLE, is_loopback
    from hub.view.relay import Relay
    from hub.view.server import serve

    role, role_reason = args.role or "instructor", "it was started with --role trainee"
    if args.role is None and not is_loopback(args.host) and tls is None:
        # Beyond this machine without a certificate to decide it, the page is a trainee's unless asked.
        role, role_reason = "trainee", (f"it serves {args.host}, beyond this machine, without a certificate: "
                                        "--role instructor to show the faults there")
    if not is_loopback(args.host):
        _log.warning("planthub view: warning: serving on %s, beyond this machine: the view has no login, so whoever "
                     "reaches that address can watch the plant and command it (--no-control: watch only)", args.host)

    def announce(url: str) -> None:
        print(f"planthub view: run {args.run!r} at {url}  (open it in a browser; Ctrl-C ends the view)", flush=True)

    opened = None
    if args.open:
        import webbrowser

        opened = webbrowser.open
    signal.signal(signal.SIGTERM, _terminated)   # until the view's loop takes the signals over
    relay = Relay(args.run, args.connect, mode=args.mode, tls=tls, name=args.name)   # a BusError: exit 1
    try:
        return asyncio.run(serve(relay, host=args.host, port=args.port, bundle=args.bundle or BUNDLE,
                                 control=not args.no_control, reason="it was started with --no-control",
                                 timeout=args.timeout, announce=announce, opened=opened, role=role,
                                 role_reason=role_reason))
    finally:
        relay.close()
