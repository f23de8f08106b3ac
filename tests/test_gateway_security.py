"""The OPC UA gateway's certificate security: a real asyncua server with --certificate and --private-key
offers Basic256Sha256 Sign and SignAndEncrypt only; a real asyncua client with a trusted certificate
reads and writes tags over SignAndEncrypt, one without security or with an untrusted certificate is
refused; each unusable certificate, key or trusted certificate is named with its file and cause."""
import asyncio
import csv
import dataclasses

import pytest
from asyncua import Client, ua
from asyncua.crypto import cert_gen
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding
from cryptography.x509.oid import ExtendedKeyUsageOID

from hub.core.errors import PlanthubError
from hub.gateway.certificates import load_certificates
from hub.gateway.image import ProcessImage
from hub.gateway.opcua import OpcUaServer
from hub.gateway.server_thread import ServerThread
from hub.gateway.tags import tag_map
from hub.scenario.checker import load_scenario

from .gateway_support import free_port, run_beside_client
from .helpers import planthub
from .test_gateway import belt_scenario

SERVER_URI, PLC_URI = "urn:planthub:test:gateway", "urn:planthub:test:plc"
SECURE = ua.MessageSecurityMode.SignAndEncrypt


def make_certificate(folder, name, uri, use, der=False):
    """A self-signed application certificate for `uri` and its key (PEM): (certificate, key) paths."""
    key = cert_gen.generate_private_key()
    names = [x509.UniformResourceIdentifier(uri)] if uri else []
    cert = cert_gen.generate_self_signed_app_certificate(key, name, {}, names + [x509.DNSName("localhost")],
                                                         extended=[use])
    cert_path = folder / (f"{name}.der" if der else f"{name}.pem")
    cert_path.write_bytes(cert.public_bytes(Encoding.DER if der else Encoding.PEM))
    key_path = folder / f"{name}-key.pem"
    key_path.write_bytes(cert_gen.dump_private_key_as_pem(key))
    return cert_path, key_path


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    """The gateway's certificate (DER) and key, a trusted PLC's and a stranger's (both PEM)."""
    folder = tmp_path_factory.mktemp("pki")
    return {"server": make_certificate(folder, "gateway", SERVER_URI, ExtendedKeyUsageOID.SERVER_AUTH, der=True),
            "plc": make_certificate(folder, "plc", PLC_URI, ExtendedKeyUsageOID.CLIENT_AUTH),
            "stranger": make_certificate(folder, "stranger", PLC_URI, ExtendedKeyUsageOID.CLIENT_AUTH)}


@pytest.fixture
def secured(tmp_path, pki):
    """A real server of the belt's tags with the gateway's certificate, trusting the PLC's; (image, endpoint)."""
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc", None)
    image = ProcessImage(tags)
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"
    certificates = load_certificates(*pki["server"], [pki["plc"][0]])
    with ServerThread(OpcUaServer(image, endpoint, ("operator", "s3cret"), certificates), "opcua") as thread:
        thread.publish({"who": "B001"})
        image.put({"who": "B001"})
        yield image, endpoint


async def session(endpoint, who=None, mode=SECURE, user=("operator", "s3cret"), ignore_endpoints=False):
    """A real asyncua client: with `who`'s certificate (None: no security) connects, reads barrier.who,
    writes belt.speed; 'connected: …' or the name of what refused it."""
    client = Client(endpoint, timeout=5)
    client.application_uri = PLC_URI
    if user:
        client.set_user(user[0])
        client.set_password(user[1])
    try:
        if who:
            await client.set_security(SecurityPolicyBasic256Sha256, str(who[0]), str(who[1]), mode=mode)
        await client.connect()
    except ua.UaStatusCodeError as exc:
        return type(exc).__name__
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}"
    try:
        ns = await client.get_namespace_index("urn:planthub:belt_plc")
        who_read = await client.get_node(ua.NodeId("barrier.who", ns)).read_value()
        await client.get_node(ua.NodeId("belt.speed", ns)).write_value(ua.Variant(0.5, ua.VariantType.Double))
        return f"connected: {who_read}"
    finally:
        await client.disconnect()


