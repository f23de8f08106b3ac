"""`planthub gateway opcua|modbus|s7|enip SCENARIO --object NAME`: a scenario's participant object served to a
PLC or SCADA client over OPC UA, Modbus TCP, S7 or EtherNet/IP (hub/gateway/), joined to the run as that participant.
A scenario launches it as `python: [hub, gateway, opcua, FILE, --object, NAME, …]` (`python -m hub gateway …`)."""
from __future__ import annotations

import argparse
import logging
import math
import os
import time
from pathlib import Path

from hub.core.errors import PlanthubError

_log = logging.getLogger(__name__)

# S7's own port is 102 and EtherNet/IP's 44818; the S7 default is above 1023, where no privilege is needed.
ENDPOINTS = {"opcua": "opc.tcp://127.0.0.1:4840/planthub", "modbus": "127.0.0.1:5020", "s7": "127.0.0.1:1102",
             "enip": "127.0.0.1:44818"}
JOIN_MARGIN = 1.0   # s of the hub's join wait left for the join itself, after the PLC set plc_ready
# The hub runs a copy of the scenario whose `control` has no `python:` line, so that it launches nothing.
EXAMPLE = ("planthub gateway opcua COPY.yaml --object control --endpoint "
           "opc.tcp://0.0.0.0:4840/planthub --connect tcp/127.0.0.1:7447")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from hub.bus.participant import add_options
    from hub.cli.options import add_set

    parser.add_argument("protocol", choices=sorted(ENDPOINTS),
                        help="opcua (a server at opc.tcp://…), modbus (TCP), s7 (S7 over ISO-on-TCP) or enip "
                             "(EtherNet/IP, Logix tags)")
    parser.add_argument("scenario", type=Path, help="the run's scenario: its participant object gives the tags")
    parser.add_argument("--object", required=True, metavar="NAME", help="the participant object the gateway serves")
    parser.add_argument("--endpoint", metavar="ADDRESS",
                        help="where the server listens (default: " + ", ".join(f"{k} {v}" for k, v in ENDPOINTS.items())
                             + ")")
    parser.add_argument("--tags", type=Path, metavar="FILE.yaml", help="tag map overrides (`tags: {SLOT: {...}}`)")
    parser.add_argument("--export-tags", type=Path, metavar="FILE.csv",
                        help="write the tag map as a table for a PLC's tag editor and exit")
    parser.add_argument("--export-tia", type=Path, metavar="FILE.csv",
                        help="write the S7 tags (I, Q, M) as a TIA Portal PLC tag table and exit")
    parser.add_argument("--sync", choices=["lockstep", "live"], default="lockstep",
                        help="lockstep: hold the plant at every scan until the PLC answers (deterministic), and "
                             "a PLC's poll of cycle between two scans until the next begins; "
                             "live: never hold (run the plant with --realtime)")
    parser.add_argument("--scan", type=float, metavar="S",
                        help="lockstep: plant time between two scans, a whole number of communication steps "
                             "(default: every step)")
    parser.add_argument("--plc-timeout", type=float, default=0.5, metavar="S",
                        help="lockstep: wall-clock s the PLC has to answer a scan (less than the run's bus lease)")
    parser.add_argument("--ready-timeout", type=float, metavar="S",
                        help="lockstep: s to wait for the PLC to set plc_ready before joining the plant (default: "
                             "what is left of the hub's join wait when the hub launched it, else 30)")
    parser.add_argument("--user", metavar="NAME",
                        help="opcua: only this user may connect; the password is taken from PLANTHUB_OPCUA_PASSWORD")
    parser.add_argument("--certificate", type=Path, metavar="CERT",
                        help="opcua: the server's application certificate (PEM or DER, its application URI in "
                             "subjectAltName); with --private-key the endpoint offers Basic256Sha256 Sign and "
                             "SignAndEncrypt only")
    parser.add_argument("--private-key", type=Path, metavar="KEY", help="opcua: the certificate's RSA key (PEM or DER)")
    parser.add_argument("--trust", type=Path, action="append", default=[], metavar="CLIENT_CERT",
                        help="opcua: admit only clients presenting this certificate (repeatable, or a folder of "
                             "them); without it any client with a valid certificate")
    add_set(parser)
    add_options(parser)


