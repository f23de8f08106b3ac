"""TLS on the bus: the certificates of `run.bus.tls`, their checks, and why a handshake was refused.

Zenoh itself reads the files (hub/bus/session.py puts their paths into its configuration). What Zenoh
does not do well is tell what is wrong: a file that is not a certificate comes back as "peer sent
no certificates", and a refused handshake only as a log line while the session waits on. So the
files are checked here first, and a connection that does not come up is tried once more with
Python's own TLS, whose error names the cause.
"""
from __future__ import annotations

import socket
import ssl
from dataclasses import dataclass
from pathlib import Path

SECURE = ("tls", "quic")   # the Zenoh link protocols that run over TLS


@dataclass(frozen=True)
class TlsSettings:
    """The `run.bus.tls` section (paths absolute), or a participant's `--tls-*` options."""

    ca: str | None = None            # PEM: the authority that signed the other side's certificate
    certificate: str | None = None   # PEM: this side's certificate (chain)
    key: str | None = None           # PEM: its private key, unencrypted
    mutual: bool = False             # listening: accept only peers that present a certificate signed
                                     # by `ca`; connecting: present `certificate` when asked
    verify_name: bool = True         # connecting: the certificate must name the endpoint's host


def secure(endpoint: str) -> bool:
    return endpoint.split("/", 1)[0] in SECURE


def problems(tls: TlsSettings | None, listen, connect, *, listening: bool,
             control: tuple[str, ...] | None = None) -> list[tuple[tuple, str]]:
    """Everything wrong with a session's TLS set-up, as (place, message): the place is a path under
    `run.bus` (("tls", "key"), ("listen", 0)); `listening`: the session listens on `listen` (a
    participant only connects); `control`: the common names of run.bus.access.control."""
    listen, connect = (list(listen) if listening else []), list(connect)
    found = []
    if control is not None and not (tls is not None and tls.mutual):
        found.append((("access",), "access control tells participants apart by their certificates: "
                                   "it needs run.bus.tls with mutual: true"))
    if tls is None:
        for group, endpoints in (("listen", listen), ("connect", connect)):
            for i, endpoint in enumerate(endpoints):
                if secure(endpoint):
                    need = "a certificate and its key" if group == "listen" else \
                        "the authority (ca) that signed the certificate of the other side"
                    found.append(((group, i), f"{endpoint} is a TLS endpoint: give the TLS settings with {need}"))
        return found
    if not tls.ca:
        found.append((("tls", "ca"), "missing: the certificate of the authority that signed the certificates "
                                     "(the hub's, and with mutual TLS the participants')"))
    for field in ("certificate", "key"):
        other = "key" if field == "certificate" else "certificate"
        if getattr(tls, other) and not getattr(tls, field):
            found.append((("tls", field), f"missing: the {other} needs its {field}"))
    for i, endpoint in enumerate(listen):
        if secure(endpoint) and not tls.certificate:
            found.append((("listen", i), f"listening on {endpoint} needs a certificate and its key"))
    if listening and not listen and tls.certificate:
        listen = ["tls/127.0.0.1:0"]   # what the hub listens on without listen endpoints (hub/bus/session.py)
    if (listen or connect) and not any(secure(e) for e in listen + connect):
        found.append((("tls",), f"no endpoint uses it ({', '.join(listen + connect)}): write tls/HOST:PORT"))
    found += [(("tls", field), message) for field, message in file_problems(tls)]
    return found


