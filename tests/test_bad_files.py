"""Bad scenario files end in a ScenarioError naming file, line and cause — never a traceback, never
a hang: every class a mutation fuzzer found over the shipped scenarios, and NaN and infinity."""
from __future__ import annotations

import subprocess
import sys

import pytest

from hub.core.errors import ScenarioError
from hub.scenario.checker import load_scenario
from hub.scenario.yamlsource import MAX_DEPTH, MAX_VALUES

from .helpers import ROOT

BASE = (ROOT / "scenarios" / "belt_bottle_sensor.yaml").read_text()


def line(text: str, needle: str) -> int:
    """The 1-based line of the first line of `text` that holds `needle`."""
    return next(n for n, row in enumerate(text.splitlines(), 1) if needle in row)


def problems(path, overrides=None) -> list[str]:
    with pytest.raises(ScenarioError) as caught:
        load_scenario(path, overrides)
    return [str(p) for p in caught.value.problems]


def write(tmp_path, data: bytes | str, name="bad.yaml"):
    path = tmp_path / name
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    return path


def test_invalid_utf8_is_named_with_its_line(tmp_path):
    path = write(tmp_path, BASE.encode().replace(b"One bottle", b"One \xff bottle"))
    assert problems(path) == [f"{path}:{line(BASE, 'One bottle')}: not UTF-8 text: byte 0xff at offset {BASE.encode().index(b'One bottle') + 4}"]


@pytest.mark.parametrize("char, shown", [("\x00", "U+0000"), ("\x07", "U+0007")])
def test_a_control_character_is_named_with_its_line(tmp_path, char, shown):
    path = write(tmp_path, BASE.replace("One bottle", f"One{char} bottle"))
    assert problems(path) == [f"{path}:{line(BASE, 'One bottle')}: not valid YAML: the character {shown} is not allowed in a YAML file"]


def test_a_date_is_text_as_yaml_12_reads_it(tmp_path):
    """YAML 1.1 made `2020-13-01` an (invalid) date; a scenario is read as YAML 1.2: a string."""
    path = write(tmp_path, BASE.replace("description: One bottle carried by one belt through one light barrier.",
                                        "description: 2020-13-01"))
    assert load_scenario(path).description == "2020-13-01"


def test_an_unknown_tag_is_named(tmp_path):
    path = write(tmp_path, BASE.replace("    speed: 0.5\n", "    speed: !custom 1\n"))
    found = problems(path)
    assert found == [f"{path}:{line(BASE, 'speed: 0.5')}: objects.belt.speed: cannot read '1': could not determine a constructor "
                     f"for the tag '!custom'"]


@pytest.mark.parametrize("text", ["planthub: 1\nobjects: " + "[" * 3000 + "]" * 3000 + "\n",
                                  "planthub: 1\n" + "".join(f"{'  ' * i}k{i}:\n" for i in range(600)) + "  " * 600 + "x: 1\n"])
def test_deep_nesting_is_refused(tmp_path, text):
    path = write(tmp_path, text)
    (found,) = problems(path)
    assert found.startswith(f"{path}:") and f"the document nests deeper than {MAX_DEPTH} levels" in found


@pytest.mark.parametrize("value", ["&loop [*loop]", "&loop {inner: *loop}"])
def test_a_recursive_alias_is_named_with_its_line(tmp_path, value):
    """`x: &a [*a]` is a graph, not a tree: named where the alias points back, never a RecursionError."""
    path = write(tmp_path, BASE.replace("    speed: 0.5\n", f"    speed: {value}\n"))
    at = line(BASE, "speed: 0.5")
    inner = "objects.belt.speed[0]" if value.startswith("&loop [") else "objects.belt.speed.inner"
    assert f"{path}:{at}: {inner}: an alias refers to a value that holds it (defined at line {at}): a scenario is a " \
           "tree, so an alias may only repeat a value defined before and outside it" in problems(path)


def test_a_list_repeated_by_aliases_is_no_loop(tmp_path):
    from hub.scenario.yamlsource import load_yaml

    data, _, found = load_yaml(write(tmp_path, "a: &x [1, {b: 2}]\nc: [*x, *x]\n"))
    assert found == [] and data == {"a": [1, {"b": 2}], "c": [[1, {"b": 2}], [1, {"b": 2}]]}


def test_a_complex_key_is_named(tmp_path):
    path = write(tmp_path, BASE.replace("objects:\n", "objects:\n  ? [a, b]\n  : {module: bottle}\n"))
    assert f"{path}:{line(BASE, 'objects:') + 1}: objects: a key must be a name, not a list or a mapping (a YAML `? ` complex key)" in problems(path)


def test_a_merge_key_is_an_unknown_key(tmp_path):
    path = write(tmp_path, BASE.replace("  bottle:\n    module: bottle\n", "  bottle:\n    <<: {mass: 1}\n    module: bottle\n"))
    assert problems(path) == [f"{path}:{line(BASE, 'module: bottle')}: objects.bottle.<<: unknown key '<<'"]


