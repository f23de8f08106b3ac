"""`python -m hub report paper` writes the numbers beside the paper's; plots only where matplotlib is."""

from hub.cli.main import main
from hub.reports.paper_report import write
from hub.reports.plots import Line, Panel, draw


def test_the_report_puts_our_numbers_beside_the_papers(tmp_path):
    report = write(tmp_path, plots=False, cost=False).read_text()
    for heading in ("## 1. Acceleration", "## 2. Tipping torque", "## 3. Constant distances"):
        assert heading in report
    assert "15.8 – 22.4" in report and "~3°, then ~1/3° in a second motion" in report
    assert "| ours: grip on the moving surface | 20.00 – 28.00 |" in report
    for name in ("acceleration", "tipping_torque", "constant_distances", "constant_distances_along"):
        assert (tmp_path / "runs" / name / "recording.csv").exists()
    assert (tmp_path / "variants" / "tipping_torque_k16.yaml").exists()


def test_the_cli_runs_the_named_report_into_its_folder(tmp_path, monkeypatch, capsys):
    calls = []

    def fake_write(out, plots, progress):
        calls.append((out, plots))
        progress("step")
        return out / "report.md"

    monkeypatch.setattr("hub.reports.paper_report.write", fake_write)
    assert main(["report", "paper", "--out", str(tmp_path), "--no-plots"]) == 0
    assert calls == [(tmp_path, False)]
    assert f"planthub report paper: {tmp_path / 'report.md'}" in capsys.readouterr().out


def test_plots_are_drawn_as_png(tmp_path):
    path = draw(tmp_path / "p.png", [Panel("title", "x", "y", [Line([0, 1, 2], [0, 1, 4], "a"), Line([0, 2], [1, 1])])])
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