def test_a_trusted_plc_reads_and_writes_over_sign_and_encrypt_and_the_endpoint_offers_nothing_unsecured(
        secured, pki):
    image, endpoint = secured
    assert asyncio.run(session(endpoint, pki["plc"])) == "connected: B001"
    assert image.outputs()["speed"] == 0.5
    assert asyncio.run(session(endpoint, pki["plc"], mode=ua.MessageSecurityMode.Sign)) == "connected: B001"

    async def offered():
        client = Client(endpoint, timeout=5)
        return {(e.SecurityPolicyUri.rsplit("#", 1)[1], e.SecurityMode.name) for e in await client.connect_and_get_server_endpoints()}

    assert asyncio.run(offered()) == {("Basic256Sha256", "Sign"), ("Basic256Sha256", "SignAndEncrypt")}


def test_a_client_without_security_an_untrusted_certificate_or_a_wrong_password_is_refused(secured, pki, monkeypatch):
    image, endpoint = secured
    assert asyncio.run(session(endpoint)) == \
           "UaError: No matching endpoints: 1, http://opcfoundation.org/UA/SecurityPolicy#None"
    assert asyncio.run(session(endpoint, pki["stranger"])) == "BadCertificateUntrusted"
    assert asyncio.run(session(endpoint, pki["plc"], user=("operator", "wrong"))) == "BadUserAccessDenied"
    # A client that ignores the endpoint list and opens a session on an unsecured channel anyway
    # (asyncua's own server would let it in): the gateway refuses it.
    monkeypatch.setattr(Client, "find_endpoint", staticmethod(lambda endpoints, mode, policy: endpoints[0]))
    assert asyncio.run(session(endpoint)) == "BadUserAccessDenied"
    assert image.outputs()["speed"] == 0.0   # none of them wrote


def test_trust_is_judged_on_the_channels_certificate_not_on_the_one_a_client_names(secured, pki, monkeypatch):
    """A stranger on a channel of its own certificate that names no certificate in CreateSession
    (asyncua's validator then checks nothing), or names the trusted PLC's public one: refused."""
    from asyncua.client.ua_client import UaClient

    image, endpoint = secured
    original = UaClient.create_session
    for named in (None, pki["plc"][0].read_bytes()):
        async def create_session(self, parameters, named=named):
            if named is not None:
                named = x509.load_pem_x509_certificate(named).public_bytes(Encoding.DER)
            return await original(self, dataclasses.replace(parameters, ClientCertificate=named))
        monkeypatch.setattr(UaClient, "create_session", create_session)
        assert asyncio.run(session(endpoint, pki["stranger"])) == "BadUserAccessDenied"
        assert asyncio.run(session(endpoint, pki["plc"])) == "connected: B001"   # the PLC still gets in
    assert image.outputs()["speed"] == 0.5   # only the PLC wrote


def test_without_trust_any_client_with_a_valid_certificate_is_admitted(tmp_path, pki):
    tags = tag_map(load_scenario(belt_scenario(tmp_path)), "plc", None)
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"
    with ServerThread(OpcUaServer(ProcessImage(tags), endpoint, None, load_certificates(*pki["server"])), "opcua"):
        assert asyncio.run(session(endpoint, pki["stranger"], user=None)) == "connected: "
        assert asyncio.run(session(endpoint, user=None)).startswith("UaError: No matching endpoints")


# ---- unusable files -------------------------------------------------------------------------

def test_each_unusable_file_is_named_with_its_cause_all_at_once(tmp_path, pki):
    cert, key = pki["server"]
    other_key = pki["plc"][1]
    no_uri, no_uri_key = make_certificate(tmp_path, "nouri", None, ExtendedKeyUsageOID.SERVER_AUTH)
    garbage = tmp_path / "garbage.pem"
    garbage.write_text("not a certificate\n")
    empty = tmp_path / "empty"
    empty.mkdir()
    cases = [
        ((tmp_path / "missing.der", key, []), f"--certificate {tmp_path / 'missing.der'}: no such file"),
        ((tmp_path, key, []), f"--certificate {tmp_path}: cannot be read (Is a directory)"),
        ((garbage, key, []), f"--certificate {garbage}: not an X.509 certificate (PEM or DER)"),
        ((cert, tmp_path / "missing.pem", []), f"--private-key {tmp_path / 'missing.pem'}: no such file"),
        ((cert, garbage, []), f"--private-key {garbage}: not a private key (PEM or DER)"),
        ((cert, other_key, []), f"--private-key {other_key}: not the key of the certificate {cert} "
                                f"(their public keys differ)"),
        ((no_uri, no_uri_key, []), f"--certificate {no_uri}: no application URI (a URI in its subjectAltName)"),
        ((cert, key, [tmp_path / "plc.der"]), f"--trust {tmp_path / 'plc.der'}: no such file"),
        ((cert, key, [empty]), f"--trust {empty}: a folder without certificates"),
        ((cert, key, [garbage]), f"--trust {garbage}: not an X.509 certificate (PEM or DER)"),
    ]
    for args, message in cases:
        with pytest.raises(PlanthubError) as caught:
            load_certificates(*args)
        assert message in str(caught.value), (args, str(caught.value))
    with pytest.raises(PlanthubError) as caught:   # every problem, at once
        load_certificates(garbage, tmp_path / "missing.pem", [empty])
    assert str(caught.value).count("\n  - ") == 3


