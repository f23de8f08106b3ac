"""The `convert` module: each conversion's values, worked out here another way; an FMU's Int32 counter
driving a belt through it; every bad parameter named at its line.

    card.logic.counter (int, stair FMU) ──► speed.value.in ; speed.value.out (real, m/s) ──► belt.drive.speed
    belt.drive.velocity ──► raw.value.in (real → int counts) ; ──► fast.value.in (real → bool)
"""
import csv
import math
from decimal import ROUND_CEILING, ROUND_DOWN, ROUND_FLOOR, ROUND_HALF_EVEN, ROUND_HALF_UP, Decimal
from fractions import Fraction

import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.core.signals import Signals
from hub.scenario.checker import load_scenario
from modules.convert import Convert, Converter, conversion

from .foreign_fmus import build
from .helpers import ROOT, run_scenario

FULL = 27648   # a PLC analogue card's nominal full scale, in raw counts


@pytest.fixture(scope="module")
def stair(tmp_path_factory):
    return build("stair", 3, tmp_path_factory.mktemp("foreign"))


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def convert(**params):
    return conversion({"from": "real", "to": "real", **params})


# --- each conversion ------------------------------------------------------------------------

DECIMAL_RULE = {"nearest": ROUND_HALF_UP, "half_even": ROUND_HALF_EVEN, "down": ROUND_FLOOR,
                "up": ROUND_CEILING, "toward_zero": ROUND_DOWN}
TRICKY = [2.5, -2.5, 3.5, -3.5, 2.4999999999999996, 0.49999999999999994, -0.5, 0.5, 1.0, -7.0, 1e15 + 0.5,
          -0.0, 123.75, -123.25]


@pytest.mark.parametrize("rule", DECIMAL_RULE)
def test_real_to_int_rounds_by_its_rule(rule):
    """Decimal's rounding of the double's exact value (ROUND_HALF_UP is ties away from zero) against the module's."""
    to_int = convert(to="int", round=rule)
    for x in TRICKY:
        expected = int(Decimal(x).quantize(Decimal(1), rounding=DECIMAL_RULE[rule]))
        assert to_int(x) == expected and type(to_int(x)) is int, (rule, x)


def test_nearest_is_the_default_and_rounds_ties_away_from_zero():
    to_int = convert(to="int")
    assert [to_int(x) for x in (2.5, -2.5, 0.49999999999999994, 1.5, -1.5)] == [3, -3, 0, 2, -2]


def test_a_real_beyond_a_64_bit_int_is_named():
    with pytest.raises(ValueError) as info:
        convert(to="int")(1e19)
    assert str(info.value) == "1e+19 rounds to 10000000000000000000, beyond a 64-bit int slot"


def test_int_to_real_is_the_same_number():
    to_real = conversion({"from": "int", "to": "real"})
    assert [(to_real(n), type(to_real(n))) for n in (0, -3, FULL)] == [(0.0, float), (-3.0, float), (27648.0, float)]
    assert to_real(2**53 + 1) == float(2**53)   # the nearest double, as documented


def test_bool_to_numbers_by_levels():
    assert [conversion({"from": "bool", "to": "real"})(b) for b in (False, True)] == [0.0, 1.0]
    assert [conversion({"from": "bool", "to": "real", "levels": [4, 20]})(b) for b in (False, True)] == [4.0, 20.0]
    to_int = conversion({"from": "bool", "to": "int", "levels": [0, FULL]})
    assert [(to_int(b), type(to_int(b))) for b in (False, True)] == [(0, int), (FULL, int)]


def test_int_to_bool_is_true_for_any_value_but_zero():
    to_bool = conversion({"from": "int", "to": "bool"})
    assert [to_bool(n) for n in (0, 1, -3, 2**63 - 1)] == [False, True, True, True]


