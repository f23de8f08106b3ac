"""The bus: Zenoh sessions on loopback, messages, liveliness, clear errors."""
import re
import socket

import pytest

from hub.bus.session import Bus, BusError, Inbox, free_loopback_endpoint, local_endpoint
from hub.bus.settings import BusSettings


@pytest.fixture
def pair():
    """A listening session and one connected to it, both closed after the test."""
    with Bus(BusSettings()) as a:
        with Bus(BusSettings(connect=a.endpoints), listen=False) as b:
            yield a, b


def test_a_bus_listens_on_a_free_loopback_port_by_default():
    with Bus(BusSettings()) as bus:
        (endpoint,) = bus.endpoints
        assert re.fullmatch(r"tcp/127\.0\.0\.1:\d+", endpoint)
    assert bus.closed


def test_publish_subscribe_with_encoding_and_attachment(pair):
    a, b = pair
    inbox = Inbox()
    b.subscribe("demo/**", inbox.put)
    publisher = a.publisher("demo/x", "zenoh/bytes;planthub/real")
    assert wait_for(lambda: publisher.matching)
    publisher.put(b"\x01\x02", attachment=b"\x07")
    message = inbox.get(5)
    assert (message.key, message.payload, message.encoding, message.attachment) == \
        ("demo/x", b"\x01\x02", "zenoh/bytes;planthub/real", b"\x07")


def test_a_token_is_seen_coming_and_going(pair):
    a, b = pair
    inbox = Inbox()
    a.watch_tokens("demo/alive/*", inbox.put)
    token = b.declare_token("demo/alive/p1")
    seen = inbox.get(5)
    assert (seen.key, seen.alive) == ("demo/alive/p1", True)
    token.undeclare()
    gone = inbox.get(5)
    assert (gone.key, gone.alive) == ("demo/alive/p1", False)


def test_an_inbox_wait_has_a_timeout():
    assert Inbox().get(0.01) is None


def test_a_port_in_use_is_named():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        endpoint = f"tcp/127.0.0.1:{s.getsockname()[1]}"
        with pytest.raises(BusError) as info:
            Bus(BusSettings(listen=(endpoint,)))
    message = str(info.value)
    assert message.startswith(f"cannot open the bus (peer; listen on {endpoint}): ")
    assert "Address already in use" in message and ".rs:" not in message


def test_a_client_without_a_router_is_named():
    endpoint = free_loopback_endpoint()
    with pytest.raises(BusError, match=rf"cannot open the bus \(client; connect to {endpoint}\): "
                                       rf"Unable to connect to any of"):
        Bus(BusSettings(mode="client", connect=(endpoint,)))


def test_local_endpoint_for_a_wildcard_listener():
    assert local_endpoint("tcp/0.0.0.0:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/[::]:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/10.0.0.2:7447") == "tcp/10.0.0.2:7447"


def wait_for(condition, timeout=5.0):
    from hub.bus.session import wait_until

    return wait_until(condition, timeout)


def test_a_bad_bus_section_is_reported_with_the_scenario_problems(write_scenario):
    from hub.core.errors import ScenarioError
    from hub.scenario.checker import load_scenario

    path = write_scenario("""
        planthub: 1
        run: {bus: {mode: pear, lease: 0, listen: [7447], on_loss: retry}}
        objects:
          c: {module: constant, type: real, value: 1}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:2: run.bus.lease: 0 is less than or equal to the minimum of 0",
        f"{path}:2: run.bus.listen[0]: 7447 is not of type 'string'",
        f"{path}:2: run.bus.mode: 'pear' is not one of ['peer', 'client', 'router']",
        f"{path}:2: run.bus.on_loss: 'retry' is not one of ['stop', 'pause']"]


def test_the_bus_section_with_its_defaults(write_scenario):
    from hub.scenario.checker import load_scenario

    path = write_scenario("""
        planthub: 1
        run: {bus: {listen: [tcp/0.0.0.0:7447], on_loss: pause}}
        objects:
          c: {module: constant, type: real, value: 1}
        """)
    assert load_scenario(path).run.bus == BusSettings(listen=("tcp/0.0.0.0:7447",), on_loss="pause")
