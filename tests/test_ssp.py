"""A controller delivered as an SSP (modules/ssp.py): the same recording as its FMUs wired by hand, its parameter sets, every refusal named.

    barrier.trigger.occupied ──► ctl.logic.blocked ──► timer.start
    go.value.out (true)      ──► ctl.logic.go      ──► drive.run
                                 timer.remaining   ──► drive.speed_setpoint
    belt.drive.speed ◄── ctl.logic.speed ◄──────────── drive.speed

The archives are built here (tests/ssp_archives.py) from build/fmus' timer and belt_drive, and one
with the model-exchange stand-in tank3 (tests/fmu_models/foreign).
"""
from __future__ import annotations

import csv

import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.scenario.checker import load_scenario

from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario
from .ssp_archives import HEAD, TIMER_BELT, TUNING, parameter_set, write_ssp

BUILT = ROOT / "build" / "fmus"

PLANT = """\
planthub: 1
run: {duration: 1.2, physics_rate: 150, communication_step: 0.02}
objects:
  belt:    {module: conveyor, position: [0, 0, 0], length: 2.5, speed: 0.0, k: 16}
  bottle:  {module: bottle, position: [0.3, 0, 0]}
  barrier: {module: light_barrier, position: [0.3, 0, 0.05]}
  go:      {module: constant, type: bool, value: true}
"""
RECORDED = "belt.drive.velocity, bottle.body.position, barrier.trigger.occupied"

#: line 10 holds the SSP object's `file:`, which every problem of the archive is named at
WITH_SSP = PLANT + """\
  ctl:
    module: ssp
    file: ctl.ssp
flows:
  - {from: barrier.trigger.occupied, to: ctl.logic.blocked}
  - {from: go.value.out, to: ctl.logic.go, when: target}
  - {from: ctl.logic.speed, to: belt.drive.speed}
record: [ctl.logic.speed, ctl.logic.running, ctl.logic.done, %s]
""" % RECORDED

BY_HAND = PLANT + f"""\
  timer: {{module: fmu, file: {BUILT / 'timer-fmi2.fmu'}, parameters: {{period: 0.8}}}}
  drive: {{module: fmu, file: {BUILT / 'belt_drive-fmi2.fmu'}, parameters: {{ramp: 2.0}}}}
flows:
  - {{from: barrier.trigger.occupied, to: timer.logic.start}}
  - {{from: go.value.out, to: drive.logic.run, when: target}}
  - {{from: timer.logic.remaining, to: drive.logic.speed_setpoint}}
  - {{from: drive.logic.speed, to: belt.drive.speed}}
record: [drive.logic.speed, drive.logic.running, timer.logic.elapsed, {RECORDED}]
"""
RENAMED = {"ctl.logic.speed": "drive.logic.speed", "ctl.logic.running": "drive.logic.running",
           "ctl.logic.done": "timer.logic.elapsed"}


@pytest.fixture(scope="module", autouse=True)
def fmus():
    """The project's FMUs, brought up to date (free after `make fmus`)."""
    return build(BUILT)


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def scene(tmp_path, write_scenario, ssd=TIMER_BELT, ssv=TUNING, text=WITH_SSP, **archive):
    write_ssp(tmp_path / "ctl.ssp", ssd, ssv, **archive)
    return write_scenario(text)


def problems(path, overrides=None) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, overrides)
    return [str(p).replace(f"{path.parent}/", "") for p in info.value.problems]


@pytest.mark.parametrize("event_driven", [False, True])
def test_an_ssp_records_exactly_what_its_fmus_wired_by_hand_record(tmp_path, write_scenario, event_driven):
    """Jacobi inside the SSP as between `fmu` objects: the recording's bytes are the same, the
    SSP's slots named as the hand-wired FMUs' slots they stand for."""
    overrides = {"run.event_driven": event_driven}
    run_scenario(scene(tmp_path, write_scenario), tmp_path / "ssp", overrides)
    run_scenario(write_scenario(BY_HAND, "by_hand.yaml"), tmp_path / "by_hand", overrides)
    ssp = (tmp_path / "ssp" / "recording.csv").read_text()
    by_hand = (tmp_path / "by_hand" / "recording.csv").read_text()
    for slot, same in RENAMED.items():
        ssp = ssp.replace(f'"{slot}"', f'"{same}"', 1)
    assert ssp == by_hand
    assert (tmp_path / "ssp" / "events.csv").read_bytes() == (tmp_path / "by_hand" / "events.csv").read_bytes()
    data = rows(tmp_path / "ssp" / "recording.csv")
    # The run shows the controller at work: the belt pushed the bottle off the barrier, then stopped.
    assert max(float(r["ctl.logic.speed"]) for r in data) > 0.3 and float(data[-1]["ctl.logic.speed"]) == 0.0
    assert [r["ctl.logic.done"] for r in data].count("1") == 1


