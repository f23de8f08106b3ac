"""Fixtures of the FMU tests: the built FMUs and FMU instances that are freed after each test."""

from pathlib import Path

import fmpy
import pytest

from .fmu_support import REPO, TEST_MODELS_DIR, Instance, build


@pytest.fixture(scope="session")
def fmu_build():
    """build/fmus, brought up to date: the very FMUs the hub loads (`make fmus` has usually built them already)."""
    return build(REPO / "build" / "fmus")


@pytest.fixture(scope="session")
def probe_build(tmp_path_factory):
    """The build directory of the test-only probe model."""
    return build(tmp_path_factory.mktemp("probe"), models_dir=TEST_MODELS_DIR)


@pytest.fixture
def open_instance(tmp_path):
    """open_instance(fmu_path, **kwargs) -> Instance; all are freed after the test."""
    opened = []

    def open_(fmu, **kwargs):
        unzip_dir = tmp_path / Path(fmu).stem
        if not unzip_dir.exists():
            fmpy.extract(str(fmu), str(unzip_dir))
        instance = Instance(fmu, unzip_dir, **kwargs)
        opened.append(instance)
        return instance

    yield open_
    for instance in opened:
        instance.close()
