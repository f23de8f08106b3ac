"""A controller delivered as an SSP (System Structure and Parameterization 1.0): its one system read, checked against its FMUs and parameter sets.

What is read, and by whom. fmpy (`fmpy.ssp.ssd`, 0.3.32) reads SystemStructure.ssd: the schema
check, the components, the connectors' names and kinds, the connections and the parameter
bindings with their parameter sets (inline, and .ssv files from the archive). Three facts fmpy
leaves out are read here from the same, already validated XML: a connector's type and unit
(fmpy's Connector keeps only name and kind), a connection's transformation (fmpy looks for
LinearTransformation in the ssd namespace, where the schema puts it in ssc, and reads no mapping
transformation), and `suppressUnitConversion`. Each .ssv a binding names is looked up and
validated here before fmpy reads it, because fmpy reports a missing one as a bare KeyError and an
invalid one as "Failed to validate SystemStructure.ssd".

What is supported: one flat system of FMU components (co-simulation, or model exchange integrated
by the hub with its default solver, as an `fmu` object would be); system connectors of kind
input and output (the object's slots); connections from a system input or a component's output
to a component's input or a system output, of one slot type, with an optional
LinearTransformation between reals; parameter sets applied as start values. Everything else —
nested systems, components that are not FMUs, signal dictionaries, parameter mappings, mapping
transformations, unit conversions — is refused by name, never ignored. A parameter's unit in an
.ssv is taken to be its variable's: it is not converted.
"""
from __future__ import annotations

import hashlib
import math
import posixpath
import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from fmpy.ssp.ssd import Component, System, read_ssd, validate_tree
from lxml import etree

from hub.core import scratch
from hub.core.errors import PlanthubError
from hub.core.registry import did_you_mean
from hub.core.slots import SlotType
from hub.logic.fmi import FmuError, FmuInterface, inspect_fmu
from hub.logic.fmi_variables import parameter_problems, parameter_values

SSD = "SystemStructure.ssd"
_NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
       "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
       "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
_FMU_TYPE = "application/x-fmu-sharedlibrary"   # a Component's type when it names none
_SSV_TYPE = "application/x-ssp-parameter-set"
# SSP's types (ssc:GTypeChoice) as slots, by the rules FMU variables follow (hub/logic/fmi_variables.py).
_TYPES = {"Real": SlotType.REAL, "Integer": SlotType.INT, "Enumeration": SlotType.INT, "Boolean": SlotType.BOOL,
          "String": SlotType.STRING, "Binary": SlotType.STRING}
_MAPPINGS = ("BooleanMappingTransformation", "IntegerMappingTransformation", "EnumerationMappingTransformation")


class SspError(PlanthubError):
    """An SSP cannot be used: every problem found, each naming the file, the element and the cause."""

    def __init__(self, path: Path, problems: list[str]):
        self.problems = [f"{path.name}: {p}" for p in problems]
        super().__init__("; ".join(self.problems))


@dataclass(frozen=True)
class Port:
    """A system connector: a slot of the object that runs the system."""

    name: str
    kind: str          # input or output
    type: SlotType


@dataclass(frozen=True)
class Link:
    """One connection, its ends as (component, variable) or (None, system connector)."""

    start: tuple[str | None, str]
    end: tuple[str | None, str]
    scale: tuple[float, float] | None = None   # a LinearTransformation's (factor, offset)

    def __str__(self) -> str:
        return f"{_end(self.start)} → {_end(self.end)}"


@dataclass(frozen=True)
class Part:
    """One FMU component: its interface (extracted to the scratch folder) and the values the
    SSP's parameter sets give its variables, checked, by variable."""

    name: str
    fmu: FmuInterface
    parameters: dict = field(default_factory=dict)


@dataclass(frozen=True)
class SspSystem:
    path: Path
    name: str
    parts: tuple[Part, ...]
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]
    links: tuple[Link, ...]

    def part(self, name: str) -> Part:
        return next(p for p in self.parts if p.name == name)


