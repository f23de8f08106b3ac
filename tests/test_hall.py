"""The hall the scale benchmark runs (tests/hall.py): ten copies of the bottling plant that the
checker takes, each line's objects, places, flows and bottle ids its own."""
import yaml

from hub.scenario.checker import load_scenario

from .hall import PLANT, SPACING, write_hall


def test_the_hall_is_ten_bottling_lines_side_by_side_each_wired_within_itself(tmp_path):
    plant = yaml.safe_load(PLANT.read_text())
    path = write_hall(tmp_path / "hall.yaml", 10, 20.0)
    hall = yaml.safe_load(path.read_text())
    assert len(hall["objects"]) == 10 * len(plant["objects"])
    assert len(hall["flows"]) == 10 * len(plant["flows"])
    for line in (0, 9):
        prefix = f"l{line}_"
        assert hall["objects"][prefix + "b01"]["position"][1] == plant["objects"]["b01"]["position"][1] + line * SPACING
        assert hall["objects"][prefix + "robot"]["pick"][1] == plant["objects"]["robot"]["pick"][1] + line * SPACING
        assert hall["objects"][prefix + "b02"]["after"] == prefix + "b01"
        assert hall["objects"][prefix + "pallet"]["prefix"] == f"L{line}M"
        assert hall["objects"][prefix + "control"]["runs"] == "hub"
        assert all(f["from"].startswith(prefix) == f["to"].startswith(prefix)
                   for f in hall["flows"] if prefix in f["from"] or prefix in f["to"])
    scenario = load_scenario(path)
    assert scenario.run.end_tick == 20 * 150 and len(scenario.objects) == 10 * len(plant["objects"])
