"""The bottling plant routed by an external PLC client process through `planthub gateway`, over OPC
UA, Modbus TCP and EtherNet/IP, in lockstep: every bottle reaches its lane, and scanning at every step the
run is bit for bit the run of the routing participant it stands in for (modules/plant_control.py,
in the hub's process); scanning every 0.1 s (a PLC's usual scan) it still routes every bottle right."""
import pytest

from .gateway_support import bottling_via_gateway
from .helpers import run_scenario
from .test_bottling_plant import LANES, SCENARIO, deliveries

pytestmark = pytest.mark.slow   # each test routes the bottling plant through a gateway and a PLC process

DURATION = 56.0   # s: by then every lane has had a bottle (tests/test_bottling_plant.py)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("participant")
    run_scenario(SCENARIO, out, {"run.duration": DURATION, "objects.control.runs": "hub"})
    return out


def gateway_run(tmp_path, protocol, *gateway_args):
    out, said, _ = bottling_via_gateway(tmp_path, protocol, DURATION, *gateway_args)
    return out, said


def every_bottle_in_its_lane(out):
    from hub.scenario.checker import load_scenario
    taken, misrouted = deliveries(load_scenario(SCENARIO), out)
    assert not misrouted, f"misrouted (bottle, destination, sink): {misrouted}"
    assert {sink for sink, _ in taken} == set(LANES) and len(taken) >= 8
    return taken


@pytest.mark.parametrize("protocol", ["opcua", "modbus", "enip"])
def test_a_plc_over_the_gateway_routes_every_bottle_as_the_participant_does_bit_for_bit(tmp_path, protocol, reference):
    out, plc_out = gateway_run(tmp_path, protocol)
    every_bottle_in_its_lane(out)
    scans = int(plc_out.split()[1])
    assert scans == round(DURATION / 0.02)      # a scan at every communication step, each answered
    assert (out / "recording.csv").read_bytes() == (reference / "recording.csv").read_bytes()
    assert (out / "events.csv").read_bytes() == (reference / "events.csv").read_bytes()


def test_a_plc_scanning_every_100_ms_over_modbus_routes_every_bottle(tmp_path, reference):
    out, plc_out = gateway_run(tmp_path, "modbus", "--scan", "0.1")
    taken = every_bottle_in_its_lane(out)
    assert int(plc_out.split()[1]) == round(DURATION / 0.1)
    assert taken == deliveries_of(reference)   # the same bottles to the same lanes, later by a scan at most


def deliveries_of(out):
    from hub.scenario.checker import load_scenario
    return deliveries(load_scenario(SCENARIO), out)[0]
