"""The OPC UA side of a gateway (asyncua): every asyncua call planthub makes is in this file.

Address space: Objects/<run>/<folder>/<tag> (browse names in the plant's namespace), one folder per plant object a tag is wired to (and
`gateway` for the handshake), in the namespace `urn:planthub:<run>`; each variable's node id is
`ns=<that namespace>;s=<folder>.<tag>`, its data type the tag's, its Description where it comes
from, its EngineeringUnits and EURange where the tag map gives them. Only the PLC's outputs are
writable. A write is refused with the protocol's own status: an unknown node BadNodeIdUnknown, a
PLC input BadUserAccessDenied (asyncua, for every user but an admin), a value of another type
BadTypeMismatch, a value out of the tag's range or not finite BadOutOfRange; each refusal is logged
and nothing reaches the plant. Clients subscribe with their own sampling interval. In lockstep a
Read of `cycle`'s value between two scans (as the process image decides) waits, in the server's event
loop, until the next begins.

Security: with `Certificates` the endpoint offers Basic256Sha256 Sign and SignAndEncrypt only, the
server's application URI taken from its certificate; a client's certificate must be valid (its time
range, its application URI) and, when trusted ones are given, one of them. asyncua 2.1.0 still lets
a client that ignores the endpoint list open a session on an unsecured channel, so every session
without a channel certificate is refused here too (BadUserAccessDenied).
"""
from __future__ import annotations

import asyncio
import dataclasses
import logging

from asyncua import Server, ua
from asyncua.common.callback import CallbackType
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from asyncua.server.address_space import AttributeService
from cryptography.hazmat.primitives.serialization import Encoding

from hub.gateway.certificates import Certificates
from hub.gateway.image import ProcessImage
from hub.gateway.tags import OUTPUT, Tag, namespace

_VARIANT = {"Boolean": ua.VariantType.Boolean, "UInt32": ua.VariantType.UInt32, "Int32": ua.VariantType.Int32,
            "Double": ua.VariantType.Double, "String": ua.VariantType.String}
for _name in ("asyncua", "asyncua.server", "asyncua.server.address_space"):
    logging.getLogger(_name).setLevel(logging.ERROR)   # asyncua logs every session, and warns of NoSecurity


class OpcUaServer:
    """The tags of `image` served at `endpoint` (opc.tcp://HOST:PORT/PATH)."""

    def __init__(self, image: ProcessImage, endpoint: str, user: tuple[str, str] | None = None,
                 certificates: Certificates | None = None):
        self.image, self.endpoint, self.user, self.certificates = image, endpoint, user, certificates
        self.server = None
        self.nodes = {}        # slot → NodeId
        self.waiting = []      # the futures of the reads of `cycle` held for the next scan
        self._wake = None      # the image's listener: the held reads go on (in this server's loop)

    async def start(self) -> None:
        users = _Users(self.user, secured=self.certificates is not None,
                       trusted=self.certificates.trusted if self.certificates else ())
        server = Server(user_manager=users if self.user or self.certificates else None)
        await server.init()
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"planthub gateway: {self.image.tags.run}")
        if self.certificates is None:
            server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        else:
            await self._secure(server, self.certificates)
        # No X509 identity token: the channel's own certificate is the one judged (_Users).
        server.set_identity_tokens([ua.UserNameIdentityToken] if self.user else [ua.AnonymousIdentityToken])
        ns = await server.register_namespace(namespace(self.image.tags.run))
        # Browse names in the plant's own namespace too (a bare string would put them in namespace 0),
        # so that a client's get_child(["2:<run>", "2:<folder>", "2:<tag>"]) finds them.
        name = lambda text: ua.QualifiedName(text, ns)
        root = await server.nodes.objects.add_folder(ua.NodeId(self.image.tags.run, ns), name(self.image.tags.run))
        folders = {}
        for tag in self.image.tags.tags:
            if tag.folder not in folders:
                folders[tag.folder] = await root.add_folder(ua.NodeId(tag.folder, ns), name(tag.folder))
            node = await folders[tag.folder].add_variable(
                ua.NodeId(tag.node_id, ns), name(tag.name), ua.Variant(self.image.values[tag.slot], _VARIANT[tag.opcua_type]))
            await node.write_attribute(ua.AttributeIds.Description,
                                       ua.DataValue(ua.Variant(ua.LocalizedText(tag.description))))
            if tag.units:
                await node.add_property(ns, "EngineeringUnits", ua.EUInformation(DisplayName=ua.LocalizedText(tag.units),
                                                                                Description=ua.LocalizedText(tag.units)))
            limits = tag.range or tag.scale
            if limits:
                await node.add_property(ns, "EURange", ua.Range(Low=float(limits[0]), High=float(limits[1])))
            if tag.direction == OUTPUT:
                await node.set_writable()
            self.nodes[tag.slot] = node.nodeid
        server.iserver.attribute_service = _CheckedWrites(server.iserver.aspace, self.image,
                                                          {self.nodes[t.slot]: t for t in self.image.tags.tags})
        server.subscribe_server_callback(CallbackType.PreRead, self._hold)
        await server.start()
        self.server = server
        loop = asyncio.get_running_loop()
        self._wake = lambda: loop.call_soon_threadsafe(self._go_on)
        self.image.listen(self._wake)

    @staticmethod
    async def _secure(server: Server, certificates: Certificates) -> None:
        await server.set_application_uri(certificates.application_uri)
        await server.load_certificate(certificates.certificate, format="der")
        await server.load_private_key(certificates.private_key, format="pem")
        server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
                                    ua.SecurityPolicyType.Basic256Sha256_Sign])
        options = CertificateValidatorOptions.BASIC_VALIDATION
        if certificates.trusted:
            options |= CertificateValidatorOptions.TRUSTED
        server.set_certificate_validator(CertificateValidator(options, _Pinned(certificates.trusted)))

    async def publish(self, changed: dict) -> None:
        for slot, value in changed.items():
            tag = self.image.tags.by_slot[slot]
            await self.server.write_attribute_value(self.nodes[slot], ua.DataValue(ua.Variant(value, _VARIANT[tag.opcua_type])))

    def _go_on(self, stopping: bool = False) -> None:
        """The held reads go on: their scan began, or the run ended (or the server stops). A wake the loop
        runs late, when the PLC has answered that scan already, leaves them held for the next."""
        if self.image.between_scans() and not stopping:
            return
        waiting, self.waiting = self.waiting, []
        for future in waiting:
            if not future.done():
                future.set_result(None)

    async def _hold(self, event, _dispatcher) -> None:
        """A Read of `cycle`'s value while the plant steps to its next scan waits for it (as
        ProcessImage.hold does in the other protocols' threads, here in the server's event loop),
        until the image's listener wakes it: the scan began (its values published) or the run ended."""
        cycle = self.nodes["cycle"]
        if not any(r.NodeId == cycle and r.AttributeId == ua.AttributeIds.Value for r in event.request_params.NodesToRead):
            return
        if not self.image.begin_hold():
            return
        future = asyncio.get_running_loop().create_future()
        self.waiting.append(future)   # before the loop runs a wake the plant may have sent since begin_hold
        try:
            await asyncio.wait_for(future, self.image.hold_limit)
        except TimeoutError:
            if future in self.waiting:
                self.waiting.remove(future)

    async def stop(self) -> None:
        if self._wake is not None:
            self.image.unlisten(self._wake)
            self._wake = None
        self._go_on(stopping=True)   # a read held for a next scan is answered now
        if self.server is not None:
            await self.server.stop()
            self.server = None