def fired_at(path) -> float:
    """When the timer fired (the system output `done`)."""
    return next(float(r["time"]) for r in rows(path / "recording.csv") if r["ctl.logic.done"] == "1")


def test_the_parameter_set_and_the_scenarios_parameters_set_the_timer(tmp_path, write_scenario):
    """The SSV's timer.period (0.8 s) decides when `done` fires; another .ssv moves it, and the
    scenario's `parameters:` override both."""
    run_scenario(scene(tmp_path, write_scenario), tmp_path / "ssv")
    assert fired_at(tmp_path / "ssv") == 0.8
    write_ssp(tmp_path / "ctl.ssp", TIMER_BELT, parameter_set({"timer.period": ("Real", "0.4")}))
    run_scenario(tmp_path / "scene.yaml", tmp_path / "shorter")
    assert fired_at(tmp_path / "shorter") == 0.4
    run_scenario(tmp_path / "scene.yaml", tmp_path / "override", {"objects.ctl.parameters": {"timer.period": 0.5}})
    assert fired_at(tmp_path / "override") == 0.5


def test_a_binding_prefix_names_the_component(tmp_path, write_scenario):
    """A system's parameter set of bare names, applied to one component by the binding's prefix."""
    ssd = TIMER_BELT.replace('<ssd:ParameterBinding source="resources/tuning.ssv"/>',
                             '<ssd:ParameterBinding source="resources/tuning.ssv" prefix="timer."/>')
    run_scenario(scene(tmp_path, write_scenario, ssd, parameter_set({"period": ("Real", "0.6")})), tmp_path / "out")
    assert fired_at(tmp_path / "out") == 0.6


def test_a_linear_transformation_scales_the_value_on_its_connection(tmp_path, write_scenario):
    """factor 2 on drive.speed → speed: the system output is twice the drive's speed at every point."""
    run_scenario(scene(tmp_path, write_scenario), tmp_path / "plain")
    ssd = TIMER_BELT.replace('<ssd:Connection startElement="drive" startConnector="speed" endConnector="speed"/>',
                             '<ssd:Connection startElement="drive" startConnector="speed" endConnector="speed">'
                             '<ssc:LinearTransformation factor="2.0"/></ssd:Connection>')
    run_scenario(scene(tmp_path, write_scenario, ssd), tmp_path / "doubled")
    plain = [float(r["ctl.logic.speed"]) for r in rows(tmp_path / "plain" / "recording.csv")]
    doubled = [float(r["ctl.logic.speed"]) for r in rows(tmp_path / "doubled" / "recording.csv")]
    # The timer is armed at t = 0 in both runs (the bottle starts in the barrier), so the drive's
    # own speed is the same and only the system output differs, by the factor exactly.
    assert doubled == [2 * x for x in plain] and max(plain) > 0.3


# Each refusal: (what is changed in the archive, the message at scene.yaml:10: objects.ctl.file).
AT = "scene.yaml:10: objects.ctl.file: ctl.ssp: "
CONNECTION = '<ssd:Connection startElement="timer" startConnector="remaining" endElement="drive" endConnector="speed_setpoint"/>'


def test_a_file_that_is_no_zip_is_named(tmp_path, write_scenario):
    path = write_scenario(WITH_SSP)
    (tmp_path / "ctl.ssp").write_text("not a zip")
    assert problems(path) == [f"{AT}not an SSP (an SSP is a zip archive)"]


def test_an_archive_without_its_ssd_is_named(tmp_path, write_scenario):
    assert problems(scene(tmp_path, write_scenario, ssd=None)) == [
        f"{AT}no SystemStructure.ssd in the archive (an SSP describes its system there)"]


