"""Fixtures of the FMU tests: the built FMUs and FMU instances that are freed after each test."""

from pathlib import Path

import fmpy
import pytest

from .fmu_support import REPO, TEST_MODELS_DIR, TEST_NETS_DIR, VERSIONS, Instance, build
from .petri_support import PLANT_NETS, FMURunner, PythonRunner, load


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


@pytest.fixture(scope="session")
def net_test_build(tmp_path_factory):
    """The build directory of the test-only nets in tests/fmus/nets (and no models)."""
    no_models = tmp_path_factory.mktemp("no_models")
    return build(tmp_path_factory.mktemp("test_nets"), models_dir=no_models, nets_dir=TEST_NETS_DIR)


@pytest.fixture(params=["python", "fmi2", "fmi3"])
def run_net(request, open_instance):
    """run_net(name, **start_values) -> a runner of that net on the interpreter or on one FMI version's FMU."""

    def start(name, **start_values):
        net = load(name)
        if request.param == "python":
            return PythonRunner(net, start_values)
        build_dir = request.getfixturevalue("fmu_build" if name in PLANT_NETS else "net_test_build")
        return FMURunner(open_instance(build_dir / f"{name}-{request.param}.fmu"), net, start_values)

    return start


@pytest.fixture(params=VERSIONS, ids=lambda v: f"fmi{v}")
def plant_net(request, fmu_build, open_instance):
    """plant_net(name, **start_values) -> the FMU of a net in fmus/nets, driven through fmpy."""
    return lambda name, **start_values: FMURunner(
        open_instance(fmu_build / f"{name}-fmi{request.param}.fmu"), load(name), start_values)
