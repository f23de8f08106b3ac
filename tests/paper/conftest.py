"""Each paper scenario runs once per test session; its tests read the same run."""
import pytest

from hub.reports import paper
from hub.reports.runs import run


@pytest.fixture(scope="session")
def acceleration_run():
    return run(paper.ACCELERATION)


@pytest.fixture(scope="session")
def tipping_run():
    return run(paper.TIPPING)


@pytest.fixture(scope="session")
def distances_run(tmp_path_factory):
    return run(paper.DISTANCES, tmp_path_factory.mktemp("loop"))
