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


def pytest_collection_modifyitems(items):
    """The files that hold a slow test first, the rest in their order: with the suite spread over
    workers a file at a time (make test), the longest files start first and the short ones fill in
    at the end, instead of one long file running alone after everything else."""
    slow = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow)   # a stable sort: each file's own order kept
