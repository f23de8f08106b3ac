"""Reading nets: PNML and YAML give one net model; the plant's nets and the schema agree."""

import json

import jsonschema
import pytest

from fmus.petri import load_net
from fmus.petri.schema import SCHEMA_PATH

from .fmu_support import TEST_NETS_DIR
from .petri_support import PLANT_NETS_DIR, load, net_files

# fmus/nets/belt_run_stop.pnml written in the YAML form.
BELT_RUN_STOP_YAML = """
description: Belt drive run/stop; a stop command wins over a run command in the same step.
places:
  Stopped: {marking: 1, description: The belt stands.}
  Running: {marking: 0, description: The belt runs.}
  Run: {marking: 0, description: "Command: run."}
  Stop: {marking: 0, description: "Command: stop."}
transitions:
  start: {in: [Run, Stopped], out: [Running], inhibit: [Stop]}
  halt: {in: [Stop, Running], out: [Stopped]}
  run_again: {in: [Run, Running], out: [Running], description: Drop a run command while running.}
  stop_again: {in: [Stop, Stopped], out: [Stopped], description: Drop a stop command while stopped.}
  run_overridden: {in: [Run, Stop], out: [Stop], description: Drop a run command that came with a stop command.}
"""


def test_pnml_and_yaml_give_the_same_net(tmp_path):
    path = tmp_path / "belt_run_stop.net.yaml"
    path.write_text(BELT_RUN_STOP_YAML)
    assert load_net(path).structure() == load("belt_run_stop").structure()


def test_short_and_long_forms_are_the_same(tmp_path):
    short, long = tmp_path / "a" / "n.net.yaml", tmp_path / "b" / "n.net.yaml"
    short.parent.mkdir()
    long.parent.mkdir()
    short.write_text("places: {A: 2, B: 0}\ntransitions:\n  t: {in: [A], out: [B]}\n")
    long.write_text("places:\n  A: {marking: 2}\n  B: {}\ntransitions:\n  t:\n    in: {A: 1}\n    out: {B: 1}\n")
    assert load_net(short).structure() == load_net(long).structure()


def test_pnml_pages_ids_inscriptions_and_both_inhibitor_notations():
    net = load("awkward_names")
    assert [p.name for p in net.places] == ["t", "h", "v", "inst", "m", "int", "fire", "take", "s"]
    assert [p.marking for p in net.places] == [2, 0, 0, 0, 1, 0, 0, 0, 0]
    transitions = {t.name: t for t in net.transitions}
    assert transitions["p"].inputs == (("t", 2),) and transitions["p"].inhibitors == (("inst", 3),)  # PIPE style
    assert transitions["step"].inhibitors == (("take", 1),)  # <toolspecific tool="planthub"><inhibitor/>
    assert transitions["step"].outputs == (("fire", 3),)
    # Only planthub's toolspecific counts: another tool's <delay>99</delay> is ignored.
    assert {t.name: t.delay for t in net.delayed} == {"i": 0.05, "delays": 0.1, "delays_ready": 0.0}
    assert transitions["p"].delay is None


def test_takes_and_gives_are_the_net_change_of_the_arcs():
    transitions = {t.name: t for t in load("awkward_names").transitions + load("conflicts").transitions}
    assert (transitions["delays"].takes, transitions["delays"].gives) == ((("fire", 1),), ())  # 2 fire -> fire
    assert (transitions["read_U"].takes, transitions["read_U"].gives) == ((), (("UA", 1),))  # U is only tested
    assert (transitions["p"].takes, transitions["p"].gives) == ((("t", 2),), (("h", 1), ("v", 1)))


@pytest.mark.parametrize("path", [p for p in net_files(PLANT_NETS_DIR) + net_files(TEST_NETS_DIR)
                                  if p.name.endswith(".net.yaml")], ids=lambda p: p.name)
def test_yaml_nets_are_valid_against_the_published_schema(path):
    import yaml  # the schema is for editors too: check with a plain YAML reader, not ours

    schema = json.loads(SCHEMA_PATH.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.validate(yaml.safe_load(path.read_text()), schema, cls=jsonschema.Draft202012Validator)


def test_lines_point_into_the_file():
    net = load("track_switch")
    lines = (PLANT_NETS_DIR / "track_switch.pnml").read_text().splitlines()
    for item in net.places + net.transitions:
        assert f'id="{item.name}"' in lines[item.line - 1]
