"""load_net: read a net file in either format, check it completely, and return the Net or raise NetError."""

import re
from pathlib import Path

from . import pnml, schema, yaml_form
from .assemble import assemble
from .problems import Problems

# The file name gives the FMU's model identifier.
SUFFIXES = {".pnml": pnml.read, ".net.yaml": yaml_form.read}
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# FMI's modelIdentifier is a C identifier: description.py applies the same rule (a test keeps the two lists equal).
C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while "
    "_Bool _Complex _Imaginary bool true false".split())


def _split(path):
    """(name, reader) from a net's file name (track_switch.pnml -> track_switch), or (None, None)."""
    file_name = Path(path).name
    for suffix, reader in SUFFIXES.items():
        if file_name.endswith(suffix):
            return file_name[: -len(suffix)], reader
    return None, None


def net_name(path):
    """The net's name from its file name, or None if it is not a net file."""
    return _split(path)[0]


def load_net(path):
    """The checked Net in path (*.pnml or *.net.yaml); NetError lists every problem with file and line."""
    path = Path(path)
    problems = Problems(path)
    name, read = _split(path)
    if name is None:
        problems.add(1, f"unknown kind of net file: expected a name ending in {' or '.join(SUFFIXES)}")
        problems.raise_if_any()
    if not _IDENTIFIER.match(name) or name in C_KEYWORDS:
        problems.add(1, f"the file name gives the FMU name '{name}', which is not a C identifier or is a C keyword:"
                     " rename the file")
    document = read(path, problems)
    net = None
    if document is not None:
        schema.check(document, problems)
        net = assemble(name, document, problems, path)
    problems.raise_if_any()
    return net
