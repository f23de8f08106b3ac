"""Any FMU a user brings: every FMI type mapped to slots, start values kept, `parameters:` as FMI means them.

The FMUs stand in for other exporters' (tests/fmu_models/foreign, hand-written C against the FMI
headers): `enum2` (FMI 2.0) has an Enumeration input whose legal values are 1..3, start 1;
`typed3` (FMI 3.0) has Enumeration, Float32, UInt16, Int64, Int8 and Binary variables, arrays and a
structural parameter.
"""
import csv
from math import copysign

import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.logic.fmi import FmuSlave, inspect_fmu
from hub.scenario.checker import load_scenario

from .foreign_fmus import build
from .helpers import run_scenario


@pytest.fixture(scope="module")
def foreign(tmp_path_factory):
    out = tmp_path_factory.mktemp("foreign")
    return {"enum2": build("enum2", 2, out), "typed3": build("typed3", 3, out)}


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def problems(path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p) for p in info.value.problems]


def scene(write_scenario, fmu, extra="", objects="", flows="", record="t.logic.level"):
    return write_scenario(f"""
        planthub: 1
        run: {{duration: 0.3, physics_rate: 100, communication_step: 0.1}}
        objects:
          t: {{module: fmu, file: {fmu}{extra}}}
          {objects}
        flows: [{flows}]
        record: [{record}]
        """)


@pytest.mark.parametrize("extra, level", [("", "10"), (", parameters: {mode: fast}", "20"),
                                          (", parameters: {mode: 3}", "30")])