def file_problems(tls: TlsSettings) -> list[tuple[str, str]]:
    """(field, message) for each file that is missing or not what its field says it is."""
    found = []
    for field, marker, what in (("ca", "CERTIFICATE", "certificate"), ("certificate", "CERTIFICATE", "certificate"),
                                ("key", "PRIVATE KEY", "private key")):
        path = getattr(tls, field)
        if path is None:
            continue
        try:
            text = Path(path).read_text(errors="replace")
        except FileNotFoundError:
            found.append((field, f"no such file: {path}"))
            continue
        except OSError as exc:
            found.append((field, f"cannot read {path}: {exc.strerror or exc}"))
            continue
        if f"{marker}-----" not in text:
            found.append((field, f"{path} holds no PEM {what} (no '-----BEGIN {marker}-----' line)"))
        elif field == "key" and ("-----BEGIN ENCRYPTED PRIVATE KEY-----" in text or "Proc-Type: 4,ENCRYPTED" in text):
            found.append((field, f"{path} is encrypted: Zenoh reads keys without a passphrase "
                                 f"(decrypt it, e.g. `openssl pkey -in {Path(path).name} -out plain.key`)"))
    bad = {field for field, _ in found}
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    if tls.certificate and tls.key and not bad & {"certificate", "key"}:
        try:
            context.load_cert_chain(tls.certificate, tls.key)
        except ssl.SSLError as exc:
            if "KEY_VALUES_MISMATCH" in str(exc):
                found.append(("key", f"{tls.key} is not the key of the certificate {tls.certificate}"))
            else:
                found.append(("certificate", f"cannot use {tls.certificate} with {tls.key}: {exc.reason or exc}"))
    if tls.ca and "ca" not in bad:
        try:
            context.load_verify_locations(tls.ca)
        except ssl.SSLError as exc:
            found.append(("ca", f"cannot read the certificate in {tls.ca}: {exc.reason or exc}"))
    return found


def refused(endpoint: str, tls: TlsSettings, timeout: float = 2.0) -> str | None:
    """Why a TLS handshake with `endpoint` fails with these settings, or None when it succeeds or
    nothing answers there (yet): the question asked after a Zenoh connection did not come up."""
    proto, _, address = endpoint.partition("/")
    if proto != "tls" or not tls.ca:   # (no ca: reported by `problems`)
        return None
    host, _, port = address.split("#")[0].split("?")[0].rpartition(":")
    host = host.strip("[]")
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    context.check_hostname = tls.verify_name
    try:
        context.load_verify_locations(tls.ca)
        if tls.certificate and tls.key:
            context.load_cert_chain(tls.certificate, tls.key)
    except (OSError, ssl.SSLError):
        return None   # file problems are reported by `problems`
    try:
        with socket.create_connection((host, int(port)), timeout=timeout) as raw, \
                context.wrap_socket(raw, server_hostname=host) as link:
            # TLS 1.3: a listener that refuses our certificate says so after the handshake.
            link.settimeout(0.3)
            link.recv(1)
    except ssl.SSLCertVerificationError as exc:
        if "Hostname mismatch" in str(exc.verify_message):
            return (f"its certificate does not name {host} ({exc.verify_message}); connect by a name the "
                    f"certificate holds, or set verify_name: false")
        return f"its certificate is not signed by the authority in {tls.ca} ({exc.verify_message})"
    except ssl.SSLError as exc:
        reason = str(exc.reason or exc)
        if "CERTIFICATE_REQUIRED" in reason:
            return "it asks for a client certificate (mutual TLS) and none was given"
        if "UNKNOWN_CA" in reason or "BAD_CERTIFICATE" in reason or "CERTIFICATE_UNKNOWN" in reason:
            mine = f"our certificate {tls.certificate}" if tls.certificate else "our certificate"
            return f"it does not accept {mine}: not signed by an authority it trusts ({reason.lower()})"
        return f"the TLS handshake failed: {reason.lower()}"
    except (OSError, ValueError):
        return None   # nothing listens there (yet), or it does not speak first: not a TLS refusal
    return None


def environment(tls: TlsSettings | None, *, loopback: bool, own: tuple[str, str] | None = None) -> dict[str, str]:
    """What a participant the hub launches is told (PLANTHUB_TLS_*, read by hub/bus/participant.py):
    the authority, and a certificate with its key: `own` (certificate, key), the participant's own
    from the scenario, or else the hub's, which a process the hub started then presents as its own.
    `loopback`: it connects only to the hub's listeners, by 127.0.0.1, a name the hub's
    certificate need not hold (the signature is checked all the same)."""
    if tls is None:
        return {}
    env = {"PLANTHUB_TLS_CA": tls.ca or "",
           "PLANTHUB_TLS_VERIFY_NAME": "0" if loopback or not tls.verify_name else "1"}
    if own is not None:
        env.update(PLANTHUB_TLS_CERT=own[0], PLANTHUB_TLS_KEY=own[1])
    elif tls.certificate and tls.key:
        env.update(PLANTHUB_TLS_CERT=tls.certificate, PLANTHUB_TLS_KEY=tls.key)
    return env


