"""`make stability` (tests/hard/stability.py): the cases side by side on a LocalCluster, a table of
every case and its bounds, build/bench/stability.json, exit 1 on a broken bound."""
import json
import subprocess
import sys

from . import cases, stability


def test_stability_runs_its_cases_side_by_side_on_a_local_cluster(tmp_path):
    out = tmp_path / "stability.json"
    done = subprocess.run([sys.executable, "-m", "tests.hard.stability", "--only", "light", "blade", "--workers", "2",
                           "--out", str(out)], cwd=cases.ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2 cases on a LocalCluster on 127.0.0.1: 2 workers, 2 cases at once" in done.stdout
    assert "2 passed, 0 failed" in done.stdout
    found = json.loads(out.read_text())["cases"]   # in the order asked, whichever ended first
    assert [c["name"] for c in found] == ["20 g bottle on a belt at 1.0 m/s", "switch blade enabled onto a bottle"]
    assert all(c["passed"] for c in found)


def test_stability_writes_each_case_with_its_bounds_and_exits_1_on_a_broken_one(tmp_path, capsys, monkeypatch):
    out = tmp_path / "stability.json"
    # In this process (--workers 0), where a bound changed here holds.
    assert stability.main(["--only", "light", "--workers", "0", "--out", str(out)]) == 0
    (case,) = json.loads(out.read_text())["cases"]
    assert case["name"] == "20 g bottle on a belt at 1.0 m/s" and case["passed"] and case["simulated_seconds"] == 3.0
    tilt = next(b for b in case["bounds"] if b["name"] == "tilt, base_body")
    assert tilt["limit"] == cases.LIGHT_TILT["base_body"] and 0 < tilt["measured"] <= tilt["limit"]
    assert "1 passed, 0 failed" in capsys.readouterr().out
    monkeypatch.setitem(cases.LIGHT_TILT, "base_body", 1.0)     # below what it rocks by
    assert stability.main(["--only", "light", "--workers", "0", "--out", str(out)]) == 1
    (case,) = json.loads(out.read_text())["cases"]
    assert not case["passed"] and [b["name"] for b in case["bounds"] if not b["passed"]] == ["tilt, base_body"]
    assert "BROKEN tilt, base_body" in capsys.readouterr().out