def read_ssp(path) -> SspSystem:
    """The system of the SSP at `path`, every part checked; SspError lists what is wrong.

    Read once per version of the file (its resolved path, modification time and size), as
    inspect_fmu reads an FMU: the scenario check, the slot table and the build share it."""
    path = Path(path)
    if not path.is_file():
        raise SspError(path, ["no such SSP file"])
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    known = _READ.get(key)
    # The scratch folder goes at exit (or when a test removes it): its FMUs must still be there.
    if isinstance(known, SspSystem) and all(p.fmu.path.is_file() for p in known.parts):
        return known
    if isinstance(known, SspError):
        raise known
    try:
        _READ[key] = _Reader(path, key).read()
    except SspError as exc:
        _READ[key] = exc
        raise
    return _READ[key]


_READ: dict[tuple, SspSystem | SspError] = {}


def override_problems(system: SspSystem, given: dict) -> list[tuple[str, str]]:
    """(key, message) for every bad entry of a scenario's `parameters:`, keyed `component.variable`."""
    problems = []
    parts = {p.name: p for p in system.parts}
    for key, value in given.items():
        component, _, variable = str(key).partition(".")
        part = parts.get(component)
        if part is None or not variable:
            problems.append((key, f"{key!r} is not component.variable of a component of {system.path.name}"
                                  f"{did_you_mean(component, parts)}"))
            continue
        problems += [(key, message) for _, message in
                     parameter_problems(part.fmu.path.name, part.fmu.variables, part.fmu.unmapped, {variable: value})]
    return problems


def start_values(system: SspSystem, given: dict) -> dict[str, dict]:
    """Component → the values its FMU starts with: the SSP's, then the scenario's `parameters:` (checked before)."""
    out = {p.name: dict(p.parameters) for p in system.parts}
    for key, value in given.items():
        component, _, variable = key.partition(".")
        out[component].update(parameter_values(system.part(component).fmu.variables, {variable: value}))
    return out


def _end(end: tuple[str | None, str]) -> str:
    return f"{end[0]}.{end[1]}" if end[0] is not None else f"system connector {end[1]!r}"


