"""The EtherNet/IP side of a gateway (cpppo's Logix simulator): every cpppo call planthub makes is in this file.

Each tag is a controller-scoped Logix tag of its name and type (BOOL, DINT, REAL, SSTRING; the tag
map decides them), read and written by name with the Read/Write Tag services, as a ControlLogix
answers pylogix or pycomm3. Reads are answered from the process image. A write is checked before it
is taken, and refused with CIP's own general status: a PLC input 0x0F "privilege violation"; a value
out of the tag's range, not finite or a string too long or not UTF-8 0x09 "invalid attribute
value". cpppo itself refuses an unknown tag (0x05 "path destination unknown"), a value of a type
that does not fit the tag, or more elements than the tag has (0xFF, extended status 0x2107 and
0x2105); every refusal is logged, and nothing of it reaches the plant. An SSTRING's bytes are the
string's UTF-8, both ways (cpppo itself takes them for ISO 8859-1 text). In lockstep a read of `cycle`
between two scans is held until the next begins (`image.py`), and the tags after it in the same
request are read then (those before it, before the hold: a PLC names `cycle` first).

cpppo was chosen as the only maintained pure-Python EtherNet/IP *server* (pycomm3 and pylogix are
clients); it keeps its tags in module globals, so one gateway at a time in a process (as `planthub gateway` is).
Its answers take a few ms of CPU each (a Python parser per request): see make bench's gateway section (tests/README.md).
"""
from __future__ import annotations

import logging
import socket
import sys
import threading
import time

import cpppo
from cpppo.server.enip import device
from cpppo.server.enip.main import main as enip_main

from hub.core.errors import PlanthubError
from hub.core.slots import SlotType
from hub.gateway.image import ProcessImage
from hub.gateway.server_thread import refuse_taken
from hub.gateway.tags import OUTPUT, Tag

PRIVILEGE_VIOLATION, INVALID_VALUE = 0x0F, 0x09
STOP_LIMIT = 3.0   # s for cpppo's thread to end: less than the ServerThread's limit on the stop call
_log = logging.getLogger(__name__)
_CPPPO_LOGS = ("enip.srv", "enip.ucmm", "network", "cpppo")
_REFUSING = ("enip.dev", "enip.lgx")
DINT = 2 ** 31
# cpppo parses each request in Python for 1.5-2 ms of CPU a tag, holding the GIL, while the plant's
# step (Zenoh's callback threads, the participant's thread) waits to get it back: with Python's 5 ms
# switch interval a step waited up to 5 ms per hand-over. 0.5 ms: the bottling plant's first 20 s with a
# scan every 0.1 s took 9.95 s instead of 10.9 (medians of 3, side by side; the routing participant 1.14 s).
# What is left is cpppo's parse itself: ~2 ms of CPU a tag read or written (tests/bench_gateway).
SWITCH_INTERVAL = 0.0005


class EnipServer:
    """The tags of `image` served as Logix controller tags at `endpoint` (HOST:PORT; EtherNet/IP's own port is 44818)."""

    def __init__(self, image: ProcessImage, endpoint: str):
        self.image = image
        host, _, port = endpoint.rpartition(":")
        self.host, self.port = host or "127.0.0.1", int(port)
        self.control = None
        self.thread = None
        self.refusals = _Refusals(image)
        self.loggers = {}   # cpppo's loggers as they were before start: (level, propagate), restored by stop
        self.switch_interval = None   # the process's, before start: restored by stop

    async def start(self) -> None:
        refuse_taken(self.host, self.port, f"EtherNet/IP server at {self.host}:{self.port} did not start")
        for name in (*_CPPPO_LOGS, *_REFUSING):
            logger = logging.getLogger(name)
            self.loggers[name] = logger.level, logger.propagate
        for name in _CPPPO_LOGS:
            logging.getLogger(name).setLevel(logging.ERROR)   # it logs every connection at WARNING
        for name in _REFUSING:   # what they say of refused requests goes to the gateway's log, as a refusal
            logger = logging.getLogger(name)
            logger.setLevel(logging.INFO + 5)   # cpppo's NORMAL, at which it tells why a request failed
            logger.propagate = False
            logger.addHandler(self.refusals)
        self.switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(min(SWITCH_INTERVAL, self.switch_interval))
        image = self.image

        class TagAttribute(_TagAttribute):
            pass
        TagAttribute.image = image
        TagAttribute.by_name = {t.name: t for t in image.tags.tags}
        # cpppo keeps its tags in module globals, and for a tag it knows already keeps the old attribute
        # (5.2.5's setup_tag): a second server in this process (tests) would answer from the first's image
        device.lookup_reset()
        self.control = cpppo.apidict(timeout=1.0)
        self.control["control"] = cpppo.dotdict(done=False, disable=False)
        argv = ["--address", f"{self.host}:{self.port}", "--no-config",
                *(f"{t.name}={t.logix_type}" for t in image.tags.tags)]
        self.thread = threading.Thread(target=enip_main, name="enip server", daemon=True,
                                       kwargs=dict(argv=argv, attribute_class=TagAttribute,
                                                   server=dict(control=self.control["control"])))
        self.thread.start()
        deadline = time.monotonic() + 10.0
        while True:   # until it listens (cpppo binds in its own thread)
            try:
                socket.create_connection((self.host, self.port), timeout=1.0).close()
                return
            except OSError as exc:
                if not self.thread.is_alive() or time.monotonic() > deadline:
                    raise PlanthubError(f"EtherNet/IP server at {self.host}:{self.port} did not start: {exc}") from None
                time.sleep(0.05)

    def publish(self, changed: dict) -> None:
        """Nothing to do: every read is answered from the image."""

    async def stop(self) -> None:
        if self.thread is not None:
            self.control["control"]["done"] = True
            self.thread.join(STOP_LIMIT)
            if self.thread.is_alive():   # a daemon thread: it ends with the gateway's process
                _log.warning("gateway: the EtherNet/IP server at %s:%s did not stop within %g s",
                             self.host, self.port, STOP_LIMIT)
            self.thread = None
        for name in _REFUSING:
            logging.getLogger(name).removeHandler(self.refusals)
        for name, (level, propagate) in self.loggers.items():
            logger = logging.getLogger(name)
            logger.setLevel(level)
            logger.propagate = propagate
        self.loggers = {}
        if self.switch_interval is not None:
            sys.setswitchinterval(self.switch_interval)
            self.switch_interval = None


