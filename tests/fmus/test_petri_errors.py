"""Bad nets, in YAML and in PNML: every problem is reported at once, with file, line and cause."""

import subprocess
import sys
import textwrap

import pytest

from fmus.petri import NetError, load_net

from .fmu_support import FMUS_DIR

PNML_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">
  <net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet">
    <page id="page">
"""
PNML_TAIL = """    </page>
  </net>
</pnml>
"""


@pytest.fixture
def problems_of(tmp_path):
    """problems_of(file name, text) -> (path, the messages of the NetError that loading it raises)."""

    def load(name, text):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text).lstrip("\n"))
        with pytest.raises(NetError) as caught:
            load_net(path)
        assert str(caught.value) == "\n".join(caught.value.problems)
        return path, caught.value.problems

    return load


def pnml(body):
    """A PNML file around body (place, transition and arc elements), which starts on line 5."""
    return PNML_HEAD + textwrap.indent(textwrap.dedent(body).strip("\n"), "      ") + "\n" + PNML_TAIL


# ---------------------------------------------------------------- YAML


def test_yaml_every_problem_at_once_in_line_order(problems_of):
    path, problems = problems_of("plant.net.yaml", """
        places:
          Ready: 1
          Busy: -1
          Ready: 2
        transitions:
          go: {in: [Ready, Bussy], out: [Busy], delay: -0.5}
          idle: {}
        """)
    assert problems == [
        f"{path}:3: place 'Busy': marking must not be negative, got -1",
        f"{path}:4: duplicate key 'Ready' (first at line 2)",
        f"{path}:6: transition 'go': delay must not be negative, got -0.5",
        f"{path}:6: transition 'go': input arc to unknown place 'Bussy' (did you mean 'Busy'?)",
        f"{path}:7: transition 'idle' has no arcs: it would do nothing",
    ]


@pytest.mark.parametrize("text, line, message", [
    ("places: {A: 1, B: 0}\ntransitions:\n  t: {in: [A], out: [C]}\n",
     3, "transition 't': output arc to unknown place 'C'"),
    ("places: {Start: 1}\ntransitions:\n  t: {in: [Strat]}\n",
     3, "transition 't': input arc to unknown place 'Strat' (did you mean 'Start'?)"),
    ("places: {A: 1}\ntransitions:\n  A: {in: [A]}\n",
     3, "transition 'A' has the same name as place 'A' (line 1): names must be unique across places and "
        "transitions, ignoring case"),
    ("places:\n  Gate: 1\n  gate: 0\n",
     3, "place 'gate' has a name that differs only in case as place 'Gate' (line 2): names must be unique across "
        "places and transitions, ignoring case"),
    ("places:\n  A: 1.5\n", 2, "place 'A': 1.5 is neither an integer nor a mapping"),
    ("places:\n  A: {marking: -3}\n", 2, "place 'A': marking must not be negative, got -3"),
    ("places:\n  A: {tokens: 1}\n", 2, "place 'A': unknown key 'tokens' (allowed: marking, description)"),
    ("places:\n  1st: 0\n", 2, "place name '1st' is not a C identifier (letters, digits and _, not starting with "
                              "a digit): it becomes part of the FMU's variable names"),
    ("places: {A: 1}\ntransitions:\n  t:\n    in: {A: 0}\n",
     4, "transition 't': in arc to 'A': weight must be at least 1, got 0"),
    ("places: {A: 1}\ntransitions:\n  t: {in: [A, A]}\n",
     3, "transition 't': in: 'A' listed more than once (write a mapping place: weight for an arc that moves "
        "several tokens)"),
    ("places: {A: 1}\ntransitions:\n  t: {in: [A], dealy: 1}\n",
     3, "transition 't': unknown key 'dealy' (did you mean 'delay'?)"),
    ("places: {A: 1}\ntransitions:\n  t:\n    in: [A]\n    delay: .nan\n", 5, "transition 't': delay is NaN"),
    ("places: {A: 1}\ntransitions:\n  t:\n    in: [A]\n    delay: soon\n", 5, "transition 't': delay: 'soon' is not "
                                                                              "a number"),
    ("places: {A: 3}\ntransitions:\n  t: {in: {A: 2}, inhibit: {A: 2}}\n",
     3, "transition 't' can never fire: it needs 2 token(s) on 'A' but is inhibited from 2"),
    ("places: {A: 1}\ntransitions:\n  t: {in: 5}\n", 3, "transition 't': in: 5 is neither a list nor a mapping"),
    ("places: {}\n", 1, "places: the net needs at least one place"),
    ("transitions: {}\n", 1, "net: 'places' is missing"),
    ("places: {A: 1}\nplace: 2\n", 2, "net: unknown key 'place' (did you mean 'places'?)"),
    ("- A\n- B\n", 1, "net: ['A', 'B'] is not a mapping"),
    ("places:\n  A: [1\n", 3, "not valid YAML: expected ',' or ']', but got '<stream end>'"),
    ("", 1, "the file is empty: expected a mapping with 'places' and 'transitions'"),
])
def test_yaml_problem(problems_of, text, line, message):
    path, problems = problems_of("net.net.yaml", text)
    assert problems == [f"{path}:{line}: {message}"]


def test_yaml_names_are_never_booleans(tmp_path):
    # YAML 1.1 reads On/Off/Yes/No as booleans; a net is read with YAML 1.2's true/false only.
    path = tmp_path / "lamp.net.yaml"
    path.write_text("places: {On: 0, Off: 1, Yes: 0}\ntransitions:\n  switch_on: {in: [Off], out: [On]}\n")
    net = load_net(path)
    assert [p.name for p in net.places] == ["On", "Off", "Yes"]


@pytest.mark.parametrize("name, message", [
    ("switch.net.yaml", "the file name gives the FMU name 'switch', which is not a C identifier or is a C keyword:"
                        " rename the file"),
    ("belt-1.pnml", "the file name gives the FMU name 'belt-1', which is not a C identifier or is a C keyword:"
                    " rename the file"),
    ("switch.yaml", "unknown kind of net file: expected a name ending in .pnml or .net.yaml"),
])
def test_file_name_gives_the_fmu_name(problems_of, name, message):
    text = "places: {A: 1}\n" if "yaml" in name else pnml('<place id="A"/>')
    path, problems = problems_of(name, text)
    assert problems[0] == f"{path}:1: {message}"


# ---------------------------------------------------------------- PNML


def test_pnml_every_problem_at_once_in_line_order(problems_of):
    path, problems = problems_of("plant.pnml", pnml("""
        <place id="p1"><name><text>Ready</text></name><initialMarking><text>-1</text></initialMarking></place>
        <place id="p2"><name><text>Ready</text></name></place>
        <transition id="t1"><name><text>go</text></name></transition>
        <arc id="a1" source="p1" target="t11"/>
        <arc id="a2" source="p2" target="t1"/>
        """))
    assert problems == [
        f"{path}:5: place 'Ready': marking must not be negative, got -1",
        f"{path}:6: place name 'Ready' (id 'p2') is used twice (first at line 5): names become the FMU's variable "
        "names",
        f"{path}:8: arc 'a1': target 't11' is no place or transition of this net (did you mean 't1'?)",
    ], "the arc from the rejected place p2 is not reported again"


@pytest.mark.parametrize("body, line, message", [
    ('<place id="p1"><initialMarking><text>lots</text></initialMarking></place>',
     5, "place 'p1': marking: 'lots' is not an integer"),
    ('<place id="p-1"/>', 5, "place name 'p-1' is not a C identifier (letters, digits and _, not starting with a "
                             "digit): it becomes part of the FMU's variable names"),
    ('<place id="p1"/>\n<place id="p1"/>', 6, "id 'p1' is used twice (first at line 5)"),
    ('<place id="p1"/>\n<transition id="t1"/>\n<arc id="a1" source="p1" target="t1"/>\n'
     '<arc id="a2" source="p1" target="t11"/>',
     8, "arc 'a2': target 't11' is no place or transition of this net (did you mean 't1'?)"),
    ('<place id="p1"/>\n<place id="p2"/>\n<arc id="a1" source="p1" target="p2"/>',
     7, "arc 'a1' connects two places ('p1' and 'p2'): an arc joins a place and a transition"),
    ('<place id="p1"/>\n<transition id="t1"/>\n<arc id="a1" source="t1" target="p1"><type value="inhibitor"/></arc>',
     7, "arc 'a1': an inhibitor arc goes from a place to a transition, not from transition 't1' to place 'p1'"),
    ('<place id="p1"/>\n<transition id="t1"/>\n<arc id="a1" source="p1" target="t1"><type value="reset"/></arc>',
     7, "arc 'a1': type 'reset' is not supported (normal or inhibitor)"),
    ('<place id="p1"/>\n<transition id="t1"/>\n<arc id="a1" source="p1" target="t1"/>\n'
     '<arc id="a2" source="p1" target="t1"/>',
     8, "arc 'a2' repeats the arc at line 7 between 'p1' and 't1': give one arc an inscription instead"),
    ('<place id="p1"/>\n<transition id="t1"/>\n<arc id="a1" source="p1" target="t1">'
     '<inscription><text>x</text></inscription></arc>',
     7, "transition 't1': in arc to 'p1': weight: 'x' is not an integer"),
    ('<place id="p1"/>\n<transition id="t1">\n  <toolspecific tool="planthub" version="1.0"><delay>-2</delay>'
     '</toolspecific>\n</transition>\n<arc id="a1" source="p1" target="t1"/>',
     7, "transition 't1': delay must not be negative, got -2.0"),
    ('<place id="p1"/>\n<referencePlace id="r1" ref="p1"/>',
     6, "<referencePlace> (modular PNML) is not supported: merge the referenced node into its page"),
])
def test_pnml_problem(problems_of, body, line, message):
    path, problems = problems_of("net.pnml", pnml(body))
    assert problems == [f"{path}:{line}: {message}"]


@pytest.mark.parametrize("text, line, message", [
    ('<pnml><net id="a"', 1, "not well-formed XML: "),
    ('<?xml version="1.0"?>\n<petrinet/>\n', 2, "the root element is <petrinet>: expected <pnml> (namespace "
                                                "http://www.pnml.org/version-2009/grammar/pnml)"),
    ('<pnml>\n  <net id="a" type="http://www.pnml.org/version-2009/grammar/ptnet"/>\n'
     '  <net id="b" type="http://www.pnml.org/version-2009/grammar/ptnet"/>\n</pnml>\n',
     1, "the file holds 2 <net> elements: expected exactly one (one net per file, it becomes one FMU)"),
    ('<pnml>\n  <net id="a" type="http://www.pnml.org/version-2009/grammar/symmetricnet">\n'
     '    <page id="p"><place id="x"/></page>\n  </net>\n</pnml>\n',
     2, "net type is 'http://www.pnml.org/version-2009/grammar/symmetricnet': only place/transition nets "
        "(http://www.pnml.org/version-2009/grammar/ptnet) are supported"),
])
def test_pnml_document_problem(problems_of, text, line, message):
    path, problems = problems_of("net.pnml", text)
    assert len(problems) == 1 and problems[0].startswith(f"{path}:{line}: {message}")


def test_pnml_entities_are_not_expanded(tmp_path):
    # A net file must not be able to pull other files into the build.
    path = tmp_path / "xxe.pnml"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE pnml [<!ENTITY secret SYSTEM "file:///etc/hostname">]>\n'
                    + pnml('<place id="p1"><name><text>&secret;</text></name></place>').split("\n", 1)[1])
    assert [p.name for p in load_net(path).places] == ["p1"]


# ---------------------------------------------------------------- command line


def test_check_command_reports_problems_of_every_file(tmp_path):
    first, second = tmp_path / "a.net.yaml", tmp_path / "b.net.yaml"
    first.write_text("places: {A: -1}\n")
    second.write_text("places: {B: 1}\ntransitions:\n  t: {in: [C]}\n")
    result = subprocess.run([sys.executable, "-B", "-m", "petri", "check", str(first), str(second)], cwd=FMUS_DIR,
                            capture_output=True, text=True)
    assert result.returncode == 1
    assert result.stderr.splitlines() == [f"{first}:1: place 'A': marking must not be negative, got -1",
                                          f"{second}:3: transition 't': input arc to unknown place 'C'"]