def test_a_threshold_with_hysteresis_keeps_its_state_inside_the_band():
    """On above 0.5, off at or below 0.5 − 0.25 = 0.25; in between the state stays."""
    switch = convert(to="bool", threshold=0.5, hysteresis=0.25)
    inputs = [0.0, 0.5, 0.5000001, 0.3, 0.26, 0.25, 0.3, 0.49, 0.6, -1.0]
    assert [switch(x) for x in inputs] == [False, False, True, True, True, False, False, False, True, False]


def test_a_threshold_without_hysteresis_is_a_plain_comparison():
    switch = convert(to="bool", threshold=0.5)
    assert [switch(x) for x in (0.5, 0.5000001, 0.5, 0.7, -2.0)] == [False, True, False, True, False]


def scaled(x, a, b, c, d):
    """The linear map a → c, b → d as an exact fraction, x clamped into a … b first."""
    x = min(max(Fraction(x), Fraction(min(a, b))), Fraction(max(a, b)))
    return Fraction(c) + (x - Fraction(a)) * (Fraction(d) - Fraction(c)) / (Fraction(b) - Fraction(a))


def test_raw_counts_scale_to_engineering_units_clamped():
    speed = conversion({"from": "int", "to": "real", "scale": {"from": [0, FULL], "to": [0.0, 0.5]}})
    for raw in (0, 1, 6912, 13824, 20000, FULL, -100, 30000, 32767):
        assert speed(raw) == float(scaled(raw, 0, FULL, 0.0, 0.5)), raw
    assert [speed(raw) for raw in (-100, 30000)] == [0.0, 0.5]   # clamped at the ends


def test_engineering_units_scale_to_raw_counts_rounded():
    raw = conversion({"from": "real", "to": "int", "scale": {"from": [0.0, 0.5], "to": [0, FULL]}})
    for speed in (0.0, 0.125, 0.2, 0.3333, 0.5, 0.6, -0.1):
        exact = scaled(speed, 0.0, 0.5, 0, FULL)
        assert raw(speed) == round_half_up(exact), speed


def round_half_up(q: Fraction) -> int:
    whole = math.floor(abs(q) + Fraction(1, 2))
    return whole if q >= 0 else -whole


def test_a_live_zero_range_and_reversed_ranges():
    """4…20 mA on a card (5530 … 27648 raw) to 0 … 100 %, and a reversed output range (a valve closing)."""
    level = conversion({"from": "int", "to": "real", "scale": {"from": [5530, FULL], "to": [0, 100]}})
    for raw in (5530, 10000, 16589, FULL, 0):
        assert level(raw) == pytest.approx(float(scaled(raw, 5530, FULL, 0, 100)), rel=1e-15, abs=1e-13)
    closing = conversion({"from": "real", "to": "real", "scale": {"from": [0, 1], "to": [100, 0]}})
    assert [closing(x) for x in (0, 0.25, 1, 2)] == [100.0, 75.0, 0.0, 0.0]


def test_scaled_int_to_int_rounds_after_scaling():
    half = {"from": "int", "to": "int", "scale": {"from": [0, 10], "to": [0, 5]}}
    assert [conversion(half)(n) for n in (3, 5, 7, 10)] == [2, 3, 4, 5]         # 1.5, 2.5, 3.5: away from zero
    assert [conversion({**half, "round": "half_even"})(n) for n in (3, 5, 7)] == [2, 2, 4]


def test_out_of_range_stop_names_the_value():
    stop = conversion({"from": "int", "to": "real", "scale": {"from": [0, FULL], "to": [0.0, 0.5]},
                       "out_of_range": "stop"})
    assert stop(FULL) == 0.5
    with pytest.raises(ValueError) as info:
        stop(FULL + 1)
    assert str(info.value) == "27649 is outside scale.from 0 … 27648 (out_of_range: stop)"


