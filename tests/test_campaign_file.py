"""Campaign files (hub/campaign/plan.py): the cases a matrix, `zip` and seeds make, and every mistake named with file and line."""
from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from hub.campaign.plan import CampaignError, load_campaign
from hub.run import checkpoint

from .helpers import ROOT

SCENARIO = ROOT / "scenarios" / "belt_bottle_sensor.yaml"


def write(tmp_path, text: str):
    path = tmp_path / "campaign.yaml"
    path.write_text(textwrap.dedent(text).replace("SCENARIO", str(SCENARIO)))
    return path


def problems(tmp_path, text: str) -> str:
    with pytest.raises(CampaignError) as caught:
        load_campaign(write(tmp_path, text))
    return str(caught.value)


def test_matrix_zip_and_seeds_make_cases_in_file_order(tmp_path):
    campaign = load_campaign(write(tmp_path, """\
        planthub: 1
        name: speeds
        scenarios: [SCENARIO]
        matrix:
          objects.belt.speed: [0.3, 0.5]
        zip:
          objects.belt.k: [8, 16]
          run.duration: [1, 2]
        seeds: [3, 4]
        expect:
          - {name: moved, slot: barrier.trigger.occupied, is: {"==": false}}
        time_limit: 30
        """))
    assert campaign.name == "speeds"
    assert [c.label for c in campaign.cases][:3] == [
        "belt_bottle_sensor[objects.belt.speed=0.3, objects.belt.k=8, run.duration=1, run.seed=3]",
        "belt_bottle_sensor[objects.belt.speed=0.3, objects.belt.k=8, run.duration=1, run.seed=4]",
        "belt_bottle_sensor[objects.belt.speed=0.3, objects.belt.k=16, run.duration=2, run.seed=3]"]
    assert len(campaign.cases) == 2 * 2 * 2
    assert [c.index for c in campaign.cases] == list(range(8))
    case = campaign.cases[-1]
    assert case.overrides() == {"objects.belt.speed": 0.5, "objects.belt.k": 16, "run.duration": 2, "run.seed": 4,
                                "expect": [{"name": "moved", "slot": "barrier.trigger.occupied", "is": {"==": False}}]}
    assert case.time_limit == 30 and case.folder == "cases/007-belt_bottle_sensor"