def test_a_trust_folder_admits_every_certificate_in_it(tmp_path, pki):
    folder = tmp_path / "trusted"
    folder.mkdir()
    (folder / "plc.pem").write_bytes(pki["plc"][0].read_bytes())
    (folder / "README.txt").write_text("not a certificate, and not read")
    assert len(load_certificates(*pki["server"], [folder]).trusted) == 1


def test_the_command_line_names_a_bad_certificate_and_refuses_security_options_it_cannot_use(tmp_path, capsys, pki):
    path = belt_scenario(tmp_path)
    cert, key = pki["server"]
    code, _, err = planthub(capsys, "gateway", "opcua", path, "--object", "plc",
                            "--certificate", tmp_path / "nothere.der", "--private-key", key)
    assert code == 2 and f"--certificate {tmp_path / 'nothere.der'}: no such file" in err
    code, _, err = planthub(capsys, "gateway", "opcua", path, "--object", "plc", "--certificate", cert)
    assert code == 2 and "--certificate and --private-key go together" in err
    code, _, err = planthub(capsys, "gateway", "modbus", path, "--object", "plc", "--certificate", cert,
                            "--private-key", key)
    assert code == 2 and "only for opcua (Modbus TCP has no security of its own)" in err


@pytest.mark.slow
def test_planthub_gateway_with_a_certificate_serves_the_plant_to_a_trusted_plc(tmp_path, pki):
    """`planthub gateway opcua … --certificate --private-key --trust`, launched by the hub (live mode),
    and a PLC process with its trusted certificate setting the belt running over SignAndEncrypt."""
    endpoint = f"opc.tcp://127.0.0.1:{free_port()}/planthub"
    (cert, key), plc_cert = pki["server"], pki["plc"]
    path = belt_scenario(tmp_path, duration=3.0, launch=[
        "hub", "gateway", "opcua", "belt_plc.yaml", "--object", "plc", "--endpoint", endpoint, "--sync", "live",
        "--certificate", str(cert), "--private-key", str(key), "--trust", str(plc_cert[0])])
    writer = ("import asyncio, time\n"
              "from asyncua import Client, ua\n"
              "from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256\n"
              "async def main():\n"
              "    deadline = time.monotonic() + 60\n"
              "    while True:\n"
              "        try:\n"
              "            c = Client(%r, timeout=5); c.application_uri = %r\n"
              "            await c.set_security(SecurityPolicyBasic256Sha256, %r, %r)\n"
              "            await c.connect(); break\n"
              "        except Exception:\n"
              "            assert time.monotonic() < deadline; await asyncio.sleep(0.1)\n"
              "    ns = await c.get_namespace_index('urn:planthub:belt_plc')\n"
              "    await c.get_node(ua.NodeId('belt.speed', ns)).write_value(ua.Variant(0.5, ua.VariantType.Double))\n"
              "    await c.get_node(ua.NodeId('belt.run', ns)).write_value(ua.Variant(True, ua.VariantType.Boolean))\n"
              "    await c.disconnect()\n"
              "asyncio.run(main())\n") % (endpoint, PLC_URI, str(plc_cert[0]), str(plc_cert[1]))
    proc, client = run_beside_client(path, tmp_path / "run", writer)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert client.returncode == 0
    with open(tmp_path / "run" / "recording.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["belt.drive.velocity"]) == pytest.approx(0.5)   # the trusted PLC's set-point