def test_an_ssd_that_does_not_validate_is_named_with_the_schemas_complaint(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace('name="go" kind="input"', 'name="go" kind="sideways"')
    found = problems(scene(tmp_path, write_scenario, ssd))
    assert found == [f"{AT}SystemStructure.ssd does not validate against the SSP 1.0 schema: line 6: Element "
                     f"'ssd:Connector', attribute 'kind': [facet 'enumeration'] The value 'sideways' is not an element "
                     f"of the set {{'input', 'output', 'parameter', 'calculatedParameter', 'inout'}}."]


def test_a_component_whose_fmu_is_not_in_the_archive_is_named(tmp_path, write_scenario):
    fmus = {"resources/timer.fmu": BUILT / "timer-fmi2.fmu"}
    assert problems(scene(tmp_path, write_scenario, fmus=fmus)) == [
        f"{AT}component 'drive': its FMU 'resources/belt_drive.fmu' is not in the archive"]


def test_a_nested_system_is_refused(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace("    </ssd:Elements>", '      <ssd:System name="inner"/>\n    </ssd:Elements>')
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}nested system 'inner': not supported (planthub runs one flat system of FMUs)"]


def test_a_component_that_is_no_fmu_is_refused(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace('<ssd:Component name="timer" source="resources/timer.fmu">',
                             '<ssd:Component name="timer" source="resources/timer.fmu" '
                             'type="application/x-ssp-definition">')
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}component 'timer' is 'application/x-ssp-definition', not an FMU: only FMU components "
        f"(application/x-fmu-sharedlibrary) are supported"]


def test_a_signal_dictionary_is_refused(tmp_path, write_scenario):
    dictionary = ('    <ssd:SignalDictionaries>\n      <ssd:SignalDictionary name="bus">'
                  '<ssb:SignalDictionary xmlns:ssb="http://ssp-standard.org/SSP1/SystemStructureSignalDictionary" '
                  'version="1.0"><ssb:DictionaryEntry name="x"><ssc:Real/></ssb:DictionaryEntry>'
                  '</ssb:SignalDictionary></ssd:SignalDictionary>\n    </ssd:SignalDictionaries>\n')
    ssd = TIMER_BELT.replace("  </ssd:System>", dictionary + "  </ssd:System>")
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}signal dictionary 'bus': signal dictionaries are not supported"]


def test_a_mapping_transformation_is_refused(tmp_path, write_scenario):
    mapped = ('<ssd:Connection startElement="timer" startConnector="elapsed" endConnector="done">'
              '<ssc:BooleanMappingTransformation><ssc:MapEntry source="true" target="false"/>'
              '<ssc:MapEntry source="false" target="true"/></ssc:BooleanMappingTransformation></ssd:Connection>')
    ssd = TIMER_BELT.replace('<ssd:Connection startElement="timer" startConnector="elapsed" endConnector="done"/>',
                             mapped)
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection timer.elapsed → system connector 'done': a BooleanMappingTransformation: not supported "
        f"(only a LinearTransformation between reals)"]


def test_a_linear_transformation_between_booleans_is_refused(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace('<ssd:Connection startConnector="go" endElement="drive" endConnector="run"/>',
                             '<ssd:Connection startConnector="go" endElement="drive" endConnector="run">'
                             '<ssc:LinearTransformation factor="2"/></ssd:Connection>')
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection system connector 'go' → drive.run: a LinearTransformation between bools: only between reals"]


def test_a_unit_conversion_is_refused(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace('<ssd:Connector name="speed" kind="output"><ssc:Real unit="m/s"/>',
                             '<ssd:Connector name="speed" kind="output"><ssc:Real unit="mm/s"/>', 1)
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection drive.speed → system connector 'speed': unit conversion from 'm/s' to 'mm/s': not "
        f"supported (give the connection a LinearTransformation and suppressUnitConversion=\"true\")"]


def test_a_connection_between_mismatched_types_is_named_with_both_ends(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace(CONNECTION, CONNECTION.replace('"remaining"', '"elapsed"'))
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection timer.elapsed → drive.speed_setpoint: type mismatch: timer.elapsed is bool but "
        f"drive.speed_setpoint is real"]


def test_a_connection_the_wrong_way_and_an_input_fed_twice_are_named(tmp_path, write_scenario):
    backwards = '<ssd:Connection startElement="drive" startConnector="run" endElement="timer" endConnector="start"/>'
    twice = '<ssd:Connection startElement="timer" startConnector="elapsed" endElement="drive" endConnector="run"/>'
    ssd = TIMER_BELT.replace(CONNECTION, CONNECTION + backwards + twice)
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection drive.run → timer.start: it starts at drive.run, an input of its FMU; a connection runs "
        f"from a system input or a component's output",
        f"{AT}connection timer.elapsed → drive.run: drive.run is fed already, by system connector 'go' "
        f"(one writer per input)"]