#: The `tls` parameter of a logic object whose process the hub launches (modules participant, fmu):
#: the certificate that process presents on the bus instead of the hub's own.
LAUNCHED_SCHEMA = {
    "type": "object",
    "properties": {
        "certificate": {"type": "string", "x-path": True,
                        "description": "PEM: the participant's certificate, signed by run.bus.tls.ca"},
        "key": {"type": "string", "x-path": True, "description": "PEM: its private key, unencrypted"},
    },
    "required": ["certificate", "key"],
    "additionalProperties": False,
    "examples": [{"certificate": "certs/plc.pem", "key": "certs/plc.key"}],
    "description": "with a launched process: its own certificate on the bus (without: the hub's own, with a warning)",
}


def launched_problems(tls: dict, bus) -> list[tuple[tuple, str]]:
    """Everything wrong with a launched participant's own certificate (`tls`: the LAUNCHED_SCHEMA
    parameter, paths absolute) on the bus of its run (`bus`: hub.bus.settings.BusSettings or
    None), as (place within `tls`, message): the files, that the run's authority signed it, and
    under access control, that its common name may serve logic."""
    if bus is None or bus.tls is None:
        return [((), "the run's bus does not use TLS (no run.bus.tls), so a certificate of the participant's "
                     "own has no use: give run.bus.tls, or leave this out")]
    own = TlsSettings(certificate=tls["certificate"], key=tls["key"])
    found = [((field,), message) for field, message in file_problems(own)]
    if found:
        return found
    certificate = tls["certificate"]
    if bus.tls.ca and not file_problems(TlsSettings(ca=bus.tls.ca)) and not _signed_by(certificate, bus.tls.ca):
        found.append((("certificate",), f"{certificate} is not signed by the run's authority {bus.tls.ca} "
                                        f"(run.bus.tls.ca): the hub would refuse its handshake"))
    if bus.control is not None:
        name = common_name(certificate)
        if name is None:
            found.append((("certificate",), f"{certificate} has no common name, which access control "
                                            f"(run.bus.access) knows participants by"))
        elif name not in bus.control:
            listed = ", ".join(bus.control) or "none"
            found.append((("certificate",), f"{certificate} names {name!r} (its common name), which "
                                            f"run.bus.access.control does not list ({listed}): the participant "
                                            f"could not serve its logic; add {name!r} to control"))
    return found


def _signed_by(certificate: str, ca: str) -> bool:
    """Whether the authority (a PEM bundle) signed `certificate`, directly or through the
    intermediates that follow it in its own file."""
    from cryptography import x509

    try:
        chain = x509.load_pem_x509_certificates(Path(certificate).read_bytes())
        authorities = x509.load_pem_x509_certificates(Path(ca).read_bytes())
    except ValueError:
        return True   # what OpenSSL took but cryptography cannot read: left to the handshake to judge
    issuers = authorities + chain[1:]
    current = chain[0]
    for _ in range(len(chain)):
        parent = next((c for c in issuers if _issued(current, c)), None)
        if parent is None:
            return False
        if parent in authorities:
            return True
        current = parent
    return False


def _issued(child, parent) -> bool:
    from cryptography.exceptions import InvalidSignature

    try:
        child.verify_directly_issued_by(parent)
        return True
    except (ValueError, TypeError, InvalidSignature):   # another issuer, a bad signature, an unusable key type
        return False


def common_name(certificate: str) -> str | None:
    """The subject's common name of a PEM certificate (what Zenoh's access control matches)."""
    from cryptography import x509
    from cryptography.x509.oid import NameOID

    cert = x509.load_pem_x509_certificate(Path(certificate).read_bytes())
    names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(names[0].value) if names else None