class _TagAttribute(device.Attribute):
    """A Logix tag whose value is the process image's; cpppo checks a write's type and size first,
    then this checks its direction and value. A refusal is answered through cpppo's `error` (its
    status for the request), cleared at the tag's next access. cpppo serves each connection in a
    thread of its own and reads `error` in that thread right after the access: so `error` is the
    thread's own, and another PLC's access to the same tag cannot clear a refusal before it is answered."""

    image: ProcessImage = None
    by_name: dict = {}

    def __init__(self, *args, **kwargs):
        self._errors = threading.local()
        super().__init__(*args, **kwargs)

    @property
    def error(self) -> int:
        return getattr(self._errors, "code", 0x00)

    @error.setter
    def error(self, code: int) -> None:
        self._errors.code = code

    @property
    def tag(self) -> Tag:
        return self.by_name[self.name]

    def __getitem__(self, key):
        self.error = 0x00
        tag = self.tag
        if tag.slot == "cycle":
            self.image.hold()   # lockstep: held while the plant steps to its next scan (hub/gateway/image.py)
        value = self.image.read(tag.slot)
        if tag.type is SlotType.STRING:   # its UTF-8 bytes, as the ISO 8859-1 text cpppo encodes an SSTRING from
            value = value.encode()[:2 * tag.length].decode(errors="ignore").encode().decode("iso-8859-1")
        elif tag.logix_type == "DINT":
            value = (int(value) + DINT) % (2 * DINT) - DINT if tag.type is SlotType.VOID else \
                max(min(int(value), DINT - 1), -DINT)
        self.default = value
        return super().__getitem__(key)

    def __setitem__(self, key, value):
        self.error = 0x00
        tag = self.tag
        value = list(value)[0] if isinstance(key, slice) else value
        where = f"{tag.name} (EtherNet/IP)"
        if tag.direction != OUTPUT:
            self.image.refuse(where, "0x0F privilege violation: a PLC input is read-only")
            self.error = PRIVILEGE_VIOLATION
            return
        try:
            if tag.type is SlotType.STRING:   # cpppo decodes an SSTRING's bytes as ISO 8859-1: the PLC's bytes again
                raw = value.encode("iso-8859-1") if isinstance(value, str) else bytes(value)
                if len(raw) > 2 * tag.length:
                    raise ValueError(f"{len(raw)} bytes is longer than {2 * tag.length}")
                value = raw.decode()
            else:
                value = {"BOOL": bool, "REAL": float, "DINT": int}[tag.logix_type](value)
            value = tag.check_written(value)
        except (ValueError, UnicodeDecodeError) as exc:
            self.image.refuse(where, f"0x09 invalid attribute value: {exc}")
            self.error = INVALID_VALUE
            return
        self.image.write(tag.slot, value)
        super().__setitem__(key, [value] if isinstance(key, slice) else value)


class _Refusals(logging.Handler):
    """The requests cpppo refuses itself (an unknown tag, a type or a size that does not fit), logged as
    the gateway's refusals: cpppo says so only in its own log."""

    def __init__(self, image: ProcessImage):
        super().__init__(logging.INFO + 5)
        self.image = image

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        if "Failed attempting to resolve path" in text:
            symbol = text.split("'symbolic': '", 1)[-1].split("'", 1)[0]
            self.image.refuse(f"{symbol} (EtherNet/IP)", "0x05 path destination unknown: no such tag")
        elif "failed with Exception" in text and "Write Tag" in text:
            why = text.split("failed with Exception: ", 1)[-1].splitlines()[0]
            if "Forced failure" not in why:   # (that is this gateway's own refusal, logged already)
                self.image.refuse("a tag (EtherNet/IP)", f"0xFF general error: {why}")
