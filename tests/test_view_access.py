"""A view under access control: its certificate decides whether its panel may command and whether it is
an instructor's. A watch-only certificate gets the page with the panel off and the reason, and its
commands are refused by the view; a controller's is let through, on a trainee's page; an instructor's
(run.bus.access.instructor) commands over the instructor's key and sees the faults (real hub over mutual
TLS, real `planthub view`, real WebSocket)."""
from __future__ import annotations

import asyncio
import json

import pytest
import trustme

from hub.bus.session import free_loopback_endpoint

from .helpers import ROOT
from .view_support import planthub, talk, wait_for_url

SCENARIO = ROOT / "scenarios" / "source_sink.yaml"


@pytest.fixture(scope="module")
def certs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("certs")
    ca = trustme.CA()
    ca.cert_pem.write_to_path(folder / "ca.pem")
    for name, identities in (("hub", ("127.0.0.1", "localhost")), ("plc", ("plc.example",)),
                             ("trainee", ("trainee.example",)), ("teacher", ("teacher.example",))):
        cert = ca.issue_cert(*identities, common_name=name)
        cert.private_key_pem.write_to_path(folder / f"{name}.key")
        cert.cert_chain_pems[0].write_to_path(folder / f"{name}.pem")
    return folder


async def hello(ws) -> dict:
    while True:
        frame = await asyncio.wait_for(ws.receive(), 30)
        if frame.type.name == "TEXT" and json.loads(frame.data).get("type") == "hello":
            return json.loads(frame.data)


@pytest.mark.parametrize("who, control", [("trainee", False), ("plc", True), ("teacher", True)])
def test_a_watch_only_certificate_sees_the_panel_off_with_the_reason(certs, tmp_path, who, control):
    endpoint = free_loopback_endpoint().replace("tcp/", "tls/")
    bus = {"listen": [endpoint], "access": {"control": ["plc"], "watch": ["trainee"], "instructor": ["teacher"]},
           "tls": {"ca": str(certs / "ca.pem"), "certificate": str(certs / "hub.pem"), "key": str(certs / "hub.key"),
                   "mutual": True}}
    with planthub(tmp_path, "hub", "run", SCENARIO, "--realtime", 1, "--out", tmp_path / "run",
                  "--set", "run.duration=120", "--set", f"run.bus={json.dumps(bus)}"), \
            planthub(tmp_path, "view", "view", "source_sink", "--connect", endpoint, "--port", 0,
                     "--tls-ca", certs / "ca.pem", "--tls-cert", certs / f"{who}.pem",
                     "--tls-key", certs / f"{who}.key") as started:
        url = wait_for_url(started, 60)

        async def conversation(ws):
            greeting = await hello(ws)
            await ws.send_str(json.dumps({"type": "command", "op": "force", "slot": "belt.drive.run", "value": False}))
            faults = False
            while True:
                frame = await asyncio.wait_for(ws.receive(), 30)
                faults |= frame.type.name == "TEXT" and json.loads(frame.data).get("type") == "faults"
                if frame.type.name == "TEXT" and json.loads(frame.data).get("type") in ("result", "error"):
                    answer = json.loads(frame.data)
                    break
            while who == "teacher" and not faults:   # the board comes within a second or so
                frame = await asyncio.wait_for(ws.receive(), 15)
                faults = frame.type.name == "TEXT" and json.loads(frame.data).get("type") == "faults"
            return greeting, answer, faults

        greeting, answer, faults = talk(url, conversation)
    assert greeting["control"] is control
    if who == "teacher":
        assert greeting["role"] == "instructor" and faults, "an instructor's view gets the board of faults"
    else:
        assert greeting["role"] == "trainee" and not faults
        assert greeting["role_reason"] == (f"this view's certificate names {who!r}, not an instructor "
                                           "(run.bus.access.instructor: teacher, hub)")
    if control:
        assert greeting["reason"] == "" and answer.get("ok") is True, answer
    else:
        why = ("this view's certificate names 'trainee', which may only watch this run "
               "(run.bus.access.control: plc, hub)")
        assert greeting["reason"] == why
        assert answer.get("ok") is not True and why in json.dumps(answer), answer