class _Reader:
    """One reading of an archive: collects every problem, then raises once."""

    def __init__(self, path: Path, key: tuple):
        self.path = path
        self.key = key
        self.problems: list[str] = []

    def fail(self, message: str) -> None:
        self.problems.append(message)

    def stop_if_failed(self) -> None:
        if self.problems:
            raise SspError(self.path, self.problems)

    def read(self) -> SspSystem:
        if not zipfile.is_zipfile(self.path):
            raise SspError(self.path, ["not an SSP (an SSP is a zip archive)"])
        with zipfile.ZipFile(self.path) as archive:
            self.names = set(archive.namelist())
            if SSD not in self.names:
                raise SspError(self.path, [f"no {SSD} in the archive (an SSP describes its system there)"])
            try:
                root = etree.fromstring(archive.read(SSD))
            except etree.XMLSyntaxError as exc:
                raise SspError(self.path, [f"{SSD} is not XML: {exc}"]) from None
            try:
                validate_tree(root, "SystemStructureDescription.xsd")
            except Exception as exc:  # fmpy raises a bare Exception listing the schema's complaints
                raise SspError(self.path, [f"{SSD} does not validate against the SSP 1.0 schema: "
                                           f"{_schema_errors(exc)}"]) from None
            self.parameter_files(root, archive)
        self.stop_if_failed()
        system = read_ssd(str(self.path), validate=False).system
        xml = root.find("ssd:System", _NS)
        self.unsupported(system)
        self.stop_if_failed()
        parts = self.parts(system)
        kinds = self.connectors(system, xml, parts)
        links, ports = self.links(system, xml, parts, kinds)
        self.parameters(system, parts)
        self.stop_if_failed()
        return SspSystem(self.path, system.name or self.path.stem, tuple(parts.values()),
                         tuple(p for p in ports.values() if p.kind == "input"),
                         tuple(p for p in ports.values() if p.kind == "output"), tuple(links))

    def parameter_files(self, root, archive) -> None:
        """Every .ssv a binding names is in the archive and valid (before fmpy opens it)."""
        for binding in root.iter(f"{{{_NS['ssd']}}}ParameterBinding"):
            source, kind = binding.get("source"), binding.get("type", _SSV_TYPE)
            if kind != _SSV_TYPE:
                self.fail(f"a ParameterBinding of type {kind!r}: not supported (only {_SSV_TYPE})")
            elif source is not None and source not in self.names:
                self.fail(f"the parameter set {source!r} that a ParameterBinding names is not in the archive")
            elif source is not None:
                try:
                    validate_tree(etree.fromstring(archive.read(source)), "SystemStructureParameterValues.xsd")
                except Exception as exc:
                    self.fail(f"the parameter set {source!r} does not validate against the SSP 1.0 schema: "
                              f"{_schema_errors(exc)}")

    def unsupported(self, system) -> None:
        for element in system.elements:
            if isinstance(element, System):
                self.fail(f"nested system {element.name!r}: not supported (planthub runs one flat system of FMUs)")
            elif isinstance(element, Component):
                if (element.type or _FMU_TYPE) != _FMU_TYPE:
                    self.fail(f"component {element.name!r} is {element.type!r}, not an FMU: only FMU components "
                              f"({_FMU_TYPE}) are supported")
            else:
                self.fail(f"signal dictionary reference {element.name!r}: signal dictionaries are not supported")
        for dictionary in system.signalDictionaries:
            self.fail(f"signal dictionary {dictionary.name!r}: signal dictionaries are not supported")
        for owner in [system] + list(system.elements):
            for binding in owner.parameterBindings:
                if binding.parameterMapping:
                    self.fail(f"{_owner(owner, system)}: a ParameterMapping: not supported (parameter names must "
                              f"be the variables' own)")

    def parts(self, system) -> dict[str, Part]:
        folder = scratch.folder() / "ssp" / hashlib.sha1(repr(self.key).encode()).hexdigest()[:12]
        parts = {}
        with zipfile.ZipFile(self.path) as archive:
            for n, component in enumerate(system.elements):
                source = posixpath.normpath(component.source or "")
                if source not in self.names:
                    self.fail(f"component {component.name!r}: its FMU {component.source!r} is not in the archive")
                    continue
                # In a folder of its position, not the archive's path: a member name must not place a file.
                target = folder / str(n) / Path(source).name
                if not target.is_file():
                    target.parent.mkdir(parents=True, exist_ok=True)
                    target.write_bytes(archive.read(source))
                try:
                    fmu = inspect_fmu(target)
                except FmuError as exc:
                    self.fail(f"component {component.name!r} ({source}): {str(exc).split(': ', 1)[-1]}")
                    continue
                parts[component.name] = Part(component.name, fmu)
        return parts

    def connectors(self, system, xml, parts):
        """(component or None for the system, connector) → (its kind or its variable's causality, its
        slot type — None for a system connector of no declared type —, its declared unit or None)."""
        declared = _declared(xml)
        kinds: dict[tuple[str | None, str], tuple[str, SlotType | None, str | None]] = {}
        for connector in system.connectors:
            kind = connector.kind
            if kind not in ("input", "output"):
                self.fail(f"system connector {connector.name!r} is of kind {kind!r}: only input and output "
                          f"connectors of the system are supported (they are the object's slots)")
                continue
            kinds[(None, connector.name)] = (kind, *declared.get((None, connector.name), (None, None)))
        for component in system.elements:
            part = parts.get(component.name)
            if part is None:
                continue
            for connector in component.connectors:
                variable = part.fmu.variables.get(connector.name)
                if variable is None:
                    self.fail(f"component {component.name!r}: its connector {connector.name!r} is no variable of "
                              f"{part.fmu.path.name}{did_you_mean(connector.name, part.fmu.variables)}")
                    continue
                stated, unit = declared.get((component.name, connector.name), (None, None))
                if stated is not None and stated is not variable.type:
                    self.fail(f"component {component.name!r}: connector {connector.name!r} is declared "
                              f"{stated.value} but {part.fmu.path.name} has it as {variable.type.value} "
                              f"({variable.fmi_type})")
                kinds[(component.name, connector.name)] = (variable.causality, variable.type, unit)
        return kinds

    def links(self, system, xml, parts, kinds):
        """The connections that pass every check, and the system's ports typed."""
        transformations = [_transformation(c) for c in xml.findall("ssd:Connections/ssd:Connection", _NS)]
        links, fed, typed, named = [], {}, {}, set()
        for connection, (scale, mapping, suppress) in zip(system.connections, transformations):
            start = (connection.startElement, connection.startConnector)
            end = (connection.endElement, connection.endConnector)
            named.add(end)
            link = Link(start, end, scale)
            known = True
            for at in (start, end):
                if at[0] is not None and at[0] not in {e.name for e in system.elements}:
                    self.fail(f"connection {link}: no component {at[0]!r}"
                              f"{did_you_mean(at[0], [e.name for e in system.elements])}")
                    known = False
                elif at not in kinds:
                    if at[0] is None or at[0] in parts:
                        self.fail(f"connection {link}: {_end(at)} is no connector of "
                                  f"{'the system' if at[0] is None else 'its component'}")
                    known = False
            if not known:
                continue
            (start_kind, start_type, start_unit), (end_kind, end_type, end_unit) = kinds[start], kinds[end]
            if start_kind != ("input" if start[0] is None else "output"):
                self.fail(f"connection {link}: it starts at {_what(start, start_kind)}; a connection runs from a "
                          f"system input or a component's output")
                continue
            if end_kind != ("output" if end[0] is None else "input"):
                self.fail(f"connection {link}: it ends at {_what(end, end_kind)}; a connection runs to a "
                          f"component's input or a system output")
                continue
            if start[0] is None and end[0] is None:
                self.fail(f"connection {link}: from a system input straight to a system output: not supported "
                          f"(a flow in the scenario does that)")
                continue
            if mapping is not None:
                self.fail(f"connection {link}: a {mapping}: not supported (only a LinearTransformation between reals)")
                continue
            if scale is not None and not all(math.isfinite(x) for x in scale):
                self.fail(f"connection {link}: its LinearTransformation's factor and offset must be finite "
                          f"(factor {scale[0]!r}, offset {scale[1]!r})")
                continue
            start_type = start_type or typed.get(start)
            end_type = end_type or typed.get(end)
            if start_type is not None and end_type is not None and start_type is not end_type:
                self.fail(f"connection {link}: type mismatch: {_end(start)} is {start_type.value} but "
                          f"{_end(end)} is {end_type.value}")
                continue
            if scale is not None and (start_type or end_type) is not SlotType.REAL:
                self.fail(f"connection {link}: a LinearTransformation between {(start_type or end_type).value}s: "
                          f"only between reals")
                continue
            if start_unit and end_unit and start_unit != end_unit and not suppress:
                self.fail(f"connection {link}: unit conversion from {start_unit!r} to {end_unit!r}: not supported "
                          f"(give the connection a LinearTransformation and suppressUnitConversion=\"true\")")
                continue
            for at in (start, end):   # a system connector without a declared type takes its partner's
                if at[0] is None and kinds[at][1] is None:
                    typed[at] = start_type or end_type
            if end in fed:
                self.fail(f"connection {link}: {_end(end)} is fed already, by {_end(fed[end])} (one writer per input)")
                continue
            fed[end] = start
            links.append(link)
        ports = {}
        for connector in system.connectors:
            at = (None, connector.name)
            if at not in kinds:
                continue
            kind, stated, _ = kinds[at]
            slot = stated or typed.get(at)
            if slot is None:
                self.fail(f"system connector {connector.name!r} has no type and no connection gives it one")
                continue
            if kind == "output" and at not in fed:
                if at not in named:   # one fed by a refused connection is named there
                    self.fail(f"system connector {connector.name!r} is an output that no connection feeds")
                continue
            ports[connector.name] = Port(connector.name, kind, slot)
        return links, ports

    def parameters(self, system, parts) -> None:
        """Each part's start values from the parameter sets: a component's own bindings in their
        order, then the system's (addressing `component.variable`, after the binding's prefix), each
        later value over an earlier one, as SSP's integrator overrides its supplier."""
        given: dict[str, dict] = {name: {} for name in parts}
        for owner in list(system.elements) + [system]:
            for binding in owner.parameterBindings:
                prefix = binding.prefix or ""
                where = binding.source or f"{SSD} (inline, {_owner(owner, system)})"
                for parameter_set in binding.parameterValues:
                    for parameter in parameter_set.parameters:
                        name = prefix + parameter.name
                        if owner is system:
                            component, _, variable = name.partition(".")
                        else:
                            component, variable = owner.name, name
                        if component not in parts:
                            if owner is system and component not in {e.name for e in system.elements}:
                                self.fail(f"{where}: parameter {name!r} names no component (a system's parameter "
                                          f"is component.variable){did_you_mean(component, parts)}")
                            continue
                        part = parts[component]
                        value = _value(parameter)
                        found = parameter_problems(part.fmu.path.name, part.fmu.variables, part.fmu.unmapped,
                                                   {variable: value})
                        if found:
                            self.fail(f"{where}: parameter {name!r}: {found[0][1]}")
                            continue
                        given[component][variable] = value
        for name, part in parts.items():
            if given[name]:
                parts[name] = Part(name, part.fmu, parameter_values(part.fmu.variables, given[name]))