def test_an_unconnected_enumeration_input_keeps_its_start_value(foreign, write_scenario, tmp_path, extra, level):
    """enum2.mode (Enumeration 1..3, start 1) fed by nothing: the hub writes 1, not 0, so the FMU runs;
    `parameters:` sets the input by value or by item name, and the slot holds that value."""
    path = scene(write_scenario, foreign["enum2"], extra, record="t.logic.mode, t.logic.level")
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert data[0]["t.logic.mode"] == str(int(level) // 10)
    assert [r["t.logic.level"] for r in data[1:]] == [level] * (len(data) - 1)


def test_an_enumeration_fed_an_illegal_value_is_named(foreign, write_scenario, tmp_path):
    path = scene(write_scenario, foreign["enum2"], objects="zero: {module: constant, type: int, value: 0}",
                 flows="{from: zero.value.out, to: t.logic.mode, when: target}")
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == ("FMU instance 't' (enum2.fmu) at t = 0 s: set inputs failed: input 'mode' "
                               "(Enumeration): 0 is not one of its items (slow=1, fast=2, stop=3)")


TYPED = """, parameters: {A: [[2, 0], [0, 1]], gain32: 0.5}"""
TYPED_OBJECTS = """
          x: {module: constant, type: real, value: 3.0}
          c: {module: constant, type: int, value: 300}
          big: {module: constant, type: int, value: 1099511627776}
          hex: {module: constant, type: string, value: 0a0B0c}
          u0: {module: constant, type: real, value: 4.0}"""
TYPED_FLOWS = """
          {from: x.value.out, to: t.logic.x32, when: target},
          {from: c.value.out, to: t.logic.count16, when: target},
          {from: big.value.out, to: t.logic.big64, when: target},
          {from: hex.value.out, to: t.logic.blob, when: target},
          {from: u0.value.out, to: t.logic.u_0, when: target}"""
TYPED_RECORD = "t.logic.y32, t.logic.big64_out, t.logic.level8, t.logic.blob_out, t.logic.v_0, t.logic.v_1, t.logic.u_1"


def typed_scene(write_scenario, foreign, extra=""):
    return scene(write_scenario, foreign["typed3"], TYPED + extra, TYPED_OBJECTS, TYPED_FLOWS, TYPED_RECORD)


def test_every_fmi3_type_maps_to_a_slot(foreign, write_scenario, tmp_path):
    """Float32 → real, UInt16 / Int64 / Int8 / Enumeration → int, Binary → hex string, arrays → element slots
    (u_1 and u_2 fed by nothing keep their starts 2 and 3; A set whole, as a nested list)."""
    path = typed_scene(write_scenario, foreign)
    scenario = load_scenario(path)
    slots = {s.name: s.type.value for s in scenario.objects[0].module.slots(scenario.objects[0].params)["logic"]}
    assert slots == {"mode": "int", "x32": "real", "count16": "int", "big64": "int", "blob": "string",
                     "u_0": "real", "u_1": "real", "u_2": "real", "y32": "real", "big64_out": "int",
                     "level8": "int", "blob_out": "string", "v_0": "real", "v_1": "real", "twice64": "int"}
    run_scenario(path, tmp_path / "out")
    last = rows(tmp_path / "out" / "recording.csv")[-1]
    assert last["t.logic.y32"] == "1.5"                              # 0.5 * 3 in Float32
    assert last["t.logic.big64_out"] == str(2**40 + 300 * 1)         # big64 + count16 * mode (start 1)
    assert last["t.logic.level8"] == "-10"                           # -10 * mode
    assert last["t.logic.blob_out"] == "0c0b0a"                      # the bytes reversed, as lower-case hex
    assert last["t.logic.u_1"] == "2.0"
    assert (last["t.logic.v_0"], last["t.logic.v_1"]) == ("11.0", "5.0")   # A · (4, 2) + 3


def test_an_array_element_can_be_set_alone(foreign, write_scenario, tmp_path):
    """parameters: {A_1_1: 3}: the other elements keep their starts (an array is written whole)."""
    path = scene(write_scenario, foreign["typed3"], ", parameters: {A_1_1: 3}", record="t.logic.v_0, t.logic.v_1")
    run_scenario(path, tmp_path / "out")
    last = rows(tmp_path / "out" / "recording.csv")[-1]
    assert (last["t.logic.v_0"], last["t.logic.v_1"]) == ("4.0", "9.0")   # (1 0; 0 3) · (1, 2) + 3


@pytest.mark.parametrize("isolate", ["runs: child", "runs: bus"])
def test_typed_values_cross_a_pipe_and_the_bus_bit_for_bit(foreign, write_scenario, tmp_path, isolate):
    run_scenario(typed_scene(write_scenario, foreign), tmp_path / "hub")
    run_scenario(typed_scene(write_scenario, foreign, ", " + isolate), tmp_path / "other")
    assert (tmp_path / "hub" / "recording.csv").read_bytes() == (tmp_path / "other" / "recording.csv").read_bytes()


@pytest.mark.parametrize("constant, slot, message", [
    ("{module: constant, type: int, value: 70000}", "count16",
     "input 'count16' (UInt16): 70000 is outside its range 0 … 65535"),
    ("{module: constant, type: int, value: -1}", "count16",
     "input 'count16' (UInt16): -1 is outside its range 0 … 65535"),
    ("{module: constant, type: string, value: xyz}", "blob",
     "input 'blob' (Binary): a Binary is written as hex digits, two a byte (e.g. '0a1b'), got 'xyz'"),
    ("{module: constant, type: int, value: 4}", "mode",
     "input 'mode' (Enumeration): 4 is not one of its items (slow=1, fast=2, stop=3)"),
])
def test_a_value_out_of_its_range_is_named_when_written(foreign, write_scenario, tmp_path, constant, slot, message):
    path = scene(write_scenario, foreign["typed3"], objects=f"bad: {constant}",
                 flows=f"{{from: bad.value.out, to: t.logic.{slot}, when: target}}", record="t.logic.y32")
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == f"FMU instance 't' (typed3.fmu) at t = 0 s: set inputs failed: {message}"


def test_bad_parameters_are_named_at_their_lines(foreign, write_scenario):
    path = write_scenario(f"""
        planthub: 1
        objects:
          t:
            module: fmu
            file: {foreign['typed3']}
            parameters:
              modee: 2
              gain32: fast
              limit16: 60000
              mode: 7
              blob: xyz
              level8: 1
              time: 0.5
              n: 4
              A: [1, 2]
              count16: turbo
        """)
    # Each problem at its own key's line (the first is line 7).
    found = [p.replace(f"{path}:", "", 1) for p in problems(path)]
    assert [int(p.split(":")[0]) for p in found] == list(range(7, 17))
    assert [p.split(": objects.t.parameters.", 1)[1] for p in found] == [
        "modee: typed3.fmu has no variable 'modee' that can be set (did you mean 'mode'?)",
        "gain32: gain32 is Float32: expected a finite number, got 'fast'",
        "limit16: limit16 is UInt16: 60000 is outside its range 0 … 50000",
        "mode: mode is Enumeration: 7 is not one of its items (slow=1, fast=2, stop=3)",
        "blob: blob is Binary: a Binary is written as hex digits, two a byte (e.g. '0a1b'), got 'xyz'",
        "level8: level8 cannot be set: it is an output: the FMU computes it",
        "time: time cannot be set: it is the independent variable (time)",
        "n: n is not mapped: a structural parameter (it sizes u): planthub keeps its start value 3",
        "A: A has 4 elements, got 2 values",
        "count16: count16 is UInt16: expected an integer, got 'turbo'",
    ]


def test_an_enumeration_item_name_gets_a_did_you_mean(foreign, write_scenario):
    path = scene(write_scenario, foreign["enum2"], ", parameters: {mode: fats, threshold: 101}")
    assert problems(path) == [
        f"{path}:4: objects.t.parameters.mode: mode is Enumeration: 'fats' is not one of its items "
        f"(slow=1, fast=2, stop=3) (did you mean 'fast'?)",
        f"{path}:4: objects.t.parameters.threshold: threshold is Integer: 101 is outside its range 0 … 100",
    ]


def test_a_uint64_output_beyond_an_int_slot_is_named(foreign, write_scenario, tmp_path):
    """twice64 = 2 · big64 in UInt64 arithmetic: big64 = -1 gives 2^64 − 2, more than an int slot's signed 64 bits."""
    path = scene(write_scenario, foreign["typed3"], objects="big: {module: constant, type: int, value: -1}",
                 flows="{from: big.value.out, to: t.logic.big64, when: target}", record="t.logic.twice64")
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == ("FMU instance 't' (typed3.fmu) at t = 0.1 s: get outputs failed: output 'twice64' "
                               "(UInt64) is 18446744073709551614, above 9223372036854775807, the largest value an "
                               "int slot carries")


def test_the_readme_example_runs_as_it_says(foreign, tmp_path):
    """hub/logic/README.md's "Bringing your own FMU" example, run on the FMU the tests built."""
    from .helpers import ROOT

    readme = (ROOT / "hub" / "logic" / "README.md").read_text(encoding="utf-8")
    block = readme[readme.index("<!-- example: bringing your own FMU -->"):]
    block = block[block.index("```yaml\n") + 8:block.index("\n```", block.index("```yaml\n"))]
    assert "file: ../build/foreign/typed3.fmu" in block
    (tmp_path / "scenarios").mkdir()
    path = tmp_path / "scenarios" / "byo.yaml"
    path.write_text(block.replace("../build/foreign/typed3.fmu", str(foreign["typed3"])))
    run_scenario(path, tmp_path / "out")
    for row in rows(tmp_path / "out" / "recording.csv")[1:]:
        assert (row["ctl.logic.y32"], row["ctl.logic.level8"], row["ctl.logic.blob_out"], row["ctl.logic.v_0"],
                row["ctl.logic.v_1"]) == ("1.5", "-20", "0c0b0a", "5.0", "5.0")


def test_a_real_beyond_float32_is_named_when_written(foreign, write_scenario, tmp_path):
    """a.v_0 = 9e15 · 9e15 feeds b.u_0, so b.v_0 = 9e15 · 8.1e31 ≈ 7.3e47 reaches c.x32, a Float32 (at most
    3.4e38): the write is refused naming the variable, rather than an inf reaching the FMU."""
    big = ", parameters: {A: [[9.0e15, 0], [0, 1]], u_0: 9.0e15}"
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 0.5, physics_rate: 100, communication_step: 0.1}}
        objects:
          a: {{module: fmu, file: {foreign['typed3']}{big}}}
          b: {{module: fmu, file: {foreign['typed3']}, parameters: {{A: [[9.0e15, 0], [0, 1]]}}}}
          c: {{module: fmu, file: {foreign['typed3']}}}
        flows:
          - {{from: a.logic.v_0, to: b.logic.u_0}}
          - {{from: b.logic.v_0, to: c.logic.x32}}
        record: [c.logic.y32]
        """)
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    message = str(info.value)
    assert message.startswith("FMU instance 'c' (typed3.fmu) at t = 0.2 s: set inputs failed: input 'x32' (Float32): ")
    assert message.endswith(" is outside its range -3.40282e+38 … 3.40282e+38")


def test_inputs_set_again_unchanged_are_held_and_a_zero_changing_sign_is_written(foreign):
    """The adapter does not write inputs the FMU already holds, bit for bit: the FMU steps on them
    as set; 0.0 and −0.0 compare equal but are not the same input, and the FMU sees the change."""
    slave = FmuSlave(inspect_fmu(foreign["typed3"]), "t", ["x32"], ["y32"], {})
    written, write = [], slave._in.set   # what reaches the FMU's setters
    slave._in.set = lambda values: (written.append(values[0]), write(values))
    try:
        t = 0.0
        for x in (2.0, 2.0, 0.0, -0.0, -0.0, 0.0, 4.0, 4.0):
            slave.set_inputs([x])
            slave.step(t, 0.1)
            t += 0.1
            y = slave.outputs()[0]
            assert (y, copysign(1.0, y)) == (1.5 * x, copysign(1.0, x)), f"x32 = {x!r} gave y32 = {y!r}"
        assert [(v, copysign(1.0, v)) for v in written] == [(2.0, 1.0), (0.0, 1.0), (0.0, -1.0), (0.0, 1.0),
                                                            (4.0, 1.0)]
    finally:
        slave.close()
