"""FMI 3 co-simulation with event mode: the FMU's own events are handled as they come.

    ticks (FMI 3 CS, hasEventMode) ──ticks, since──▶ record

`ticks3` (tests/fmu_models/foreign) ticks every 0.25 s, a time event that only event mode counts; with
early return allowed its doStep stops at the tick. The hub handles the event (enterEventMode,
updateDiscreteStates, enterStepMode) and steps on to the communication point.
"""
import csv
import zipfile

import pytest

from .foreign_fmus import build
from .helpers import run_scenario


@pytest.fixture(scope="module")
def ticks3(tmp_path_factory):
    return build("ticks3", 3, tmp_path_factory.mktemp("foreign"))


def recorded(write_scenario, fmu, out):
    path = write_scenario(f"""
        planthub: 1
        run: {{duration: 1.0, physics_rate: 100, communication_step: 0.1}}
        objects:
          t: {{module: fmu, file: {fmu}}}
        record: [t.logic.ticks, t.logic.since]
        """)
    run_scenario(path, out)
    with open(out / "recording.csv", newline="") as f:
        return [(float(r["time"]), int(r["t.logic.ticks"]), float(r["t.logic.since"])) for r in csv.DictReader(f)]


def test_an_fmus_own_events_are_handled_where_it_returns_early(ticks3, write_scenario, tmp_path):
    """Ticks at 0.25, 0.5, 0.75 and 1.0 s, inside communication steps and on their ends, each counted at its
    own time: at every point `since` is the time from the last tick."""
    data = recorded(write_scenario, ticks3, tmp_path / "out")
    assert [ticks for _, ticks, _ in data] == [0, 0, 0, 1, 1, 2, 2, 2, 3, 3, 4]
    for time, ticks, since in data:
        assert since == pytest.approx(time - 0.25 * ticks, abs=1e-12)


def test_an_fmu_without_event_mode_is_not_given_it(ticks3, write_scenario, tmp_path):
    """The same binary declaring no event mode is instantiated without it: its ticks are never counted
    (the FMU's behaviour then), which shows the hub followed the declaration."""
    plain = tmp_path / "plain.fmu"
    with zipfile.ZipFile(ticks3) as src, zipfile.ZipFile(plain, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'hasEventMode="true"', b'hasEventMode="false"')
            dst.writestr(item, data)
    data = recorded(write_scenario, plain, tmp_path / "out")
    assert {ticks for _, ticks, _ in data} == {0}
    assert data[-1][2] == pytest.approx(1.0)
