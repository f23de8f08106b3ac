"""Shared fixtures."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest


@pytest.fixture
def write_scenario(tmp_path):
    """Write YAML text (dedented) to a file in tmp_path and return its path."""
    def write(text: str, name: str = "scene.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text).lstrip())
        return path
    return write



def pytest_collection_modifyitems(config, items):
    """The files that hold a slow test first, each whole and in its own order, then the rest as
    collected: `make test`'s `--dist loadfile` hands whole files to its workers in this order, so
    the long ones start at once and the short ones even out the end."""
    slow = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow)
