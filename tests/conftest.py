"""Shared fixtures: write small scenarios to temporary files and run them."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from hub.master import Master
from hub.plant import Plant
from hub.recorder import Recorder
from hub.scenario import load_scenario

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def write_scenario(tmp_path):
    """Write YAML text (dedented) to a file in tmp_path and return its path."""
    def write(text: str, name: str = "scene.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text).lstrip())
        return path
    return write


def run_scenario(path, out: Path | None = None, overrides: dict | None = None):
    """Load, build and run a scenario; return (scenario, recorder, result)."""
    scenario = load_scenario(path, overrides)
    with Plant(scenario) as plant:
        columns = [(ref, kind, plant.index[ref]) for ref, kind in scenario.record]
        recorder = Recorder(columns, scenario.run.physics_rate, out)
        try:
            result = Master(plant, recorder).run()
        finally:
            recorder.close()
    return scenario, recorder, result
