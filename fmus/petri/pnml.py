"""Read a PNML place/transition net (ISO/IEC 15909-2, 2009 grammar) into a Document of the YAML form's shape.

PNML has no delays or descriptions, so they ride in the place the standard
keeps for tools: <toolspecific tool="planthub" version="1.0"> holding
<delay>seconds</delay>, <description>text</description> or, on an arc,
<inhibitor/>. PIPE's <type value="inhibitor"/> on an arc is read as well.
Graphics and other tools' data are ignored."""

import re

from lxml import etree

from .document import Document
from .problems import did_you_mean

PNML_NAMESPACE = "http://www.pnml.org/version-2009/grammar/pnml"
PTNET = "http://www.pnml.org/version-2009/grammar/ptnet"
TOOL = "planthub"

_INTEGER = re.compile(r"[+-]?\d+\Z")
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\Z")


def read(path, problems):
    """The Document of the PNML net at path, or None if it cannot be read as one (the cause is in problems)."""
    # No DTDs, entities or network: a net file must not be able to read other files or hang the build.
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, remove_comments=True)
    try:
        root = etree.parse(str(path), parser).getroot()
    except etree.XMLSyntaxError as error:
        problems.add(error.lineno or 1, f"not well-formed XML: {error.msg}")
        return None
    except OSError as error:
        problems.add(1, f"cannot read the file: {error}")
        return None
    if _local(root) != "pnml" or etree.QName(root).namespace not in (None, PNML_NAMESPACE):
        problems.add(root.sourceline, f"the root element is <{root.tag}>: expected <pnml> "
                     f"(namespace {PNML_NAMESPACE})")
        return None
    nets = [child for child in _children(root) if _local(child) == "net"]
    if len(nets) != 1:
        problems.add(root.sourceline, f"the file holds {len(nets)} <net> elements: expected exactly one "
                     "(one net per file, it becomes one FMU)")
        return None
    return _Reader(problems).read(nets[0])


