"""The plant-element scenarios: each gives bit-identical files in every run (robot: tests/test_robot_arm.py)."""
import pytest

from .helpers import ROOT, run_scenario


@pytest.mark.parametrize("name", ["switch", "separator", "station", "source_sink"])
def test_a_scenario_run_twice_gives_identical_files(tmp_path, name):
    path = ROOT / "scenarios" / f"{name}.yaml"
    run_scenario(path, tmp_path / "one")
    run_scenario(path, tmp_path / "two")
    for file in ("recording.csv", "events.csv"):
        assert (tmp_path / "one" / file).read_bytes() == (tmp_path / "two" / file).read_bytes()