def run(args) -> int:
    from hub.bus.participant import check_options, serve
    from hub.cli.options import overrides
    from hub.gateway.image import ProcessImage
    from hub.gateway.participant import Gateway
    from hub.gateway.server_thread import ServerThread
    from hub.gateway.tags import tag_map
    from hub.scenario.checker import load_scenario

    parser = args.command_parser
    scenario = load_scenario(args.scenario, overrides(args))
    tags = tag_map(scenario, args.object, args.tags)
    if args.export_tags or args.export_tia:
        for path, text in ((args.export_tags, tags.csv()), (args.export_tia, tags.tia_csv())):
            if path:
                path.write_text(text)
                print(f"{text.count(chr(10)) - 1} tags of {args.object!r} written to {path}")
        return 0
    args.run = args.run or scenario.name
    args.name = args.name or args.object
    args = check_options(parser, args)
    step = scenario.run.substeps / scenario.run.physics_rate
    if args.scan is not None and (args.scan <= 0 or abs(args.scan / step - round(args.scan / step)) > 1e-9):
        parser.error(f"--scan {args.scan:g}: a whole number of the run's communication step ({step:g} s)")
    if args.sync == "lockstep" and not 0 < args.plc_timeout < args.lease:
        parser.error(f"--plc-timeout {args.plc_timeout:g}: above 0 and below the lease (--lease {args.lease:g} s), "
                     f"or the hub takes the waiting gateway for frozen")
    user = None
    if args.user:
        password = os.environ.get("PLANTHUB_OPCUA_PASSWORD")
        if args.protocol != "opcua" or not password:
            parser.error("--user: only for opcua, with the password in PLANTHUB_OPCUA_PASSWORD")
        user = (args.user, password)
    certificates = _certificates(parser, args)
    image = ProcessImage(tags, lockstep=args.sync == "lockstep")
    endpoint = args.endpoint or ENDPOINTS[args.protocol]
    protocol = _server(args.protocol, image, endpoint, user, certificates)
    ready_timeout = _ready_timeout(args)
    with ServerThread(protocol, f"{args.protocol} server at {endpoint}") as server:
        gateway = Gateway(tags, server, mode=args.sync, scan=args.scan, plc_timeout=args.plc_timeout,
                          ready_timeout=ready_timeout)
        _log.info(f"gateway {args.object!r}: {len(tags.tags)} tags at {endpoint} ({args.sync})")
        try:
            gateway.wait_for_plc()
        except PlanthubError as exc:
            ready = tags.by_slot["plc_ready"]
            where = {"opcua": ready.node_id, "modbus": f"coil {ready.address}", "s7": ready.s7_address,
                     "enip": "controller tag plc_ready"}[args.protocol]
            _log.error(f"planthub gateway {args.object!r}: {exc} (plc_ready is {where} of the {args.protocol} "
                       f"server at {endpoint}); the PLC sets it once it runs, then the gateway joins the plant")
            return 1
        try:
            status = serve(gateway, args=args)
        finally:
            image.release()   # a read the PLC has held for a next scan is answered now
        if image.refused:
            _log.warning(f"gateway {args.object!r}: {image.refused} requests refused (each logged above)")
        return status


def _server(protocol: str, image, endpoint: str, user, certificates):
    """The protocol's server of the process image (each protocol's library stays in its own file)."""
    if protocol == "opcua":
        from hub.gateway.opcua import OpcUaServer
        return OpcUaServer(image, endpoint, user, certificates)
    if protocol == "modbus":
        from hub.gateway.modbus import ModbusServer
        return ModbusServer(image, endpoint)
    if protocol == "s7":
        from hub.gateway.s7 import S7Server
        return S7Server(image, endpoint)
    from hub.gateway.enip import EnipServer
    return EnipServer(image, endpoint)


def _ready_timeout(args) -> float:
    """How long the gateway waits for plc_ready: inside the hub's join wait when the hub launched it
    (PLANTHUB_JOIN_DEADLINE), so that the gateway, not the hub, says what is missing."""
    deadline = os.environ.get("PLANTHUB_JOIN_DEADLINE")
    left = None
    if deadline:
        try:
            left = float(deadline) - time.time() - JOIN_MARGIN
        except ValueError:
            left = math.nan
        if not math.isfinite(left):
            raise PlanthubError(f"the environment's PLANTHUB_JOIN_DEADLINE={deadline!r} is not a time (seconds since "
                                f"the epoch, as the hub that launches a gateway sets it)")
    if args.ready_timeout is None:
        return max(left, 0.1) if left is not None else 30.0
    if left is not None and args.ready_timeout > left and args.sync == "lockstep":
        _log.warning(f"gateway {args.object!r}: --ready-timeout {args.ready_timeout:g} s is longer than the "
                     f"{left + JOIN_MARGIN:.3g} s left of the hub's join wait: the hub gives up first; "
                     f"raise the object's join_timeout")
    return args.ready_timeout


def _certificates(parser, args):
    """The files of --certificate, --private-key and --trust read and checked (None: no security asked for)."""
    from hub.cli.exits import UsageError
    from hub.gateway.certificates import CertificateError, load_certificates

    if not (args.certificate or args.private_key or args.trust):
        return None
    if args.protocol != "opcua":
        parser.error("--certificate, --private-key, --trust: only for opcua (Modbus TCP has no security of its own)")
    if not (args.certificate and args.private_key):
        parser.error("--certificate and --private-key go together (--trust needs both)")
    try:
        return load_certificates(args.certificate, args.private_key, args.trust)
    except CertificateError as exc:
        raise UsageError(str(exc)) from exc
