"""`make bench` writes tests/README.md's benchmark figures from its report, between two markers; nothing else.

The figures are rendered from the report's figures (report.json's dict), never copied by hand: the
headline (the paper's law against the exact one, the hub against bare pybullet) and every table of
each cost section, under its section's name. Text outside the markers is the README's own.
"""
from __future__ import annotations

from pathlib import Path

from .helpers import ROOT

README = ROOT / "tests" / "README.md"
BEGIN, END = "<!-- bench:begin -->", "<!-- bench:end -->"

#: the cost sections' keys (tests/bench_report.py) → their heading here
COST_TITLES = {
    "bottle_models": "Bottle models", "fmu_stepping": "FMU stepping", "model_exchange": "Model exchange",
    "event_latency": "Event latency", "plant_elements": "Plant elements", "flush": "The recorder's flush",
    "lockstep": "Lockstep over Zenoh", "data_plane": "The data plane", "watched_plant": "The plant watched",
    "bottling_plant": "The bottling plant", "gateway": "Gateways", "campaign": "Campaigns",
    "checkpoints": "Checkpoints", "petri": "Petri nets", "view": "The view", "scale": "Scale",
}


def cell(value) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).replace("|", "\\|")


def markdown_table(rows: list[dict]) -> str:
    if not rows:
        return "(no rows)"
    header = list(rows[0])
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(cell(row.get(h, "")) for h in header) + " |" for row in rows]
    return "\n".join(lines)


def render(figures: dict) -> str:
    """The benchmark section for tests/README.md from a report's figures (what report.json holds)."""
    machine = figures.get("machine", {})
    out = [f"Written by `make bench` from its report of {machine.get('started', '(unknown time)')} "
           f"(Python {machine.get('python', '?')}, {machine.get('platform', '?')}); "
           "the whole report, with its plots and the speed-against-error scenes: `build/bench/report.md`. "
           "Medians on a shared machine: read the ratios."]
    if figures.get("failures"):
        out += ["", "**Sections that failed**: " + "; ".join(figures["failures"])]
    if figures.get("paper_speed_up"):
        header = ["scene", "error", "paper 150 Hz explicit", "default (the same cost)",
                  "cheapest exact at ≤ the paper's error", "its speed-up over the paper's"]
        out += ["", "### The paper's law against the exact one", "",
                markdown_table([dict(zip(header, row)) for row in figures["paper_speed_up"]])]
    scaling = figures.get("scaling")
    if scaling:
        rows = [{"bottles": p["bottles"], "hub µs/tick": round(p["hub_us_per_tick"]),
                 "bare pybullet µs/tick": round(p["bare_us_per_tick"]),
                 "hub / bare": round(p["hub_us_per_tick"] / p["bare_us_per_tick"], 2),
                 "hub, free transport µs/tick": round(p["free_us_per_tick"]),
                 "free / bare": round(p["free_us_per_tick"] / p["bare_us_per_tick"], 2)} for p in scaling["points"]]
        said = scaling.get("said", {})
        out += ["", "### The hub against bare pybullet: N bottles on one belt", "", markdown_table(rows), "",
                f"Bottles on one belt in real time at 150 Hz: hub {said.get('hub', '?')}, bare pybullet "
                f"{said.get('bare', '?')}, hub with free transport {said.get('free', '?')}."]
    for key, section in figures.get("costs", {}).items():
        tables = [t for t in section.get("tables", []) if t.get("rows")]
        if not tables:
            continue
        out += ["", f"### {COST_TITLES.get(key, key)}"]
        for t in tables:
            out += ([""] + ([f"*{t['title']}*", ""] if t.get("title") else []) + [markdown_table(t["rows"])])
    if figures.get("wall_minutes") is not None:
        out += ["", f"The report took {figures['wall_minutes']} min."]
    return "\n".join(out) + "\n"


def replace_between_markers(text: str, section: str) -> str:
    """`text` with what stands between the two markers replaced by `section`; the rest kept as it is."""
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        raise ValueError(f"the benchmark markers {BEGIN} … {END} are missing or out of order")
    return text[:start + len(BEGIN)] + "\n" + section.rstrip("\n") + "\n" + text[end:]


def write(figures: dict, readme: Path = README) -> None:
    readme.write_text(replace_between_markers(readme.read_text(encoding="utf-8"), render(figures)), encoding="utf-8")
