"""`make bench`: one report — build/bench/report.md with its PNG plots, and report.json with every figure.

Sections, in order: the headline figures; speed against error, scene by scene
(tests/bench_error.py), each with a plot of cost against error, its Pareto front and where the
defaults sit; the hub against bare pybullet for 10 … 1000 bottles; and the cost sections that
`make bench` printed before the report (plant elements, bottle models, FMU stepping, latency, the
recorder, Zenoh, the bottling plant, Petri nets, the view), each next to its floor. Those
sections still print their markdown tables; here they are captured, put into report.md as they
are, and their tables parsed into report.json (a cell that reads as a number becomes one).

Benchmarks report; they assert nothing. The report is never committed; a whole report also writes
the benchmark section of tests/README.md, between its markers (tests/bench_readme.py).
`python -m tests.bench_report error` (or `scaling`, `costs`) makes only those parts, and leaves
tests/README.md alone.
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import platform
import re
import statistics
import sys
import time
from pathlib import Path

from hub.run.assembly import Run

from .helpers import ROOT

OUT = ROOT / "build" / "bench"


class Report:
    """Markdown sections and the figures behind them, written once at the end."""

    def __init__(self, out: Path):
        self.out = out
        self.sections: list[str] = []
        self.figures: dict = {}
        self.failures: list[str] = []      # sections that raised: the report says so and make bench fails
        out.mkdir(parents=True, exist_ok=True)
        for old in out.glob("*.png"):
            old.unlink()

    def add(self, markdown: str) -> None:
        self.sections.append(markdown.rstrip() + "\n")
        print(markdown.rstrip() + "\n", flush=True)

    def write(self, headline: str) -> Path:
        (self.out / "report.json").write_text(json.dumps(self.figures, indent=1, ensure_ascii=False) + "\n")
        path = self.out / "report.md"
        path.write_text(headline.rstrip() + "\n\n" + "\n".join(self.sections))
        return path


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" if i == 0 else "---:" for i in range(len(header))) + "|"]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def number(cell: str):
    """A table cell as a number where it reads as one ('1530', '4.6×', '+2.1 %', '0.83 ms': the
    unit stays in the column's heading), else the text."""
    text = cell.strip().replace("−", "-")
    match = re.fullmatch(r"([+-]?\d+(?:\.\d+)?(?:e[+-]?\d+)?)\s*(×|%|ms|µs|s|mm|°|MB)?", text)
    return float(match.group(1)) if match else text


def parse_tables(markdown: str) -> list[dict]:
    """Every markdown table in `markdown`, with the heading above it: {title, rows: [{column: cell}]}."""
    out, title, lines = [], "", markdown.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("#"):
            title = line.lstrip("#").strip()
        if line.startswith("|") and i + 1 < len(lines) and re.fullmatch(r"\|[-:| ]+\|", lines[i + 1].strip()):
            header = [c.strip() for c in line.strip().strip("|").split("|")]
            rows, i = [], i + 2
            while i < len(lines) and lines[i].startswith("|"):
                cells = [c.strip() for c in lines[i].strip().strip("|").split("|")]
                rows.append({h: number(c) for h, c in zip(header, cells)})
                i += 1
            out.append({"title": title, "rows": rows})
            continue
        i += 1
    return out


def captured(report: Report, key: str, fn, *args) -> None:
    """Run a section that prints markdown; keep its text for report.md and its tables for report.json."""
    began = time.perf_counter()
    buffer = io.StringIO()
    try:
        with contextlib.redirect_stdout(buffer):
            fn(*args)
    except Exception as exc:   # the other sections still run and the report is written; make bench then fails
        report.failures.append(f"{key}: {type(exc).__name__}: {exc}")
        buffer.write(f"\n**This section failed**: {type(exc).__name__}: {exc}\n")
    text = buffer.getvalue()
    report.figures.setdefault("costs", {})[key] = {"tables": parse_tables(text),
                                                   "wall_s": round(time.perf_counter() - began, 1)}
    report.add(text)


# --- speed against error ------------------------------------------------------------------------
def guarded(report: Report, key: str, section, instead):
    """Run a section that writes into the report itself; if it raises, say so and go on."""
    try:
        return section(report)
    except Exception as exc:   # the other sections still run and the report is written; make bench then fails
        report.failures.append(f"{key}: {type(exc).__name__}: {exc}")
        report.add(f"**The {key} section failed**: {type(exc).__name__}: {exc}")
        return instead


def error_sections(report: Report) -> dict:
    from . import bench_error

    report.add("# Speed against error\n\n" + bench_error.__doc__.split("\n\n", 1)[1].strip() + "\n\n" + DEFAULTS_WHY)
    found = {}
    for scene in bench_error.scenes():
        began = time.perf_counter()
        points, reference = bench_error.sweep(scene, progress=lambda line: print(line, file=sys.stderr, flush=True))
        found[scene.name] = (scene, points)
        plot = plot_scene(report.out / f"error_{scene.name}.png", scene, points)
        report.figures.setdefault("error", {})[scene.name] = {
            "title": scene.title, "against": scene.against, "headline": scene.headline,
            "reference": scene.reference if scene.against == "reference" else None,
            "reference_cost_s_per_s": reference.cost if reference else None,
            "wall_s": round(time.perf_counter() - began, 1),
            "points": [{"axis": p.setting.axis, "setting": p.setting.label, "overrides": p.setting.overrides,
                        "cost_s_per_s": p.cost, "errors": p.errors, "diverged": p.diverged or None,
                        "pareto": p.front, "default": p.default} for p in points]}
        report.add(scene_section(scene, points, reference, plot))
    return found


DEFAULTS_WHY = """\
**Why the defaults are what they are.** 150 Hz is the paper's rate and the lowest at which every
scene here stays sound: at 60 and 100 Hz a 20 g bottle put on a 1 m/s belt rocks far further (and
at 60 Hz falls over), and a pressed queue gives more; above it, cost grows in proportion while the
error left is mostly the engine's own position update (v·dt/2), which only a higher rate shrinks.
The belt law is integrated exactly (`run.integrator: exact`): at equal cost the paper's explicit
update errs by its first order (k·dt) and diverges once k·dt > 2. 20 solver iterations: a free
bottle needs few and a pressed queue 20 to give by about a millimetre; 50 costs more for little.
`simple` bottles (gripped at the centre of mass) because they do not rock: the analytical spin-up
is met exactly, where `base_point` and `base_body` trade that for the paper's tipping. `grip:
surface`, because `along` (the paper's) leaves bottles to slide along the rails of curves. Rest
on, because it changes no figure here and saves the engine's work for standing bottles."""


def fmt(value: float | None, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if value == 0:
        return "0"
    return f"{value:.{digits}g}"


def scene_section(scene, points, reference, plot: Path | None) -> str:
    default = next(p for p in points if p.default)
    metrics = list(dict.fromkeys(m for p in points for m in p.errors))
    rows = []
    for p in points:
        cost = "diverged" if p.cost is None else f"{p.cost:.4f}"
        speed = "—" if p.cost is None else f"{1 / p.cost:.0f}×"
        ratio = "—" if p.cost is None or default.cost is None else f"{p.cost / default.cost:.2f}"
        cells = [fmt(p.errors.get(m)) for m in metrics] if p.cost is not None else [p.diverged] + [""] * (len(metrics) - 1)
        rows.append([p.setting.axis, p.setting.label, cost, speed, ratio, *cells,
                     ("**front**" if p.front else "") + (" default" if p.default else "")])
    text = [f"## {scene.title}\n",
            f"Error against the {'analytical solution' if scene.against == 'analytical' else 'reference run'}"
            + (f" ({', '.join(f'`{k}: {v}`' for k, v in scene.reference.items())}; it costs "
               f"{reference.cost:.3f} s per simulated s)" if reference else "") + f"; the plot draws *{scene.headline}*.\n",
            table(["varied", "setting", "wall s per simulated s", "real-time factor", "cost × default", *metrics,
                   "Pareto"], rows)]
    cheaper = [p for p in points if p.cost is not None and p.cost < default.cost and scene.headline in p.errors
               and p.errors[scene.headline] <= default.errors.get(scene.headline, math.inf)]
    if default.front:
        text.append("\nThe default is on the Pareto front: nothing measured here is both cheaper and more accurate.")
    elif cheaper:
        best = min(cheaper, key=lambda p: p.cost)
        text.append(f"\nCheaper at no more error than the default: {best.setting.axis} {best.setting.label} "
                    f"({best.cost / default.cost:.2f}× its cost) — within this scene; the defaults are chosen over all of them.")
    if plot is not None:
        text.append(f"\n![{scene.name}]({plot.name})")
    return "\n".join(text)


def plot_scene(path: Path, scene, points) -> Path | None:
    """Cost against the headline error, log-log: a marker per varied setting, the front as a step
    line, the default as a star, diverged settings as crosses along the top."""
    from hub.reports.plots import _pyplot

    plt = _pyplot()
    alive = [p for p in points if p.cost is not None and scene.headline in p.errors]
    if not alive:
        return None
    floor = min((p.errors[scene.headline] for p in alive if p.errors[scene.headline] > 0), default=1e-6)
    y = lambda p: max(p.errors[scene.headline], floor / 3)   # a zero error drawn at the bottom, said in the legend
    fig, ax = plt.subplots(figsize=(8, 5))
    axes = list(dict.fromkeys(p.setting.axis for p in points))
    markers = "os^vDPX<>hp*"
    for i, axis in enumerate(axes):
        mine = [p for p in alive if p.setting.axis == axis and not p.default]
        if mine:
            ax.scatter([p.cost for p in mine], [y(p) for p in mine], marker=markers[i % len(markers)], s=36, label=axis)
            for p in mine:
                ax.annotate(p.setting.label, (p.cost, y(p)), fontsize=7, xytext=(4, 3), textcoords="offset points")
    front = sorted((p for p in alive if p.front), key=lambda p: p.cost)
    if front:
        ax.step([p.cost for p in front], [y(p) for p in front], where="post", color="black", lw=1, alpha=0.6,
                label="Pareto front")
    default = next(p for p in alive if p.default) if any(p.default for p in alive) else None
    if default:
        ax.scatter([default.cost], [y(default)], marker="*", s=220, color="gold", edgecolor="black", zorder=5,
                   label="default")
    top = max(y(p) for p in alive) * 3
    dead = [p for p in points if p.cost is None]
    for p in dead:
        ax.annotate(f"{p.setting.axis} {p.setting.label}: diverged", (0.02, 0.97 - 0.05 * dead.index(p)),
                    xycoords="axes fraction", fontsize=8, color="tab:red", va="top")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(floor / 5, top)
    ax.set_xlabel("wall s per simulated s (lower: faster)")
    ax.set_ylabel(scene.headline + (" (0 drawn at the bottom)" if any(p.errors[scene.headline] == 0 for p in alive) else ""))
    ax.set_title(scene.title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def paper_speed_up(found: dict) -> list[list[str]]:
    """For the scenes with an analytical answer: the paper's explicit law at 150 Hz beside the
    default (exact, 150 Hz: the same cost) and the cheapest exact setting whose error, in the
    scene's headline metric, is no larger — its speed-up over the paper's model."""
    rows = []
    for scene, points in found.values():
        if scene.against != "analytical":
            continue
        paper = next((p for p in points if p.setting.axis.startswith("explicit") and p.setting.label == "150 Hz"), None)
        default = next((p for p in points if p.default), None)
        if paper is None or paper.cost is None or default is None:
            continue
        metric = scene.headline
        # The same scene with the exact law: the default and its physics rates (not settings that change the plant).
        exact = [p for p in points if p.cost is not None and p.setting.axis in ("default", "physics rate")
                 and p.errors.get(metric, math.inf) <= paper.errors[metric]]
        best = min(exact, key=lambda p: p.cost) if exact else None
        rows.append([scene.name, metric, fmt(paper.errors[metric]), fmt(default.errors[metric]),
                     "—" if best is None else f"{best.setting.axis} {best.setting.label}: {fmt(best.errors[metric])}",
                     "—" if best is None else f"{paper.cost / best.cost:.2f}×"])
    return rows


# --- the hub against bare pybullet --------------------------------------------------------------
def warm_cost(scenario, warm: int, ticks: int, engine_only: bool) -> float:
    """Median s per tick over `ticks` ticks after the hub ran `warm` ticks: the hub's step loop, or
    (`engine_only`) bare pybullet stepping the same bodies on from that same state."""
    samples = []
    for _ in range(5):
        with Run(scenario) as run:
            run.run(until_tick=warm)
            started = time.perf_counter()
            if engine_only:
                run.plant.world.step_engine_only(ticks)
            else:
                run.run(until_tick=warm + ticks)
            samples.append((time.perf_counter() - started) / ticks)
    return statistics.median(samples)


def scaling_section(report: Report) -> dict:
    from .bench import line_scene

    counts, warm, ticks = (10, 100, 300, 500, 1000), 75, 225
    rows, figures = [], []
    for n in counts:
        scenario = line_scene(n, seconds=(warm + ticks) / 150)
        hub, bare = warm_cost(scenario, warm, ticks, False), warm_cost(scenario, warm, ticks, True)
        free = warm_cost(line_scene(n, seconds=(warm + ticks) / 150, transport="free"), warm, ticks, False)
        figures.append({"bottles": n, "hub_us_per_tick": 1e6 * hub, "bare_us_per_tick": 1e6 * bare,
                        "free_us_per_tick": 1e6 * free})
        rows.append([str(n), f"{1e6 * hub:.0f}", f"{1e6 * bare:.0f}", f"{hub / bare:.2f}",
                     f"{1 / (hub * scenario.run.physics_rate):.2f}×", f"{1e6 * free:.0f}", f"{free / bare:.2f}",
                     f"{1 / (free * scenario.run.physics_rate):.2f}×"])
        print(f"  scaling: {n} bottles", file=sys.stderr, flush=True)
    real_time = {kind: crossing(counts, [f[f"{kind}_us_per_tick"] for f in figures], 1e6 / 150)
                 for kind in ("hub", "bare", "free")}
    said = {kind: fmt(n) if n is not None else f"more than {counts[-1]}"
            if figures[-1][f"{kind}_us_per_tick"] < 1e6 / 150 else f"fewer than {counts[0]}" for kind, n in real_time.items()}
    sensors = []
    for barriers in (0, 10, 50, 100):
        scenario = line_scene(50, seconds=(warm + ticks) / 150, barriers=barriers)
        sensors.append((barriers, warm_cost(scenario, warm, ticks, False)))
    print("  scaling: sensors", file=sys.stderr, flush=True)
    report.figures["scaling"] = {"points": figures, "bottles_in_real_time_150Hz": real_time, "said": said,
                                 "sensors": [{"barriers": b, "hub_us_per_tick": 1e6 * c} for b, c in sensors]}
    report.add("# The hub against bare pybullet: N bottles on one belt\n\n"
               f"150 Hz, every bottle awake and riding a running belt. After {warm} ticks of the hub, {ticks} ticks "
               "timed: the hub's step loop, and in a second run bare pybullet stepping the same bodies on from the "
               "same state (no fields, reads or triggers; the bottles coast on): the floor. Medians of 5. (Timed "
               "from the very start instead, the floor never moves a bottle and costs about twice as much — "
               "300 bottles: 2876 against 1385 µs a tick, measured 2 December 2026; why standing bottles cost "
               "Bullet more than coasting ones we have not found.)\n\n"
               + table(["bottles", "hub µs/tick", "bare pybullet µs/tick", "hub / bare", "hub real-time factor",
                        "hub, free transport µs/tick", "free / bare", "its real-time factor"], rows)
               + f"\n\nBottles in real time at 150 Hz on one core (6667 µs a tick; interpolated): hub "
                 f"{said['hub']}, bare pybullet {said['bare']}, hub with free transport (`transport: free`: "
                 f"the bottles ride the belt outside the engine) {said['free']}.\n\n"
               "Light barriers: 50 bottles on the belt, N barriers past them, each recorded (so its trigger is "
               "evaluated at every tick); the floor is the same run without one.\n\n"
               + table(["light barriers", "hub µs/tick", "× none", "µs per barrier"],
                       [[str(b), f"{1e6 * c:.0f}", f"{c / sensors[0][1]:.2f}",
                         "—" if b == 0 else f"{1e6 * (c - sensors[0][1]) / b:.2f}"] for b, c in sensors])
               + "\n\nFMUs and participants next to their floors: *Logic stepping* (an FMU step against the same "
                 "logic as a Python call) and *Lockstep over Zenoh* (against bare Zenoh ping-pong), below.")
    return report.figures["scaling"]


def crossing(counts, costs, budget: float) -> float | None:
    """Where cost per tick (growing with the count) crosses `budget`, interpolated linearly; None outside."""
    for (n0, c0), (n1, c1) in zip(zip(counts, costs), zip(counts[1:], costs[1:])):
        if c0 <= budget <= c1:
            return n0 + (budget - c0) * (n1 - n0) / (c1 - c0)
    return None


# --- the hard cases at full length (make stability) ---------------------------------------------
def stability_section(report: Report) -> None:
    """build/bench/stability.json, which `make stability` writes (it takes ~25 min, so `make bench`
    does not run it): each long hard case, its bounds and what was measured."""
    path = OUT / "stability.json"
    if not path.is_file():
        report.add("# Hard cases at full length\n\nNot in this report: `make stability` runs them (10 simulated "
                   "minutes of a jam, an hour of the paper's loop and of the bottling plant; ~25 min) and writes "
                   "build/bench/stability.json, which the next `make bench` puts here.")
        return
    found = json.loads(path.read_text())
    report.figures["stability"] = found
    rows = [[c["name"], f"{c['simulated_seconds']:g}", f"{c['wall_seconds']:.0f}", "passed" if c["passed"] else
             "**failed**" + (f": {c['error']}" if c["error"] else ""),
             "; ".join(f"{b['name']} {fmt(b['measured']) if isinstance(b['measured'], float) else b['measured']}"
                       f"{(' ' + b['unit']) if b['unit'] else ''} ({'≥' if b['relation'] == '>=' else '≤'} {b['limit']:g})"
                       for b in c["bounds"])] for c in found["cases"]]
    report.add("# Hard cases at full length (`make stability`)\n\n"
               f"From {path.name} ({time.strftime('%Y-%m-%d %H:%M', time.localtime(path.stat().st_mtime))}); the "
               "bounds and what they were set from are in tests/hard/cases.py.\n\n"
               + table(["case", "simulated s", "wall s", "result", "bounds: measured (bound)"], rows))


# --- the cost sections of before ----------------------------------------------------------------
def cost_sections(report: Report) -> None:
    from . import bench, bench_view
    from .bench_bottling import bottling_plant
    from .bench_bus import bus_lockstep, data_plane, watched_plant
    from .bench_campaign import campaign
    from .bench_checkpoint import checkpoints
    from .bench_gateway import gateway
    from .bench_hall import scale
    from .bench_plant import plant_elements
    from .fmus import bench_petri

    report.add("# What the hub costs, each next to its floor")
    for key, fn, args in (("bottle_models", bench.bottle_models, ()), ("fmu_stepping", bench.fmu_stepping, ()),
                          ("model_exchange", bench.model_exchange, ()),
                          ("event_latency", bench.event_latency, ()), ("plant_elements", plant_elements, ()),
                          ("flush", bench.flush_cost, ()), ("lockstep", bus_lockstep, ()), ("data_plane", data_plane, ()),
                          ("watched_plant", watched_plant, ()), ("bottling_plant", bottling_plant, ()), ("scale", scale, ()),
                          ("gateway", gateway, ()), ("campaign", campaign, ()), ("checkpoints", checkpoints, ()),
                          ("petri", bench_petri.markdown, ()), ("view", bench_view.main, ([],))):
        captured(report, key, fn, *args)


def main(parts: list[str]) -> int:
    began = time.perf_counter()
    report = Report(OUT)
    report.figures["machine"] = {"python": sys.version.split()[0], "platform": platform.platform(),
                                 "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    parts = parts or ["error", "scaling", "costs"]
    found, scaling = {}, None
    if "error" in parts:
        found = guarded(report, "error", error_sections, {})
    if "scaling" in parts:
        scaling = guarded(report, "scaling", scaling_section, None)
    stability_section(report)
    if "costs" in parts:
        cost_sections(report)
    headline = ["# planthub benchmark report", "",
                f"Made by `make bench` on {report.figures['machine']['started']} (Python "
                f"{report.figures['machine']['python']}); every figure in report.json. Medians of several runs on a noisy "
                "2-core machine: read the ratios.", "", "## Headline figures", ""]
    rows = paper_speed_up(found)
    if rows:
        headline += ["The paper's force law integrated explicitly at 150 Hz against the default (exact, 150 Hz) and "
                     "the cheapest exact setting with no more error (scenes with an analytical answer):", "",
                     table(["scene", "error", "paper 150 Hz explicit", "default (the same cost)", "cheapest exact "
                            "at ≤ the paper's error", "its speed-up over the paper's"], rows), ""]
        report.figures["paper_speed_up"] = rows
    if scaling:
        by = {p["bottles"]: p for p in scaling["points"]}
        headline += [table(["figure", "value"], [
            [f"hub / bare pybullet, {n} bottles on a belt", f"{by[n]['hub_us_per_tick'] / by[n]['bare_us_per_tick']:.2f}"]
            for n in (100, 1000) if n in by] + [
            ["bottles on one belt in real time at 150 Hz (hub)", scaling["said"]["hub"]],
            ["the same, bare pybullet", scaling["said"]["bare"]],
            ["the same, hub with free transport", scaling["said"]["free"]]] + [
            [f"hub with free transport / bare pybullet, {n} bottles on a belt",
             f"{by[n]['free_us_per_tick'] / by[n]['bare_us_per_tick']:.2f}"] for n in (100, 1000) if n in by]), ""]
    headline += [f"**Sections that failed**: {'; '.join(report.failures)}", ""] if report.failures else []
    headline.append(f"The whole report took {(time.perf_counter() - began) / 60:.1f} min.")
    report.figures["failures"] = report.failures
    report.figures["wall_minutes"] = round((time.perf_counter() - began) / 60, 1)
    path = report.write("\n".join(headline))
    if set(parts) >= {"error", "scaling", "costs"}:
        from . import bench_readme

        bench_readme.write(report.figures)
        print(f"wrote the benchmark section of {bench_readme.README}", flush=True)
    print("\n".join(headline))
    print(f"\nwrote {path} and report.json, with {len(list(OUT.glob('*.png')))} plots", flush=True)
    for failure in report.failures:
        print(f"section failed: {failure}", file=sys.stderr)
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