class _Reader:
    def __init__(self, problems):
        self.problems = problems
        self.document = Document({"places": {}, "transitions": {}})
        self.nodes = {}  # PNML id -> (kind, name, line)
        self.rejected = set()  # ids of nodes already reported: their arcs are not reported again

    def read(self, net):
        if net.get("type") != PTNET:
            self.problems.add(net.sourceline, f"net type is '{net.get('type')}': only place/transition nets "
                              f"({PTNET}) are supported")
        description = _tool_text(net, "description") or _label_text(net, "name")
        if description:
            self.document.data["description"] = description
        places, transitions, arcs = [], [], []
        self._collect(net, places, transitions, arcs)
        for element in places:
            self._place(element)
        for element in transitions:
            self._transition(element)
        for element in arcs:
            self._arc(element)
        return self.document

    def _collect(self, element, places, transitions, arcs):
        """Nodes of the net and of its pages, flattened: pages only group nodes for editors."""
        for child in _children(element):
            kind = _local(child)
            if kind == "page":
                self._collect(child, places, transitions, arcs)
            elif kind in ("place", "transition", "arc"):
                {"place": places, "transition": transitions, "arc": arcs}[kind].append(child)
            elif kind in ("referencePlace", "referenceTransition"):
                self.problems.add(child.sourceline, f"<{kind}> (modular PNML) is not supported: merge the "
                                  "referenced node into its page")
                self.rejected.add(child.get("id"))

    def _node(self, element, kind):
        """Register the node; its name (the <name> label, else its id), or None if it cannot be used."""
        node_id = element.get("id")
        if not node_id:
            self.problems.add(element.sourceline, f"<{kind}> without an id")
            return None
        if node_id in self.nodes:
            self.problems.add(element.sourceline, f"id '{node_id}' is used twice (first at line "
                              f"{self.nodes[node_id][2]})")
            return None
        name = _label_text(element, "name") or node_id
        section = "places" if kind == "place" else "transitions"
        if name in self.document.data[section]:
            first = self.document.lines[(section, name)]
            self.problems.add(element.sourceline, f"{kind} name '{name}' (id '{node_id}') is used twice (first at "
                              f"line {first}): names become the FMU's variable names")
            self.rejected.add(node_id)
            return None
        self.nodes[node_id] = (kind, name, element.sourceline)
        self.document.lines[(section, name)] = element.sourceline
        return name

    def _place(self, element):
        name = self._node(element, "place")
        if name is None:
            return
        entry = {}
        marking = _label(element, "initialMarking")
        if marking is not None:
            entry["marking"] = _integer(_text(marking))
            self.document.lines[("places", name, "marking")] = marking.sourceline
        description = _tool_text(element, "description")
        if description:
            entry["description"] = description
        self.document.data["places"][name] = entry

    def _transition(self, element):
        name = self._node(element, "transition")
        if name is None:
            return
        entry = {}
        delay = _tool_element(element, "delay")
        if delay is not None:
            entry["delay"] = _number((delay.text or "").strip())
            self.document.lines[("transitions", name, "delay")] = delay.sourceline
        description = _tool_text(element, "description")
        if description:
            entry["description"] = description
        self.document.data["transitions"][name] = entry

    def _arc(self, element):
        arc_id, line = element.get("id", "?"), element.sourceline
        ids = (element.get("source"), element.get("target"))
        for node_id in ids:
            node = self.nodes.get(node_id)
            if node is not None and node[0] == "transition":
                # The file gave this transition an arc: if the arc is rejected, its absence is the same problem.
                self.document.reported.add(("transitions", node[1]))
        if any(node_id in self.rejected for node_id in ids):
            return
        ends = []
        for end, node_id in zip(("source", "target"), ids):
            if node_id not in self.nodes:
                self.problems.add(line, f"arc '{arc_id}': {end} '{node_id}' is no place or transition of this net"
                                  + did_you_mean(node_id, self.nodes))
            ends.append(self.nodes.get(node_id))
        if None in ends:
            return
        (source_kind, source, _), (target_kind, target, _) = ends
        pipe_type = _label(element, "type")
        if pipe_type is not None and pipe_type.get("value") not in ("normal", "inhibitor"):
            self.problems.add(line, f"arc '{arc_id}': type '{pipe_type.get('value')}' is not supported (normal or "
                              "inhibitor)")
            return
        inhibitor = _is_inhibitor(element)
        if source_kind == target_kind:
            self.problems.add(line, f"arc '{arc_id}' connects two {source_kind}s ('{source}' and '{target}'): an "
                              "arc joins a place and a transition")
            return
        if inhibitor and source_kind != "place":
            self.problems.add(line, f"arc '{arc_id}': an inhibitor arc goes from a place to a transition, not from "
                              f"transition '{source}' to place '{target}'")
            return
        place, transition = (source, target) if source_kind == "place" else (target, source)
        key = "inhibit" if inhibitor else ("in" if source_kind == "place" else "out")
        arcs = self.document.data["transitions"][transition].setdefault(key, {})
        path = ("transitions", transition, key, place)
        if place in arcs:
            self.problems.add(line, f"arc '{arc_id}' repeats the arc at line {self.document.lines[path]} between "
                              f"'{source}' and '{target}': give one arc an inscription instead")
            return
        inscription = _label(element, "inscription")
        arcs[place] = 1 if inscription is None else _integer(_text(inscription))
        self.document.lines.setdefault(("transitions", transition, key), line)
        self.document.lines[path] = line


def _children(element):
    return [child for child in element if isinstance(child.tag, str)]  # skips processing instructions


def _local(element):
    return etree.QName(element).localname


def _label(element, name):
    return next((child for child in _children(element) if _local(child) == name), None)


def _text(label):
    """The <text> of a PNML label, stripped."""
    text = _label(label, "text")
    return (text.text or "").strip() if text is not None else ""


def _label_text(element, name):
    label = _label(element, name)
    return _text(label) if label is not None else ""


def _tool_element(element, name):
    for tool in _children(element):
        if _local(tool) == "toolspecific" and tool.get("tool") == TOOL:
            found = _label(tool, name)
            if found is not None:
                return found
    return None


def _tool_text(element, name):
    found = _tool_element(element, name)
    return (found.text or "").strip() if found is not None else ""


def _is_inhibitor(arc):
    pipe_type = _label(arc, "type")
    return _tool_element(arc, "inhibitor") is not None or (pipe_type is not None
                                                            and pipe_type.get("value") == "inhibitor")


def _integer(text):
    """int of text, or text itself for the schema to report."""
    return int(text) if _INTEGER.match(text) else text


def _number(text):
    return float(text) if _NUMBER.match(text) else text