def test_a_non_finite_real_entering_stops_naming_slot_value_and_time():
    """The component on the plant's own state object: a NaN written to its input, as a flow would."""
    params = {"from": "real", "to": "int", "scale": {"from": [0.0, 0.5], "to": [0, FULL]}}
    slots = Convert.slots(params)["value"]
    comp = Converter("card", "value", slots, conversion(params), 0, True, 100)
    signals = Signals(list(slots))
    comp.bind(signals, {"in": 0, "out": 1}, frozenset({"out"}))
    comp.sense(150)
    for bad in (math.nan, math.inf):
        signals.values[0], signals.updated[0] = bad, True
        with pytest.raises(SimulationError) as info:
            comp.react()
        assert str(info.value) == (f"card.value.in: got {bad!r}; every value entering the plant must be finite, "
                                   "so the run stops here (at t = 1.5 s, tick 150)")
    signals.values[0] = 0.25
    comp.react()
    assert (signals.values[1], signals.active[1]) == (13824, True)


# --- an FMU's counter drives a belt ------------------------------------------------------------

BELT = """
    planthub: 1
    run: {{duration: 2.4, physics_rate: 100, communication_step: 0.1}}
    objects:
      card:   {{module: fmu, file: {fmu}, parameters: {{period: 0.2, increment: 3456}}}}
      speed:  {{module: convert, from: int, to: real, scale: {{from: [0, 27648], to: [0.0, 0.5]}}{extra}}}
      raw:    {{module: convert, from: real, to: int, scale: {{from: [0.0, 0.5], to: [0, 27648]}}}}
      fast:   {{module: convert, from: real, to: bool, threshold: 0.3, hysteresis: 0.1}}
      belt:   {{module: conveyor, position: [0, 0, 0], length: 3.0, speed: 0.0, k: 16}}
      bottle: {{module: bottle, position: [0.1, 0, 0]}}
    flows:
      - {{from: card.logic.counter, to: speed.value.in}}
      - {{from: speed.value.out, to: belt.drive.speed}}
      - {{from: belt.drive.velocity, to: raw.value.in}}
      - {{from: belt.drive.velocity, to: fast.value.in}}
    record: [card.logic.counter, belt.drive.speed, belt.drive.velocity, raw.value.out, fast.value.out,
             bottle.body.position, bottle.body.velocity]
    """


