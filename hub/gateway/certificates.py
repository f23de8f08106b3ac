"""The OPC UA gateway's certificate, its private key and the client certificates it trusts, read and checked."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa

from hub.core.errors import PlanthubError

SUFFIXES = (".der", ".pem", ".crt", ".cer")   # what a --trust folder's certificates end with


class CertificateError(PlanthubError):
    """A certificate, key or trusted certificate the gateway was given is unusable; names every file and cause."""

    def __init__(self, problems: list[str]):
        self.problems = problems
        super().__init__("the OPC UA gateway's security:\n" + "\n".join(f"  - {p}" for p in problems))


@dataclass(frozen=True)
class Certificates:
    """The server's certificate (DER) and private key (PEM), its application URI, and the DER of every
    client certificate it admits (empty: any client whose certificate is valid)."""

    certificate: bytes
    private_key: bytes
    application_uri: str
    trusted: tuple[bytes, ...] = ()


def load_certificates(certificate: Path, private_key: Path, trust: list[Path] = ()) -> Certificates:
    """The files checked: each one readable, a certificate or an RSA key in PEM or DER, the key the
    certificate's, the certificate carrying an application URI; every problem found, raised at once."""
    problems = []
    cert = _certificate(certificate, "--certificate", problems)
    key = _key(private_key, problems)
    uri = None
    if cert is not None:
        try:
            names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
            uri = next(iter(names.get_values_for_type(x509.UniformResourceIdentifier)), None)
        except x509.ExtensionNotFound:
            pass
        if uri is None:
            problems.append(f"--certificate {certificate}: no application URI (a URI in its subjectAltName), "
                            f"which OPC UA requires of an application certificate")
        if key is not None and cert.public_key().public_numbers() != key.public_key().public_numbers():
            problems.append(f"--private-key {private_key}: not the key of the certificate {certificate} "
                            f"(their public keys differ)")
    trusted = []
    for path in trust:
        if path.is_dir():
            files = sorted(p for p in path.iterdir() if p.suffix.lower() in SUFFIXES)
            if not files:
                problems.append(f"--trust {path}: a folder without certificates (*{', *'.join(SUFFIXES)})")
        else:
            files = [path]
        for file in files:
            client = _certificate(file, "--trust", problems)
            if client is not None:
                trusted.append(client.public_bytes(serialization.Encoding.DER))
    if problems:
        raise CertificateError(problems)
    return Certificates(cert.public_bytes(serialization.Encoding.DER),
                        key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()),
                        uri, tuple(trusted))


def _read(path: Path, option: str, problems: list) -> bytes | None:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        problems.append(f"{option} {path}: no such file")
    except OSError as exc:
        problems.append(f"{option} {path}: cannot be read ({exc.strerror or exc})")
    return None


def _certificate(path: Path, option: str, problems: list) -> x509.Certificate | None:
    data = _read(path, option, problems)
    if data is None:
        return None
    try:
        return x509.load_pem_x509_certificate(data) if _is_pem(data) else x509.load_der_x509_certificate(data)
    except ValueError:
        problems.append(f"{option} {path}: not an X.509 certificate (PEM or DER)")
        return None


def _key(path: Path, problems: list):
    data = _read(path, "--private-key", problems)
    if data is None:
        return None
    try:
        key = (serialization.load_pem_private_key(data, password=None) if _is_pem(data)
               else serialization.load_der_private_key(data, password=None))
    except TypeError:   # the key is encrypted: the gateway runs unattended, with no one to type its password
        problems.append(f"--private-key {path}: encrypted with a password; give the gateway an unencrypted key")
        return None
    except ValueError:
        problems.append(f"--private-key {path}: not a private key (PEM or DER)")
        return None
    if not isinstance(key, rsa.RSAPrivateKey):
        problems.append(f"--private-key {path}: a {type(key).__name__.removeprefix('_')} key; Basic256Sha256 "
                        f"needs an RSA key")
        return None
    return key


def _is_pem(data: bytes) -> bool:
    return data.lstrip().startswith(b"-----BEGIN")