def test_a_seed_count_and_no_matrix(tmp_path):
    campaign = load_campaign(write(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nseeds: 3\n"))
    assert [c.parameters for c in campaign.cases] == [(("run.seed", 0),), (("run.seed", 1),), (("run.seed", 2),)]
    assert campaign.cases[0].time_limit == 600   # no case waits without a limit


def test_shape_mistakes_are_named_at_their_lines(tmp_path):
    text = problems(tmp_path, """\
        planthub: 1
        scenarios: []
        matrix:
          objects.belt.speed: 0.3
          "objects belt": [1]
        seeds: [1, 1]
        time_limit: -3
        timelimit: 3
        """)
    assert "problems in campaign:" in text
    assert "campaign.yaml:2: scenarios: [] should be non-empty" in text
    assert "campaign.yaml:4: matrix.objects.belt.speed: 0.3 is not of type 'array'" in text
    assert ("campaign.yaml:5: matrix.objects belt: 'objects belt' is not a dotted key of a scenario "
            "(as --set takes it, e.g. objects.belt.speed)") in text
    assert ("campaign.yaml:6: seeds: expected a number of seeds (1 or more) or a list of different seeds "
            "(0 or more)") in text
    assert "campaign.yaml:7: time_limit: -3 is less than or equal to the minimum of 0" in text
    assert "campaign.yaml:8: timelimit: unknown key 'timelimit' (did you mean 'time_limit'?)" in text


def test_a_matrix_that_does_not_hold_together(tmp_path):
    text = problems(tmp_path, """\
        planthub: 1
        scenarios: [SCENARIO]
        matrix:
          run.seed: [0, 1]
          objects.belt.k: [8]
        zip:
          run.duration: [1, 2]
          objects.belt.k: [8]
        seeds: 2
        """)
    assert "campaign.yaml:4: matrix.run.seed: run.seed is given by `seeds` too: give the seeds in one place" in text
    assert ("campaign.yaml:6: zip: the lists of `zip` are taken pairwise and need one length; they have "
            "run.duration: 2, objects.belt.k: 1") in text
    assert "campaign.yaml:8: zip.objects.belt.k: objects.belt.k is in `matrix` too: give its values in one of them" in text


def test_a_case_the_scenario_refuses_is_named_at_the_campaigns_line(tmp_path):
    text = problems(tmp_path, """\
        planthub: 1
        scenarios:
          - SCENARIO
          - missing.yaml
        matrix:
          objects.belt.sped: [0.3]
          objects.belt.length: [2.0, -1]
        expect:
          - {slot: bottle.body.nothing, is: {"==": 1}}
        from: nowhere.ckpt
        """)
    at = f"in {SCENARIO}"
    assert (f"campaign.yaml:6: matrix.objects.belt.sped[0]: {at}: objects.belt.sped: unknown key 'sped' "
            "(did you mean 'speed'?)") in text
    assert (f"campaign.yaml:7: matrix.objects.belt.length[1]: {at}: objects.belt.length: -1 is less than or equal "
            "to the minimum of 0") in text
    assert (f"campaign.yaml:9: expect[0]: {at}: expect[0].slot: object 'bottle' (bottle) has no slot 'body.nothing'"
            in text)
    assert f"campaign.yaml:4: scenarios[1]: no scenario file 'missing.yaml' (looked for {tmp_path / 'missing.yaml'})" in text
    assert f"campaign.yaml:10: from: no checkpoint file 'nowhere.ckpt' (looked for {tmp_path / 'nowhere.ckpt'})" in text
    assert text.count("unknown key 'sped'") == 1   # found in both cases, said once


def test_not_yaml_and_the_command_lines_exit_code(tmp_path):
    path = tmp_path / "campaign.yaml"
    path.write_text("planthub: 1\nscenarios: [a\n")
    done = subprocess.run([sys.executable, "-m", "hub", "campaign", str(path), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 3
    assert f"{path}:3: not valid YAML" in done.stderr
    assert not (tmp_path / "out").exists()


def campaign_command(tmp_path, *options: str) -> subprocess.CompletedProcess:
    path = write(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nseeds: 2\n")
    return subprocess.run([sys.executable, "-m", "hub", "campaign", str(path), *options], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)


def test_only_failed_needs_an_earlier_campaigns_results(tmp_path):
    done = campaign_command(tmp_path, "--out", "again", "--only-failed", "nowhere")
    assert done.returncode == 2
    assert ("--only-failed nowhere: cannot read the earlier campaign's results nowhere/campaign.json: "
            "No such file or directory") in done.stderr
    (tmp_path / "earlier").mkdir()
    (tmp_path / "earlier" / "campaign.json").write_text("{}")
    done = campaign_command(tmp_path, "--out", "earlier", "--only-failed", "earlier")
    assert done.returncode == 2
    assert "--out earlier is the campaign whose failures are run again; write them elsewhere" in done.stderr
    done = campaign_command(tmp_path, "--out", "again", "--only-failed", "earlier")
    assert done.returncode == 2
    assert ("--only-failed earlier: earlier/campaign.json is no campaign's results (`planthub campaign --out`): "
            "no list of cases with their label and verdict") in done.stderr


def test_only_failed_after_a_campaign_that_passed_runs_nothing(tmp_path):
    (tmp_path / "earlier").mkdir()
    labels = [f"belt_bottle_sensor[run.seed={seed}]" for seed in (0, 1)]
    (tmp_path / "earlier" / "campaign.json").write_text(
        json.dumps({"cases": [{"label": label, "verdict": "passed"} for label in labels]}))
    done = campaign_command(tmp_path, "--out", "again", "--only-failed", "earlier", "--junit", "again.xml")
    assert done.returncode == 0, done.stderr
    assert "planthub campaign campaign: no case to run" in done.stdout
    assert json.loads((tmp_path / "again" / "campaign.json").read_text())["cases"] == []
    assert (tmp_path / "again.xml").is_file()


def test_cases_that_do_not_fit_the_checkpoint_they_branch_from(tmp_path):
    subprocess.run([sys.executable, "-m", "hub", "run", str(SCENARIO), "--set", "run.duration=1", "--checkpoint-at",
                    "0.5", "--out", str(tmp_path / "warm"), "-q"], check=True, capture_output=True, timeout=60)
    text = problems(tmp_path, """\
        planthub: 1
        scenarios: [SCENARIO]
        matrix:
          run.duration: [1, 1.5]
          objects.belt.speed: [0.5, 0.3]
        seeds: [0, 1]
        from: warm/checkpoints/75.ckpt
        """)
    fixed = ("changes the plant: the checkpoint `from:` was taken of 'belt_bottle_sensor' as it was (only the "
             "duration, the expectations, the recording, the logic's parameters and where logic runs may differ)")
    assert f"campaign.yaml:5: matrix.objects.belt.speed[1]: objects.belt.speed=0.3 {fixed}" in text
    assert f"campaign.yaml:6: seeds: run.seed=1 {fixed}" in text
    assert "problems in campaign" in text and text.count(fixed) == 2   # the speed and the seed, whatever the duration
    (tmp_path / "bad.ckpt").write_text("bad")
    text = problems(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nfrom: bad.ckpt\n")
    assert ("campaign.yaml:3: from: bad.ckpt: not a planthub checkpoint (it does not start with "
            "'planthub checkpoint')") in text
    whole = (tmp_path / "warm" / "checkpoints" / "75.ckpt").read_bytes()
    (tmp_path / "corrupt.ckpt").write_bytes(whole[:-1] + bytes([whole[-1] ^ 1]))   # one bit of its state flipped
    text = problems(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nfrom: corrupt.ckpt\n")
    assert "campaign.yaml:3: from: corrupt.ckpt: corrupt: its state does not match the checksum in its header" in text
    (tmp_path / "cut.ckpt").write_bytes(whole[:-10])
    size = checkpoint.header(whole, "")[0].size
    text = problems(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nfrom: cut.ckpt\n")
    assert (f"campaign.yaml:3: from: cut.ckpt: truncated or padded: its header promises {size} bytes of state, "
            f"the file holds {size - 10}") in text


def test_workers_and_scheduler_addresses_that_cannot_be(tmp_path, capsys):
    from hub.cli.main import main

    path = write(tmp_path, "planthub: 1\nscenarios: [SCENARIO]\nseeds: 2\n")
    for value, message in (("0", "argument --workers: needs at least 1 worker, got 0"),
                           ("x", "argument --workers: expected a number of workers, got 'x'")):
        with pytest.raises(SystemExit) as exited:   # argparse's own exit for a bad option
            main(["campaign", str(path), "--workers", value])
        assert exited.value.code == 2
        assert message in capsys.readouterr().err
    out = tmp_path / "out"
    assert main(["campaign", str(path), "--out", str(out), "--scheduler", "tcp://127.0.0.1:port"]) == 1
    said = ("cannot reach scheduler tcp://127.0.0.1:port: not an address Dask can read (tcp://HOST:PORT): "
            "invalid literal for int() with base 10: 'port'")
    assert f"planthub campaign: {said}" in capsys.readouterr().err
    found = json.loads((out / "campaign.json").read_text())
    assert found["ended"] == f"not started: {said}"
    assert [c["verdict"] for c in found["cases"]] == ["not run"] * 2
    assert (out / "cases.csv").read_text().count("\n") == 3


def test_only_failed_names_the_failed_cases_the_file_no_longer_has(tmp_path):
    (tmp_path / "earlier").mkdir()
    (tmp_path / "earlier" / "campaign.json").write_text(json.dumps({"cases": [
        {"label": "belt_bottle_sensor[run.seed=0]", "verdict": "passed"},
        {"label": "belt_bottle_sensor[run.seed=7]", "verdict": "failed"}]}))
    done = campaign_command(tmp_path, "--out", "again", "--only-failed", "earlier")
    assert done.returncode == 0, done.stderr
    assert (f"planthub campaign: 1 failed case(s) of earlier/campaign.json are not in {tmp_path / 'campaign.yaml'} "
            "any more: belt_bottle_sensor[run.seed=7]") in done.stderr
    assert "no case to run" in done.stdout


def test_plotting_a_campaign_that_cannot_be(tmp_path, capsys):
    from hub.cli.main import main

    folder = tmp_path / "campaign"
    folder.mkdir()
    results = folder / "campaign.json"
    results.write_text('{"cases": [')
    assert main(["plot", str(folder), "f", "--against", "mode"]) == 2
    assert f"{results}: not a campaign's results (`planthub campaign --out`): Expecting value" in capsys.readouterr().err
    results.write_text(json.dumps({"cases": [{"index": 0, "parameters": {"mode": "fast"}, "figures": {"f": 1}}]}))
    assert main(["plot", str(folder), "f", "--against", "mode"]) == 2
    assert "--against mode: case 0 has 'fast', not a number" in capsys.readouterr().err
    results.write_text(json.dumps({"cases": [{"index": 0, "parameters": {"speed": 0.5}, "figures": {"f": 1}}]}))
    (tmp_path / "file").write_text("")
    out = tmp_path / "file" / "plot.png"   # under a file: no folder can be made there
    assert main(["plot", str(folder), "f", "--against", "speed", "--out", str(out)]) == 1
    assert f"cannot write {out}: " in capsys.readouterr().err
