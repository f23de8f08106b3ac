"""`make stability` (tests/hard/stability.py): a table of every case and its bounds, build/bench/stability.json, exit 1 on a broken bound."""
import json

from . import cases, stability


def test_stability_writes_each_case_with_its_bounds_and_exits_1_on_a_broken_one(tmp_path, capsys, monkeypatch):
    out = tmp_path / "stability.json"
    assert stability.main(["--only", "light", "--out", str(out)]) == 0
    (case,) = json.loads(out.read_text())["cases"]
    assert case["name"] == "20 g bottle on a belt at 1.0 m/s" and case["passed"] and case["simulated_seconds"] == 3.0
    tilt = next(b for b in case["bounds"] if b["name"] == "tilt, base_body")
    assert tilt["limit"] == cases.LIGHT_TILT["base_body"] and 0 < tilt["measured"] <= tilt["limit"]
    assert "1 passed, 0 failed" in capsys.readouterr().out
    monkeypatch.setitem(cases.LIGHT_TILT, "base_body", 1.0)     # below what it rocks by
    assert stability.main(["--only", "light", "--out", str(out)]) == 1
    (case,) = json.loads(out.read_text())["cases"]
    assert not case["passed"] and [b["name"] for b in case["bounds"] if not b["passed"]] == ["tilt, base_body"]
    assert "BROKEN tilt, base_body" in capsys.readouterr().out
