"""The scene and every body on the bus, read by a subscriber written from schemas/ alone: plain
zenoh, msgpack, numpy and jsonschema, no planthub code — against `planthub run` of the bottling
plant in another process (issue 13)."""
from __future__ import annotations

import json
import socket
import subprocess
import sys
import time

import jsonschema
import msgpack
import numpy as np
import pytest
import zenoh

from .helpers import ROOT

SCHEMA = json.loads((ROOT / "schemas" / "scene.schema.json").read_text())
RUN = "bottling_plant"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def subschema(name: str) -> dict:
    return {**SCHEMA, "$ref": f"#/$defs/{name}"}


@pytest.fixture
def plant(tmp_path):
    """The bottling plant running in its own process, listening on a loopback port."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    proc = subprocess.Popen([sys.executable, "-m", "hub", "run", str(ROOT / "scenarios" / "bottling_plant.yaml"),
                             "--listen", endpoint, "--out", str(tmp_path / "run"), "-q"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        yield endpoint, proc
    finally:
        proc.kill()
        proc.communicate(timeout=10)


def session(endpoint: str, deadline: float):
    """A Zenoh client of the hub, once the hub listens (it starts in another process)."""
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    while True:
        try:
            return zenoh.open(config)
        except zenoh.ZError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def ask_scene(z, deadline: float) -> dict:
    while time.monotonic() < deadline:
        for reply in z.get(f"plant/{RUN}/@cosim/scene", timeout=2.0):
            if reply.ok is not None:
                return json.loads(reply.ok.payload.to_bytes())
        time.sleep(0.2)
    raise AssertionError("no answer to the scene query")


def test_a_subscriber_from_the_schemas_gets_the_scene_and_every_bottle(plant):
    endpoint, proc = plant
    deadline = time.monotonic() + 120
    messages = []
    with session(endpoint, deadline) as z:
        scene = ask_scene(z, deadline)
        jsonschema.Draft202012Validator(subschema("scene")).validate(scene)
        kinds = {item["kind"] for item in scene["items"]}
        assert {"belt", "support", "box", "part", "trigger", "arm", "moving"} <= kinds
        modules = {name: o["module"] for name, o in scene["objects"].items()}
        sources = {name for name, m in modules.items() if m == "source"}
        released = {b["row"] for b in scene["bodies"] if b["object"] in sources}
        assert sources and released, "the bottling plant's sources hold bottles to release"
        arm = next(i for i in scene["items"] if i["kind"] == "arm")
        assert arm["urdf"].endswith(".urdf") and len(arm["joints"]) == 7

        sub = z.declare_subscriber(f"plant/{RUN}/@cosim/bodies", lambda s: messages.append(s.payload.to_bytes()))
        seen_released = set()
        while time.monotonic() < deadline and len(seen_released) < 3:
            time.sleep(0.2)
            for payload in messages[-3:]:
                m = msgpack.unpackb(payload, raw=False)
                seen_released |= set(np.frombuffer(m["rows"], "<u2").tolist()) & released
            assert proc.poll() is None, proc.communicate()[1]
        sub.undeclare()
    assert len(seen_released) >= 3, "released bottles are on the bus"
    ticks = []
    validator = jsonschema.Draft202012Validator(subschema("bodies_message"))
    for payload in messages:
        m = msgpack.unpackb(payload, raw=False)
        validator.validate(m)
        rows = np.frombuffer(m["rows"], "<u2")
        poses = np.frombuffer(m["poses"], "<f4").reshape(-1, 7)
        assert len(poses) == len(rows) == len(m["destinations"]) == len(m["flags"])
        assert np.isfinite(poses).all()
        assert np.allclose(np.linalg.norm(poses[:, 3:], axis=1), 1.0, atol=1e-3), "unit quaternions"
        # In play means on stage: parked bodies wait far below (and are not in the message).
        assert (poses[:, 2] > -1.0).all()
        assert len(m["parts"]) == sum(i["kind"] == "part" for i in scene["items"])
        assert len(m["triggers"]) == sum(i["kind"] == "trigger" for i in scene["items"])
        assert len(np.frombuffer(m["arms"], "<f4")) == 7
        ticks.append(m["tick"])
    assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
    # At most every 0.05 s of plant time, as the schema says (none was asked for).
    assert min(np.diff(ticks)) >= round(0.05 * scene["physics_rate"])
    # Bottles move between messages.
    first, last = (msgpack.unpackb(messages[i], raw=False) for i in (0, -1))
    assert first["poses"] != last["poses"]