class _CheckedWrites(AttributeService):
    """asyncua's attribute service, with each write to a tag checked against the tag map first and
    each accepted one handed to the process image."""

    def __init__(self, aspace, image: ProcessImage, tags: dict):
        super().__init__(aspace)
        self.image, self.tags = image, tags

    async def write(self, params, user=User(role=UserRole.Admin)):   # noqa: B008 (asyncua's own signature)
        results, passed = [], []
        for k, item in enumerate(params.NodesToWrite):
            tag = self.tags.get(item.NodeId)
            status = self._check(tag, item) if tag is not None and item.AttributeId == ua.AttributeIds.Value else None
            if tag is None and not self._aspace.read_attribute_value(item.NodeId, ua.AttributeIds.NodeId).StatusCode.is_good():
                status = ua.StatusCode(ua.StatusCodes.BadNodeIdUnknown)   # (asyncua would say access denied)
                self.image.refuse(f"{item.NodeId.to_string()} (OPC UA)", "BadNodeIdUnknown: no such node")
            results.append(status)
            if status is None:
                passed.append(k)
        done = await super().write(dataclasses.replace(params, NodesToWrite=[params.NodesToWrite[k] for k in passed]), user)
        for k, status in zip(passed, done):
            results[k] = status
            item = params.NodesToWrite[k]
            tag = self.tags.get(item.NodeId)
            if tag is not None and item.AttributeId == ua.AttributeIds.Value:
                if status.is_good():
                    self.image.write(tag.slot, item.Value.Value.Value)
                else:
                    self.image.refuse(f"{tag.node_id} (OPC UA)", status.name)
        return results

    def _check(self, tag: Tag, item):
        """None if the write may go on to asyncua, else the status that refuses it."""
        if tag.direction != OUTPUT:
            return None   # asyncua refuses it by the node's access level
        variant = item.Value.Value
        if variant is None or variant.VariantType != _VARIANT[tag.opcua_type]:
            got = variant.VariantType.name if variant is not None else "nothing"
            self.image.refuse(f"{tag.node_id} (OPC UA)", f"BadTypeMismatch: {got}, the tag is {tag.opcua_type}")
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        try:
            tag.check_written(variant.Value)
        except ValueError as exc:
            self.image.refuse(f"{tag.node_id} (OPC UA)", f"BadOutOfRange: {exc}")
            return ua.StatusCode(ua.StatusCodes.BadOutOfRange)
        return None


class _Users:
    """Who may open a session: on a secured gateway only a client on a channel with a certificate
    (asyncua passes the channel's client certificate here) and, with `--trust`, only one of the
    trusted certificates; with a user only that user and password; anyone else is refused (asyncua
    answers BadUserAccessDenied).

    The trust is checked here, on the channel's certificate, and not only by asyncua's validator:
    asyncua 2.1.0 validates the certificate a client names in CreateSession, and only if it names
    one, never that it is the channel's — a client on a channel of its own certificate that names
    none (or a trusted client's public certificate) would pass it."""

    def __init__(self, user: tuple[str, str] | None, secured: bool, trusted: tuple[bytes, ...] = ()):
        self.user, self.secured, self.trusted = user, secured, set(trusted)

    def get_user(self, iserver, username=None, password=None, certificate=None):
        if self.secured and not certificate:
            return None
        if self.trusted and bytes(certificate) not in self.trusted:
            return None
        if self.user is not None and (username, password) != self.user:
            return None
        return User(role=UserRole.User, name=username)


class _Pinned:
    """The trust store asyncua's certificate validator asks: exactly the certificates given are trusted."""

    def __init__(self, trusted: tuple[bytes, ...]):
        self.trusted = set(trusted)

    def is_trusted(self, certificate) -> bool:
        return certificate.public_bytes(Encoding.DER) in self.trusted

    def is_revoked(self, certificate) -> bool:
        return False