def test_an_alias_bomb_is_refused_quickly(tmp_path):
    """8 levels of 9 aliases each: 43 million values from 500 bytes."""
    lines = ["planthub: 1", "a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9)]
    path = write(tmp_path, "\n".join(lines) + "\n")
    proc = subprocess.run([sys.executable, "-m", "hub", "validate", str(path)], capture_output=True, text=True,
                          cwd=ROOT, timeout=60)
    assert proc.returncode == 3   # a bad scenario
    assert f"{path}: the document expands to more than {MAX_VALUES} values" in proc.stderr


@pytest.mark.parametrize("key, value", [("objects.belt.speed", float("nan")), ("objects.belt.k", float("nan")),
                                        ("objects.bottle.mass", float("inf")), ("objects.belt.length", float("nan")),
                                        ("objects.bottle.radius", float("nan")), ("run.sleep_after", float("inf")),
                                        ("run.duration", float("inf")), ("run.communication_step", float("inf"))])
def test_nan_and_infinity_are_refused_in_every_number(tmp_path, key, value):
    path = write(tmp_path, BASE)
    assert problems(path, {key: value}) == [f"--set: {key}: {value!r} is not a finite number"]


def test_nan_in_a_list_is_named_with_its_place(tmp_path):
    path = write(tmp_path, BASE.replace("position: [1.5, 0.0, 0.05]", "position: [1.5, .nan, 0.05]"))
    assert problems(path) == [f"{path}:{line(BASE, 'position: [1.5')}: objects.barrier.position[1]: nan is not a finite number"]


def test_nan_in_a_parameter_is_not_judged_again_by_the_modules_own_checks():
    """The separator's check divides bottle_diameter by 2: a NaN there, reported and set aside, must
    not reach it (it did: a TypeError traceback)."""
    path = ROOT / "scenarios" / "separator.yaml"
    assert problems(path, {"objects.sep.bottle_diameter": float("nan")}) == [
        "--set: objects.sep.bottle_diameter: nan is not a finite number"]


@pytest.mark.parametrize("key, value, shown", [("run.duration", 1e300, "1e+300"),
                                              ("objects.belt.length", -2.0 ** 60, "-1.152921504606847e+18"),
                                              ("run.seed", 2 ** 70, "1180591620717411303424")])
def test_a_number_beyond_2_to_the_53_is_named(tmp_path, key, value, shown):
    """Found by the property tests: a participant's `step: 1.2e306` overflowed to infinity when the
    checker counted its ticks (OverflowError). No scenario number needs more than a double holds
    exactly."""
    path = write(tmp_path, BASE)
    assert problems(path, {key: value}) == [
        f"--set: {key}: {shown} is out of range: a scenario's numbers stay within ±2**53 (about 9.0e15)"]


@pytest.mark.parametrize("entry, message", [
    ('{slot: barrier.trigger.occupied, is: {"==": true, "!=": false}}', "expect[0].is: {'==': True, '!=': False} has too many properties"),
    ("{slot: barrier.trigger.occupied, is: yes}", "expect[0].is: 'yes' is not of type 'object'"),
    ('{slot: barrier.trigger.occupied, is: {"==": true}, at: null}', "expect[0].at: None is not of type 'number'"),
    ('{slot: barrier.trigger.occupied, is: {"==": true}, at: "soon"}', "expect[0].at: 'soon' is not of type 'number'"),
    ('{slot: barrier.trigger.occupied, is: {"==": true}, at: .inf}', "expect[0].at: inf is not a finite number"),
])
def test_malformed_expectations_are_named(tmp_path, entry, message):
    path = write(tmp_path, BASE + f"expect:\n  - {entry}\n")
    assert problems(path) == [f"{path}:{len(BASE.splitlines()) + 2}: {message}"]


def test_set_reads_numbers_as_yaml_12(tmp_path):
    """`--set objects.belt.k=1e6`: YAML 1.1 read `1e6` as a string; it is a number."""
    proc = subprocess.run([sys.executable, "-m", "hub", "validate", "scenarios/belt_bottle_sensor.yaml",
                           "--set", "objects.belt.k=1e6"], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 0, proc.stderr


def test_set_with_nan_is_refused_on_the_command_line():
    proc = subprocess.run([sys.executable, "-m", "hub", "run", "scenarios/belt_bottle_sensor.yaml",
                           "--set", "objects.belt.speed=.nan"], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 3   # a bad scenario
    assert "--set: objects.belt.speed: nan is not a finite number" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("value, message", [("nan", "'nan' is not of type 'number'"),
                                            (float("nan"), "nan is not a finite number")])
def test_a_bad_value_given_with_set_is_blamed_on_set(tmp_path, value, message):
    """Not on the line of the file whose value it replaced."""
    path = write(tmp_path, BASE)
    assert problems(path, {"run.duration": value}) == [f"--set: run.duration: {message}"]