def test_an_fmu_counter_drives_the_belt_speed_through_the_conversion(stair, write_scenario, tmp_path):
    """The stair FMU counts 3456 raw counts every 0.2 s; the belt runs at counter · 0.5 / 27648 m/s from the very
    point the counter is read (no delay through convert), clamped at 0.5 once the counter passes 27648; the
    bottle follows the belt's law dv/dt = k (v_belt − v), k = 16/s, within 1 µm and 1 µm/s."""
    run_scenario(write_scenario(BELT.format(fmu=stair, extra="")), tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    times = [round(float(r["time"]) * 10) for r in data]          # points, in communication steps
    assert times == list(range(25))
    counters = [int(r["card.logic.counter"]) for r in data]
    assert counters == [3456 * (n // 2) for n in times]          # a count at every whole 0.2 s
    speeds = [float(r["belt.drive.speed"]) for r in data]
    assert speeds == [float(min(Fraction(c, FULL) / 2, Fraction(1, 2))) for c in counters]
    assert speeds[16:] == [0.5] * 9 and counters[-1] > FULL     # clamped beyond full scale
    # The belt drives at the speed set at the point before (a source shows the world as sensed).
    velocities = [float(r["belt.drive.velocity"]) for r in data]
    assert velocities == [0.0] + speeds[:-1]
    # The output card's reading back: the velocity in raw counts, and a switch above 0.3 m/s.
    assert [int(r["raw.value.out"]) for r in data] == [round(v / 0.5 * FULL) for v in velocities]
    assert [r["fast.value.out"] for r in data] == [str(int(v > 0.3)) for v in velocities]

    # Per physics tick (100 Hz): the belt law's exact velocity update, then the engine's position step x += v·dt.
    k, dt, x, v = 16.0, 0.01, 0.0, 0.0
    for n, row in enumerate(data):
        assert float(row["bottle.body.velocity.x"]) == pytest.approx(v, abs=1e-6), n
        assert float(row["bottle.body.position.x"]) - 0.1 == pytest.approx(x, abs=1e-6), n
        for _ in range(10):   # the speed set at this point drives the step that follows
            v = speeds[n] + (v - speeds[n]) * math.exp(-k * dt)
            x += v * dt
    assert float(data[-1]["bottle.body.position.x"]) - 0.1 > 0.7   # it travelled with the belt


def test_out_of_range_stop_ends_the_run_at_the_count_beyond_full_scale(stair, write_scenario, tmp_path):
    path = write_scenario(BELT.format(fmu=stair, extra=", out_of_range: stop"))
    with pytest.raises(SimulationError) as info:
        run_scenario(path, tmp_path / "out")
    assert str(info.value) == ("speed.value.in: 31104 is outside scale.from 0 … 27648 (out_of_range: stop), "
                               "so the run stops here (at t = 1.8 s, tick 180)")


def test_a_pulled_output_holds_the_conversion_of_zero_from_the_start(write_scenario, tmp_path):
    """Nothing feeds `in`: a flow that pulls `out` gets the scale's value for 0 (4 mA on a 4…20 mA range)."""
    path = write_scenario("""
        planthub: 1
        run: {duration: 0.2, physics_rate: 100, communication_step: 0.1}
        objects:
          ma: {module: convert, from: int, to: real, scale: {from: [5530, 27648], to: [4, 20]}}
          belt: {module: conveyor, position: [0, 0, 0], length: 1.0, speed: 0.0}
        flows: [{from: ma.value.out, to: belt.drive.speed, when: target}]
        record: [belt.drive.speed, ma.value.out]
        """)
    run_scenario(path, tmp_path / "out")
    assert {(r["belt.drive.speed"], r["ma.value.out"]) for r in rows(tmp_path / "out" / "recording.csv")} \
        == {("4.0", "4.0")}


def test_the_readme_example_runs_as_it_says(stair, tmp_path):
    """hub/logic/README.md's "Conversions (`convert`)" example, run on the stair FMU the tests built."""
    readme = (ROOT / "hub" / "logic" / "README.md").read_text(encoding="utf-8")
    block = readme[readme.index("<!-- example: conversions -->"):]
    block = block[block.index("```yaml\n") + 8:block.index("\n```", block.index("```yaml\n"))]
    assert "file: ../build/foreign/stair.fmu" in block
    (tmp_path / "scenarios").mkdir()
    path = tmp_path / "scenarios" / "convert.yaml"
    path.write_text(block.replace("../build/foreign/stair.fmu", str(stair)))
    run_scenario(path, tmp_path / "out")
    data = rows(tmp_path / "out" / "recording.csv")
    assert [(r["card.logic.counter"], r["belt.drive.speed"]) for r in data[:5]] == [
        ("0", "0.0"), ("0", "0.0"), ("3456", "0.0625"), ("3456", "0.0625"), ("6912", "0.125")]


# --- bad parameters, each named at its line ---------------------------------------------------

def problems(write_scenario, *lines):
    """The problems of a scenario whose object `c` (a convert, line 4 on) has these parameter lines."""
    body = "\n".join(f"    {line}" for line in lines)
    path = write_scenario(f"planthub: 1\nobjects:\n  c:\n    module: convert\n{body}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p).replace(f"{path}:", "") for p in info.value.problems]


@pytest.mark.parametrize("lines, expected", [
    (["from: int", "to: int"],
     "6: objects.c.to: from and to are both int and there is no scale: nothing to convert (connect the slots directly)"),
    (["from: bool", "to: bool"],
     "6: objects.c.to: from and to are both bool and there is no scale: nothing to convert (connect the slots directly)"),
    (["from: bool", "to: real", "scale: {from: [0, 1], to: [0, 5]}"],
     "7: objects.c.scale: bool → real: a bool has no range to scale; bool → int or real takes `levels`, "
     "real → bool a `threshold`"),
    (["from: int", "to: real", "scale:", "  from: [27648, 27648]", "  to: [0, 0.5]"],
     "8: objects.c.scale.from: a range of zero width (27648 … 27648): no slope maps it"),
    (["from: int", "to: real", "scale:", "  from: [0, 27648]", "  to: [0.5, 0.5]"],
     "9: objects.c.scale.to: a range of zero width (0.5 … 0.5): every value would give 0.5"),
    (["from: int", "to: real", "out_of_range: stop"],
     "7: objects.c.out_of_range: out_of_range is for a scale, and there is none"),
    (["from: int", "to: real", "round: down"],
     "7: objects.c.round: round is for a number converted to int, not int → real"),
    (["from: bool", "to: int", "round: down"],
     "7: objects.c.round: round is for a number converted to int, not bool → int"),
    (["from: int", "to: real", "threshold: 0.5"],
     "7: objects.c.threshold: a threshold is for real → bool, not int → real"),
    (["from: int", "to: bool", "threshold: 5"],
     "7: objects.c.threshold: a threshold is for real → bool, not int → bool (int → bool is true for any value but 0)"),
    (["from: int", "to: real", "hysteresis: 0.1"],
     "7: objects.c.hysteresis: hysteresis goes with a threshold, for real → bool, not int → real"),
    (["from: real", "to: bool"],
     "3: objects.c: real → bool needs a threshold: true above it"),
    (["from: real", "to: bool", "hysteresis: 0.1"],
     "3: objects.c: real → bool needs a threshold: true above it"),
    (["from: int", "to: real", "levels: [4, 20]"],
     "7: objects.c.levels: levels are the values of false and true, for bool → int or real, not int → real"),
    (["from: bool", "to: int", "levels: [0, 0.5]"],
     "7: objects.c.levels: bool → int needs whole numbers, got [0, 0.5]"),
    (["from: float", "to: real"],
     "5: objects.c.from: 'float' is not one of ['bool', 'int', 'real']"),
    (["from: real", "to: bool", "threshold: 0.5", "hysteresis: -0.1"],
     "8: objects.c.hysteresis: -0.1 is less than the minimum of 0"),
])
def test_a_bad_parameter_is_named_at_its_line(write_scenario, lines, expected):
    assert problems(write_scenario, *lines) == [expected]


def test_every_problem_of_one_object_is_reported_at_once(write_scenario):
    found = problems(write_scenario, "from: int", "to: real", "threshold: 1", "round: up", "levels: [0, 1]")
    assert found == ["8: objects.c.round: round is for a number converted to int, not int → real",
                     "7: objects.c.threshold: a threshold is for real → bool, not int → real",
                     "9: objects.c.levels: levels are the values of false and true, for bool → int or real, "
                     "not int → real"]


def test_its_slots_are_checked_like_any_flow(write_scenario):
    """A converted real into a bool target, and a ring of two converters (a zero-delay loop)."""
    path = write_scenario("""
        planthub: 1
        objects:
          b: {module: convert, from: int, to: real}
          c: {module: convert, from: real, to: int}
          belt: {module: conveyor, position: [0, 0, 0], length: 1}
        flows:
          - {from: b.value.out, to: c.value.in}
          - {from: c.value.out, to: b.value.in}
          - {from: b.value.out, to: belt.drive.run}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [str(p) for p in info.value.problems] == [
        f"{path}:9: flows[2]: type mismatch: b.value.out is real but belt.drive.run is bool",
        f"{path}:7: flows: flows form a zero-delay loop (line 7: b.value.out → c.value.in; "
        "line 8: c.value.out → b.value.in); break it with a component that delays"]
