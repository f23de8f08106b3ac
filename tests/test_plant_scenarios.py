"""The plant-element scenarios: each gives bit-identical files in every run (robot: tests/test_robot_arm.py);
every shipped scenario runs with the resting bottles checked against the engine."""
import pytest

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .helpers import ROOT, run_scenario


@pytest.mark.parametrize("name", ["switch", "separator", "station", "source_sink"])
def test_a_scenario_run_twice_gives_identical_files(tmp_path, name):
    path = ROOT / "scenarios" / f"{name}.yaml"
    run_scenario(path, tmp_path / "one")
    run_scenario(path, tmp_path / "two")
    for file in ("recording.csv", "events.csv"):
        assert (tmp_path / "one" / file).read_bytes() == (tmp_path / "two" / file).read_bytes()


# The shipped scenarios in which bottles come to rest (the others have none still long enough).
RESTING = ["belt_ramp_fmu", "belt_ramp_participant", "robot", "robot_logic", "stop_at_barrier",
           "two_drives_distributed"]


@pytest.mark.parametrize("name", RESTING)
def test_resting_bottles_stay_where_the_engine_holds_them(name):
    """The scenario run with the world comparing every resting bottle with the engine at every
    tick (hub/physics/rest.py); the bottling plant's: tests/test_bottling_plant.py."""
    scenario = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
    most = []

    class Look:   # an observer: how many bottles rest at each point
        def observe(self, tick, signals, events):
            most.append(int(world.rest.resting.sum()))

        def close(self, reason):
            pass
    with Run(scenario, observers=[Look()]) as run:
        world = run.plant.world
        world.check_rest = True
        result = run.run()
    most = max(most)
    assert result.ticks == scenario.run.end_tick and most >= 1
