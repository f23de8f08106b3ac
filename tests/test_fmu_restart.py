"""`on_fault: restart`: an FMU in a child process that crashes or hangs is started again from its state at the last checkpoint and stepped back to where it was; the run gives the same files (hub/logic/isolated.py)."""
from __future__ import annotations

import os
import signal

import pytest

from hub.core.errors import ScenarioError, SimulationError
from hub.run.assembly import Run
from hub.scenario.checker import load_scenario

from .fmus.fmu_support import build
from .helpers import ROOT

BELT_FMU = ROOT / "scenarios" / "belt_ramp_fmu.yaml"
RESTART = {"objects.drive.runs": "child", "objects.drive.on_fault": "restart"}


@pytest.fixture(scope="module", autouse=True)
def fmus():
    return build(ROOT / "build" / "fmus")


def _worker(run):
    return next(c.slave for c in run.plant.components if c.obj == "drive")


def _uninterrupted(out, settings) -> None:
    with Run(load_scenario(BELT_FMU, settings), out=out) as run:
        run.run()


def _same_files(a, b) -> None:
    for name in ("recording.csv", "events.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_a_crashed_fmu_restarts_from_the_last_checkpoint_and_the_run_is_the_same(tmp_path):
    with Run(load_scenario(BELT_FMU, RESTART), out=tmp_path / "crashed", checkpoints=((150,), None)) as run:
        run.run(225)
        slave = _worker(run)
        lost = slave._process.pid
        os.kill(lost, signal.SIGKILL)   # a segfault in the FMU's code, as the hub sees it
        run.run()
        assert slave._process.pid != lost
        summary = run.summary()
    [restart] = summary.restarts
    assert (restart.time, restart.since, restart.steps) == (1.5, 1.0, 25)   # 0.5 s of 0.02 s steps
    assert "its worker process was killed by SIGKILL" in restart.cause
    assert ("  restarted    FMU instance 'drive' at t = 1.5 s, from its state at t = 1 s and 25 steps again"
            in summary.lines())
    assert summary.as_dict()["restarts"][0]["from"] == 1.0
    _uninterrupted(tmp_path / "whole", RESTART)
    _same_files(tmp_path / "crashed", tmp_path / "whole")


def test_a_hung_fmu_is_killed_and_restarted_from_its_start_without_a_checkpoint(tmp_path):
    settings = {**RESTART, "objects.drive.step_timeout": 0.5}
    with Run(load_scenario(BELT_FMU, settings), out=tmp_path / "hung") as run:
        run.run(300)
        slave = _worker(run)
        os.kill(slave._process.pid, signal.SIGSTOP)   # it stops answering: past step_timeout it is killed
        try:
            run.run()
        finally:
            os.kill(slave._process.pid, signal.SIGCONT)
        [restart] = run.summary().restarts
    assert (restart.time, restart.since, restart.steps) == (2.0, 0.0, 100)
    assert "did not return within 0.5 s (step_timeout), so its worker process was killed" in restart.cause
    _uninterrupted(tmp_path / "whole", settings)
    _same_files(tmp_path / "hung", tmp_path / "whole")


def test_without_restart_a_crashed_fmu_stops_the_run(tmp_path):
    with Run(load_scenario(BELT_FMU, {"objects.drive.runs": "child"}), out=tmp_path) as run:
        run.run(30)
        os.kill(_worker(run)._process.pid, signal.SIGKILL)
        with pytest.raises(SimulationError, match=r"its worker process was killed by SIGKILL; the run stops here"):
            run.run()


def test_restart_goes_with_a_child_process():
    with pytest.raises(ScenarioError, match=r"on_fault: restart goes with runs: child \(an FMU in a worker process "
                                            r"the hub can start again\), not runs: hub"):
        load_scenario(BELT_FMU, {"objects.drive.on_fault": "restart"})


def test_a_step_that_fails_again_after_a_restart_stops_the_run_naming_both(tmp_path):
    """The test-only `faulty` FMU's step at `hang_at` never returns, whatever worker steps it: the
    restart does not help, and the run stops saying so."""
    faulty = build(tmp_path / "faulty", models_dir=ROOT / "tests" / "fmu_models")
    scene = tmp_path / "scene.yaml"
    scene.write_text(f"""planthub: 1
run: {{duration: 2.0, physics_rate: 100, communication_step: 0.1}}
objects:
  counter: {{module: fmu, file: {faulty / 'faulty-fmi2.fmu'}, parameters: {{hang_at: 4}}, step_timeout: 0.5,
             runs: child, on_fault: restart}}
record: [counter.logic.steps]
""")
    with Run(load_scenario(scene), out=tmp_path / "out") as run, \
            pytest.raises(SimulationError, match=r"^FMU instance 'counter' \(faulty-fmi2.fmu\) at t = 0.3 s: its step "
                                                 r"did not return within 0.5 s .* \(restarted once at this step: FMU "
                                                 r"instance 'counter' \(faulty-fmi2.fmu\) at t = 0.3 s: its step did "
                                                 r"not return within 0.5 s"):
        run.run()