def test_a_connector_the_fmu_lacks_is_named_with_a_suggestion(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace('<ssd:Connector name="remaining" kind="output">',
                             '<ssd:Connector name="remainder" kind="output">')
    found = problems(scene(tmp_path, write_scenario, ssd))
    assert found[0] == (f"{AT}component 'timer': its connector 'remainder' is no variable of timer.fmu "
                        f"(did you mean 'remaining'?)")


def test_a_parameter_set_naming_an_unknown_variable_is_named(tmp_path, write_scenario):
    ssv = parameter_set({"timer.perod": ("Real", "0.4"), "timr.period": ("Real", "0.4")})
    assert problems(scene(tmp_path, write_scenario, ssv=ssv)) == [
        f"{AT}resources/tuning.ssv: parameter 'timer.perod': timer.fmu has no variable 'perod' that can be set "
        f"(did you mean 'period'?)",
        f"{AT}resources/tuning.ssv: parameter 'timr.period' names no component (a system's parameter is "
        f"component.variable) (did you mean 'timer'?)"]


def test_a_parameter_value_out_of_range_and_an_output_set_are_named(tmp_path, write_scenario):
    ssv = parameter_set({"timer.period": ("Real", "-1"), "drive.speed": ("Real", "1")})
    assert problems(scene(tmp_path, write_scenario, ssv=ssv)) == [
        f"{AT}resources/tuning.ssv: parameter 'timer.period': period is Real: -1.0 is outside its range 0 … ∞",
        f"{AT}resources/tuning.ssv: parameter 'drive.speed': speed cannot be set: it is an output: the FMU "
        f"computes it"]


def test_a_parameter_set_that_does_not_validate_is_named(tmp_path, write_scenario):
    ssv = TUNING.replace("<ssv:Real ", "<ssv:Rational ")
    assert problems(scene(tmp_path, write_scenario, ssv=ssv)) == [
        f"{AT}the parameter set 'resources/tuning.ssv' does not validate against the SSP 1.0 schema: line 4: Element "
        f"'ssv:Rational': This element is not expected. Expected is one of ( ssv:Real, ssv:Integer, ssv:Boolean, "
        f"ssv:String, ssv:Enumeration, ssv:Binary )."]


def test_a_connection_to_an_unknown_component_is_named(tmp_path, write_scenario):
    ssd = TIMER_BELT.replace(CONNECTION, CONNECTION.replace('endElement="drive"', 'endElement="drvie"'))
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        f"{AT}connection timer.remaining → drvie.speed_setpoint: no component 'drvie' (did you mean 'drive'?)"]


def test_a_parameter_set_missing_from_the_archive_is_named(tmp_path, write_scenario):
    assert problems(scene(tmp_path, write_scenario, ssv=None)) == [
        f"{AT}the parameter set 'resources/tuning.ssv' that a ParameterBinding names is not in the archive"]


def test_the_scenarios_parameters_are_checked_at_their_line(tmp_path, write_scenario):
    text = WITH_SSP.replace("    file: ctl.ssp\n", "    file: ctl.ssp\n    parameters:\n      timer.perod: 1\n"
                                                   "      belt.period: 1\n")
    assert problems(scene(tmp_path, write_scenario, text=text)) == [
        "scene.yaml:12: objects.ctl.parameters.timer.perod: timer.fmu has no variable 'perod' that can be set "
        "(did you mean 'period'?)",
        "scene.yaml:13: objects.ctl.parameters.belt.period: 'belt.period' is not component.variable of a component "
        "of ctl.ssp (known: drive, timer)"]


def test_gauss_seidel_is_refused_at_load(tmp_path, write_scenario):
    assert problems(scene(tmp_path, write_scenario), {"run.master": "gauss-seidel"}) == [
        f"{AT[:-9]}ctl.ssp runs its FMUs as run.master: jacobi does; under gauss-seidel the FMUs must be separate "
        f"`fmu` objects wired by flows"]


