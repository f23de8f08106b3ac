"""hub/bus/README.md's participant example, run exactly as printed: it joins a run from another process and
drives the belt to the in-process FMU's recording, byte for byte."""
import re

import yaml

from hub.bus.session import Bus
from hub.bus.settings import BusSettings

from .bus_support import BELT_FMU, BELT_PARTICIPANT, hub, output_of, process, same_files
from .fmus.fmu_support import build
from .helpers import ROOT, run_scenario


def readme_example() -> str:
    text = (ROOT / "hub" / "bus" / "README.md").read_text()
    match = re.search(r"<!-- participant example -->\n```python\n(.*?)```", text, re.S)
    assert match, "hub/bus/README.md lost its participant example"
    return match.group(1)


def test_the_example_is_short_and_is_the_shipped_participant():
    code = readme_example()
    assert len(code.splitlines()) <= 25
    assert code == (ROOT / "modules" / "belt_drive_logic.py").read_text()


def test_the_example_joins_a_run_and_gives_the_fmu_recording(tmp_path):
    build(ROOT / "build" / "fmus")
    run_scenario(BELT_FMU, tmp_path / "fmu")
    example = tmp_path / "my_belt_drive.py"
    example.write_text(readme_example())
    scene = yaml.safe_load(BELT_PARTICIPANT.read_text())
    del scene["objects"]["drive"]["command"]   # nobody launches it: it joins
    scene["name"] = "line1"
    (tmp_path / "joined.yaml").write_text(yaml.safe_dump(scene))
    with Bus(BusSettings()) as bus, hub(tmp_path / "joined.yaml", tmp_path / "joined", bus=bus) as master:
        with process(example, "--run", "line1", "--name", "drive",
                     "--connect", bus.endpoints[0]) as proc:
            master.run()
            code, _, err = output_of(proc)
    assert code == 0, err
    assert same_files(tmp_path / "fmu", tmp_path / "joined")
