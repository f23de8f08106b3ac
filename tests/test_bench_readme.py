"""tests/bench_readme.py: make bench's figures rendered from a report into tests/README.md, between its markers only."""
import pytest

from .bench_readme import BEGIN, END, README, render, replace_between_markers, write

FIGURES = {
    "machine": {"python": "3.11.2", "platform": "Linux-x86_64", "started": "2026-12-04 10:00:00"},
    "paper_speed_up": [["belt_spinup", "velocity", "0.0205", "1e-08", "physics rate 60 Hz: 0.018", "2.40×"]],
    "scaling": {"points": [{"bottles": 100, "hub_us_per_tick": 900.4, "bare_us_per_tick": 400.0,
                            "free_us_per_tick": 100.2}],
                "said": {"hub": "623", "bare": "975", "free": "more than 1000"}},
    "costs": {"lockstep": {"tables": [{"title": "Lockstep over Zenoh",
                                       "rows": [{"participants": 1.0, "ping-pong / hub": 1.27},
                                                {"participants": 4.0, "ping-pong / hub": 1.2}]}], "wall_s": 30.0},
              "flush": {"tables": [], "wall_s": 1.0}},
    "failures": [],
    "wall_minutes": 17.2,
}


def test_the_section_is_rendered_from_the_report():
    text = render(FIGURES)
    assert "2026-12-04 10:00:00" in text and "3.11.2" in text
    assert "| belt_spinup | velocity | 0.0205 | 1e-08 | physics rate 60 Hz: 0.018 | 2.40× |" in text
    assert "| 100 | 900 | 400 | 2.25 | 100 | 0.25 |" in text
    assert "hub 623, bare pybullet 975, hub with free transport more than 1000" in text
    assert "### Lockstep over Zenoh\n\n*Lockstep over Zenoh*\n\n| participants | ping-pong / hub |\n|---|---|\n| 1 | 1.27 |\n| 4 | 1.2 |" in text
    assert "The recorder's flush" not in text   # a section without tables gets no heading
    assert "The report took 17.2 min." in text


def test_a_failed_section_is_said():
    assert "**Sections that failed**: gateway: OSError: boom" in render({**FIGURES, "failures": ["gateway: OSError: boom"]})


def test_only_what_is_between_the_markers_is_replaced(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"# tests\n\nprose before\n\n{BEGIN}\nold figures\n{END}\n\nprose after\n")
    write(FIGURES, readme)
    text = readme.read_text()
    assert text.startswith(f"# tests\n\nprose before\n\n{BEGIN}\nWritten by `make bench`")
    assert text.endswith(f"The report took 17.2 min.\n{END}\n\nprose after\n")
    assert "old figures" not in text
    write(FIGURES, readme)
    assert readme.read_text() == text   # the same report writes the same file


def test_missing_markers_are_an_error():
    with pytest.raises(ValueError, match="markers"):
        replace_between_markers("no markers here", "x")


def test_the_tests_readme_has_the_markers():
    text = README.read_text(encoding="utf-8")
    assert text.count(BEGIN) == 1 and text.count(END) == 1 and text.index(BEGIN) < text.index(END)