def test_the_fmus_are_extracted_to_the_scratch_folder_not_beside_the_scenario(tmp_path, write_scenario):
    from hub.core import scratch

    run_scenario(scene(tmp_path, write_scenario), tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ctl.ssp", "out", "scene.yaml"]
    assert list((scratch.folder() / "ssp").glob("*/0/timer.fmu"))


def test_the_readme_example_runs(tmp_path):
    """hub/logic/README.md's block under "A controller from an SSP", with timer_belt.ssp beside it."""
    readme = (ROOT / "hub" / "logic" / "README.md").read_text(encoding="utf-8")
    block = readme[readme.index("<!-- example: a controller from an SSP -->"):]
    block = block[block.index("```yaml\n") + 8:block.index("\n```", block.index("```yaml\n"))]
    write_ssp(tmp_path / "timer_belt.ssp")
    (tmp_path / "scene.yaml").write_text(block)
    run_scenario(tmp_path / "scene.yaml", tmp_path / "out")
    assert fired_at(tmp_path / "out") == 0.5


def test_an_unfed_component_input_keeps_the_start_its_parameter_set_gives(tmp_path, write_scenario):
    """drive.run fed by no connection but set true by the .ssv: the run of `go` wired to it."""
    run_scenario(scene(tmp_path, write_scenario), tmp_path / "wired")
    ssd = TIMER_BELT.replace('<ssd:Connection startConnector="go" endElement="drive" endConnector="run"/>', "")
    ssv = parameter_set({"timer.period": ("Real", "0.8"), "drive.run": ("Boolean", "true")})
    run_scenario(scene(tmp_path, write_scenario, ssd, ssv), tmp_path / "started")
    assert (tmp_path / "started" / "recording.csv").read_bytes() == (tmp_path / "wired" / "recording.csv").read_bytes()


def test_one_fmu_makes_two_components(tmp_path, write_scenario):
    """A second timer from the same resources/timer.fmu, started when the first fires."""
    later = ('      <ssd:Component name="later" source="resources/timer.fmu">\n        <ssd:Connectors>\n'
             '          <ssd:Connector name="start" kind="input"><ssc:Boolean/></ssd:Connector>\n'
             '          <ssd:Connector name="elapsed" kind="output"><ssc:Boolean/></ssd:Connector>\n'
             '        </ssd:Connectors>\n      </ssd:Component>\n')
    ssd = (TIMER_BELT.replace("    </ssd:Elements>", later + "    </ssd:Elements>")
           .replace('      <ssd:Connector name="done" kind="output"><ssc:Boolean/></ssd:Connector>\n',
                    '      <ssd:Connector name="done" kind="output"><ssc:Boolean/></ssd:Connector>\n'
                    '      <ssd:Connector name="later_done" kind="output"><ssc:Boolean/></ssd:Connector>\n')
           .replace("    </ssd:Connections>",
                    '      <ssd:Connection startElement="timer" startConnector="elapsed" endElement="later" '
                    'endConnector="start"/>\n      <ssd:Connection startElement="later" startConnector="elapsed" '
                    'endConnector="later_done"/>\n    </ssd:Connections>'))
    ssv = parameter_set({"timer.period": ("Real", "0.8"), "later.period": ("Real", "0.3")})
    text = WITH_SSP.replace("record: [", "record: [ctl.logic.later_done, ")
    run_scenario(scene(tmp_path, write_scenario, ssd, ssv, text), tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert fired_at(tmp_path / "out") == 0.8
    # The first timer's output of the point 0.8 s arms the second for its step from 0.8 s, as a
    # flow between two fmu objects would: it fires 0.3 s later.
    assert next(float(r["time"]) for r in data if r["ctl.logic.later_done"] == "1") == pytest.approx(1.1)


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """The test-only `faulty` model (tests/fmu_models/faulty): its `level` turns NaN at step `nan_at`."""
    return build(tmp_path_factory.mktemp("faulty"), models_dir=ROOT / "tests" / "fmu_models")


def test_a_nan_between_two_fmus_stops_the_run_naming_the_output(faulty, tmp_path, write_scenario):
    """No flow carries it, so the SSP checks it as a flow's source would be: faulty.level → drive.speed_setpoint."""
    ssd = (TIMER_BELT.replace('name="timer" source="resources/timer.fmu"', 'name="faulty" source="resources/faulty.fmu"')
           .replace('<ssd:Connector name="start" kind="input"><ssc:Boolean/></ssd:Connector>',
                    '<ssd:Connector name="fail" kind="input"><ssc:Boolean/></ssd:Connector>')
           .replace('<ssd:Connector name="elapsed" kind="output"><ssc:Boolean/></ssd:Connector>', "")
           .replace('<ssd:Connector name="remaining" kind="output"><ssc:Real unit="s"/></ssd:Connector>',
                    '<ssd:Connector name="level" kind="output"><ssc:Real/></ssd:Connector>')
           .replace('<ssd:Connection startConnector="blocked" endElement="timer" endConnector="start"/>', "")
           .replace('startElement="timer" startConnector="remaining"', 'startElement="faulty" startConnector="level"')
           .replace('<ssd:Connection startElement="timer" startConnector="elapsed" endConnector="done"/>', "")
           .replace('<ssd:Connector name="done" kind="output"><ssc:Boolean/></ssd:Connector>', ""))
    fmus = {"resources/faulty.fmu": faulty / "faulty-fmi2.fmu",
            "resources/belt_drive.fmu": BUILT / "belt_drive-fmi2.fmu"}
    text = WITH_SSP.replace("ctl.logic.done, ", "")
    path = scene(tmp_path, write_scenario, ssd, parameter_set({"faulty.nan_at": ("Integer", "4")}), text, fmus=fmus)
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == ("SSP instance 'ctl': connection faulty.level → drive.speed_setpoint carries nan at "
                               "t = 0.08 s; a non-finite value is not passed on to an FMU, so the run stops here")


def test_a_transformation_that_is_not_finite_is_named_at_load(tmp_path, write_scenario):
    """factor="NaN" is a legal xs:double; passed on it would feed NaN to the drive at every step."""
    ssd = TIMER_BELT.replace(CONNECTION, CONNECTION[:-2] + '><ssc:LinearTransformation factor="NaN"/></ssd:Connection>')
    assert problems(scene(tmp_path, write_scenario, ssd)) == [
        AT + "connection timer.remaining → drive.speed_setpoint: its LinearTransformation's factor and offset must be "
             "finite (factor nan, offset 0.0)"]


TANK = """\
  <ssd:System name="filler">
    <ssd:Connectors>
      <ssd:Connector name="inflow" kind="input"><ssc:Real/></ssd:Connector>
      <ssd:Connector name="level" kind="output"><ssc:Real/></ssd:Connector>
      <ssd:Connector name="full" kind="output"><ssc:Boolean/></ssd:Connector>
    </ssd:Connectors>
    <ssd:Elements>
      <ssd:Component name="tank" source="resources/tank3.fmu">
        <ssd:Connectors>
          <ssd:Connector name="inflow" kind="input"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="level" kind="output"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="full" kind="output"><ssc:Boolean/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startConnector="inflow" endElement="tank" endConnector="inflow"/>
      <ssd:Connection startElement="tank" startConnector="level" endConnector="level"/>
      <ssd:Connection startElement="tank" startConnector="full" endConnector="full"/>
    </ssd:Connections>
  </ssd:System>
</ssd:SystemStructureDescription>
"""


def test_a_model_exchange_component_is_integrated_as_an_fmu_object_would_be(tmp_path, write_scenario):
    """tank3 (FMI 3, model exchange only) inside an SSP: the level and `full` recorded byte for byte as
    the same FMU as an `fmu` object records them (CVODE with its defaults in both)."""
    from .foreign_fmus import build as build_foreign

    tank = build_foreign("tank3", 3, tmp_path / "foreign")
    write_ssp(tmp_path / "filler.ssp", HEAD + TANK, None, fmus={"resources/tank3.fmu": tank})
    common = """\
        planthub: 1
        run: {duration: 4.0, physics_rate: 100, communication_step: 0.02}
        objects:
          inflow: {module: constant, type: real, value: 0.1}
          %s
        flows:
          - {from: inflow.value.out, to: %s.logic.inflow, when: target}
        record: [%s.logic.level, %s.logic.full]
        """
    in_ssp = write_scenario(common % ("tank: {module: ssp, file: filler.ssp}", "tank", "tank", "tank"), "ssp.yaml")
    alone = write_scenario(common % (f"tank: {{module: fmu, file: {tank}}}", "tank", "tank", "tank"), "fmu.yaml")
    run_scenario(in_ssp, tmp_path / "ssp")
    run_scenario(alone, tmp_path / "fmu")
    recorded = (tmp_path / "ssp" / "recording.csv").read_bytes()
    assert recorded == (tmp_path / "fmu" / "recording.csv").read_bytes()
    assert b",1\n" in recorded   # the tank filled within the run: the state event was integrated to
    # A model-exchange component takes any step the hub gives it: an event-driven run is not refused.
    load_scenario(in_ssp, {"run.event_driven": True})

