"""modules/README.md is the reference `planthub describe --reference` writes from the modules' parameter schemas and slot declarations, and every slot in it says what it means."""
import pytest

from hub.cli.reference import COMMAND
from hub.core.registry import default_registry

from .helpers import ROOT, planthub

REGISTRY = default_registry()


def test_modules_readme_is_what_the_generator_writes(capsys, tmp_path):
    code, _, err = planthub(capsys, "describe", "--reference", tmp_path / "README.md")
    assert code == 0, err
    fresh = (tmp_path / "README.md").read_text(encoding="utf-8")
    kept = (ROOT / "modules" / "README.md").read_text(encoding="utf-8")
    assert kept == fresh, (f"modules/README.md is not what the modules declare now (a parameter, a Slot or "
                           f"a docstring changed): run `{COMMAND}` and commit it")


@pytest.mark.parametrize("name", REGISTRY.names())
def test_every_slot_of_the_reference_says_what_it_means(name):
    silent = [f"{component}.{slot.name}" for component, slot in REGISTRY.get(name).reference_slots()
              if not slot.doc.strip()]
    assert not silent, f"{name}: give these slots a description in their Slot declaration: {', '.join(silent)}"


def test_a_family_stands_in_place_of_the_slot_its_parameters_type():
    """constant's `value.out` has the type its `type` parameter names: the reference says so, in its place."""
    rows = [(component, slot.name, slot.type if isinstance(slot.type, str) else slot.type.value)
            for component, slot in REGISTRY.get("constant").reference_slots()]
    assert rows == [("value", "set", "void"), ("value", "out", "param `type`")]


def test_reference_takes_no_module_name(capsys, tmp_path):
    code, _, err = planthub(capsys, "describe", "conveyor", "--reference", tmp_path / "README.md")
    assert code == 2 and "--reference writes every module's reference: give no module name" in err
    assert not (tmp_path / "README.md").exists()


def test_every_slot_a_shipped_scenario_makes_is_in_its_modules_reference():
    """What the reference lists covers what the modules make: each slot of each object of the
    shipped scenarios is listed by name, or its component has a family of its direction that
    stands for it (an FMU's `<input>`, a sink's `DEST`)."""
    from hub.core.slots import Slot
    from hub.scenario.checker import load_scenario

    unlisted = {}   # (module, component.slot (direction)) → the first scenario that makes it
    for path in sorted((ROOT / "scenarios").rglob("*.yaml")):
        for spec in load_scenario(path).objects:
            reference = spec.module.reference_slots()
            named = {(c, s.name, s.direction) for c, s in reference if isinstance(s, Slot)}
            families = {(c, s.direction) for c, s in reference if not isinstance(s, Slot)}
            for component, slots in spec.module.slots(spec.params).items():
                for slot in slots:
                    if (component, slot.name, slot.direction) not in named | {(c, slot.name, d) for c, d in families}:
                        unlisted.setdefault(f"{spec.module_name} {component}.{slot.name} ({slot.direction.value})",
                                            path.name)
    assert not unlisted, "slots the modules' reference does not list: " + "; ".join(
        f"{slot}, in {scenario}" for slot, scenario in unlisted.items())