def _what(at: tuple[str | None, str], kind: str) -> str:
    if at[0] is None:
        return f"{_end(at)}, a system {kind}"
    return f"{_end(at)}, {'an' if kind[0] in 'aeiou' else 'a'} {kind} of its FMU"


def _owner(owner, system) -> str:
    return "the system" if owner is system else f"component {owner.name!r}"


def _value(parameter):
    """An SSV value (XML text) as YAML would give it, so one check serves both."""
    text = parameter.value
    if parameter.type == "Real":
        return float(text)
    if parameter.type == "Integer":
        return int(text)
    if parameter.type == "Boolean":
        return text in ("true", "1")
    return text   # String, Binary (hex), Enumeration (an item's name)


def _declared(xml) -> dict[tuple[str | None, str], tuple[SlotType | None, str | None]]:
    """(element or None, connector) → (its declared slot type or None, its unit or None)."""
    out = {}
    owners = [(None, xml)] + [(c.get("name"), c) for c in xml.findall("ssd:Elements/ssd:Component", _NS)]
    for name, element in owners:
        for connector in element.findall("ssd:Connectors/ssd:Connector", _NS):
            kind, unit = None, None
            for child in connector:
                local = child.tag.rsplit("}", 1)[-1]
                if child.tag.startswith(f"{{{_NS['ssc']}}}") and local in _TYPES:
                    kind, unit = _TYPES[local], child.get("unit")
            out[(name, connector.get("name"))] = (kind, unit)
    return out


def _transformation(connection):
    """(LinearTransformation's (factor, offset) or None, a mapping transformation's name or None, suppressUnitConversion)."""
    scale = mapping = None
    for child in connection:
        local = child.tag.rsplit("}", 1)[-1]
        if local == "LinearTransformation":
            scale = (float(child.get("factor", 1.0)), float(child.get("offset", 0.0)))
        elif local in _MAPPINGS:
            mapping = local
    return scale, mapping, connection.get("suppressUnitConversion") in ("true", "1")


def _schema_errors(exc: Exception) -> str:
    """fmpy's "ERROR (line 6, column 0): Element '{http://…}Connector' …" lines as "line 6: Element 'ssd:Connector' …"."""
    lines = [re.sub(r"^\w+ \(line (\d+), column \d+\): ", r"line \1: ", line.strip())
             for line in str(exc).splitlines()[1:] if line.strip()]
    text = "; ".join(lines) or str(exc)
    for prefix, uri in _NS.items():
        text = text.replace(f"{{{uri}}}", f"{prefix}:")
    return text
