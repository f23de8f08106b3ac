"""`python -m hub report paper`: runs the paper's three plausibility tests and writes report.md with PNG plots."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from hub.reports import paper
from hub.reports.plots import Line, Panel, draw
from hub.reports.runs import Run, run


def write(out: Path, *, plots: bool = True, cost: bool = True, progress=None) -> Path:
    """Run everything, write `out/report.md` (and `out/*.png`, `out/runs/`, `out/variants/`)."""
    out = Path(out)
    (out / "variants").mkdir(parents=True, exist_ok=True)
    say = progress or (lambda message: None)
    parts = [_HEADER]
    say("1/3 acceleration")
    parts.append(_acceleration(out, plots))
    say("2/3 tipping torque")
    parts.append(_tipping(out, plots))
    say("3/3 constant distances")
    parts.append(_distances(out, plots))
    if cost:
        say("cost of the bottle models")
        parts.append(_cost())
    report = out / "report.md"
    report.write_text("\n".join(parts), encoding="utf-8")
    return report


_HEADER = """# The paper's plausibility tests, reproduced

Rilling & Lochmann, *Physically Based Real-time Simulation of an Automation Plant*, section
RESULTS: three scenes, physics at 150 Hz, friction and restitution 0. The scenarios are in
`scenarios/paper/`; every run's recording is in `runs/`, every variant scenario this report
made in `variants/`. `tests/paper/` asserts the facts below; this page shows them.
"""


def _run(out: Path, path: Path, name: str, overrides: dict | None = None) -> Run:
    return run(path, out / "runs" / name, overrides)


def _variant(out: Path, path: Path, name: str, change) -> Path:
    """A copy of a scenario with `change(data)` applied, kept beside the report."""
    data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    change(data)
    data["name"] = name
    target = out / "variants" / f"{name}.yaml"
    target.write_text(f"# Made by `python -m hub report paper` from {Path(path).name}.\n"
                      + yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return target


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---:" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


# --- 1 ----------------------------------------------------------------------------------------
def _acceleration(out: Path, plots: bool) -> str:
    result = _run(out, paper.ACCELERATION, "acceleration")
    curves = paper.acceleration(result)
    rows = [[f"{c.k:g}", f"{1000 * c.max_error * c.speed:.2g} mm/s", f"{100 * c.max_error:.2g} %",
             f"{c.t90:.3f} s", f"{c.t90_analytical:.3f} s"] for c in curves]
    if plots:
        lines = []
        for c in curves:
            lines.append(Line(c.time, c.velocity, f"k = {c.k:g}: simulated"))
            lines.append(Line(c.time, c.analytical, f"k = {c.k:g}: v_tar·(1 − e^(−k·t))", "--", 1.0))
        draw(out / "acceleration.png", [Panel("Bottle dropped on a belt at 0.5 m/s", "time (s)",
                                              "velocity along the belt (m/s)", lines)])
    return f"""
## 1. Acceleration (the paper's Fig. 13)

A bottle dropped from 5 mm onto a belt at 0.5 m/s, for k = 1, 4 and 16 (`acceleration.yaml`).
The paper shows the curves (k = 16 "simulates a non-slip traction") without numbers. Ours
follow v(t) = v_tar·(1 − e^(−k·t)) at every recorded tick, because each physics tick applies
the force that reaches the exact solution of the field's law (stable at any k·dt):

{_table(["k (1/s)", "largest error", "of belt speed", "90 % of speed at", "analytical"], rows)}

![velocity over time](acceleration.png)
"""


# --- 2 ----------------------------------------------------------------------------------------
def _tipping(out: Path, plots: bool) -> str:
    main = paper.tipping(_run(out, paper.TIPPING, "tipping_torque"))

    def mass_scaled(k):
        def change(data):
            for spec in data["objects"].values():
                if spec["module"] == "conveyor":
                    spec.pop("gain")
                    spec["k"] = k
        return change

    scaled = paper.tipping(_run(out, _variant(out, paper.TIPPING, "tipping_torque_k3", mass_scaled(3.0)),
                                "tipping_torque_k3"))
    toppled = paper.tipping(_run(out, _variant(out, paper.TIPPING, "tipping_torque_k16", mass_scaled(16.0)),
                                 "tipping_torque_k16"))
    fractions = paper.tipping(_run(out, _fraction_sweep(out), "tipping_base_fraction"))

    by = {t.bottle: t for t in main}
    masses = sorted({round(t.mass * 1000) for t in main if t.model == "base_body"})

    def cell(group, m, of=None):
        t = (of or by).get(f"{group}_{m}")
        return f"{t.first:.2f}° / {t.second:.2f}°" if t else ""

    paper_says = {20: paper.PAPER["tilt_20g"], 80: paper.PAPER["tilt_80g"]}
    rows = [[f"{m} g", paper_says.get(m, ""), cell("paper", m), cell("point", m), cell("centre", m)] for m in masses]
    by_scaled = {t.bottle: t for t in scaled}
    by_toppled = {t.bottle: t for t in toppled}
    rows_k = [[f"{m} g", cell("paper", m, by_scaled), cell("point", m, by_scaled),
               f"{by_toppled[f'point_{m}'].final:.0f}°"] for m in masses]
    rows_f = [[_share(t.bottle), f"{t.first:.2f}°", f"{t.second:.2f}°"] for t in fractions]
    if plots:
        panels = []
        for group, title in (("paper", "second body at the base (the paper's model)"),
                             ("point", "force at the base point")):
            lines = [Line(by[f"{group}_{m}"].time, by[f"{group}_{m}"].pitch, f"{m} g") for m in masses]
            lines += [Line(by[f"centre_{m}"].time, by[f"centre_{m}"].pitch, f"{m} g, force at the centre (control)",
                           ":", 1.0) for m in (20, 80) if f"centre_{m}" in by]
            panels.append(Panel(f"Put on a belt at 1.0 m/s: {title}", "time (s)",
                                "inclination forward (°)", lines))
        draw(out / "tipping.png", panels)
        lines = [Line(t.time, t.pitch, _share(t.bottle)) for t in fractions]
        draw(out / "tipping_models.png", [Panel("20 g: second body by its share of the mass, and base point",
                                                "time (s)", "inclination forward (°)", lines)])
    floor = max(by[f"centre_{m}"].first for m in (20, 80) if f"centre_{m}" in by)
    return f"""
## 2. Tipping torque (the paper's Fig. 14)

Bottles (r = 3 cm, h = 10 cm) of 20 to 80 g put at rest on belts running at 1.0 m/s
(`tipping_torque.yaml`), each gripped by one of three models. The belts use the paper's
unscaled law F = gain·(v_tar − v) with gain = 0.15 N·s/m, so a lighter bottle is dragged up to
speed faster (rate gain/m: 7.5/s at 20 g, 1.9/s at 80 g) — the mechanism behind the paper's
finding. Largest inclination from the plumb line in the direction of motion, first motion /
largest after it has died down to a tenth:

{_table(["mass", "paper", "second body (paper's model)", "force at base point", "force at centre (control)"], rows)}

![inclination over time](tipping.png)

- **Lighter bottles rock more**, as in the paper: the 20 g bottle rocks back by a few degrees and
  settles in a smaller second motion; from about 35 g on, the inclination is at the floor that the
  control bottle shows without any torque ({floor:.2f}°): Bullet's rigid contact rocks a sliding
  cylinder by a few tenths of a degree. A rigid bottle on a rigid belt does not lean at all below
  the tipping threshold: the base acceleration must exceed g·r/h_c = 9.81·0.03/0.05 = 5.9 m/s²
  (here gain·Δv/m: 7.5 m/s² at 20 g, 4.3 m/s² at 35 g). The paper's ~1° at 80 g is below that
  floor in a rigid model; its engine's contacts were presumably softer.
- **Second body or base point**: as the second body's share of the mass goes to 0 the paper's model
  becomes the base-point model; the share (which the paper does not give) sets how much the base
  weighs the bottle down (20 g at 1.0 m/s):

{_table(["model", "first motion", "after it"], rows_f)}

![the models compared](tipping_models.png)

- **With our mass-scaled law** (`k` instead of `gain`: F = k·m·(v_tar − v), as friction scales)
  every bottle of one shape rocks alike, whatever it weighs (k = 3/s, the rate the gain gives a
  50 g bottle), and with k = 16/s at 1.0 m/s the base accelerates at 16 m/s², far over the
  threshold: every bottle falls over (final inclination). A real belt cannot pull harder than
  friction allows (μ·g ≈ 3–5 m/s²), so real bottles slip instead of falling:

{_table(["mass", "k = 3: second body", "k = 3: base point", "k = 16: base point, final"], rows_k)}
"""


def _share(bottle: str) -> str:
    """`share_5` → "second body, 5 % of the mass"; `base_point` → "force at the base point"."""
    if bottle.startswith("share_"):
        return f"second body, {bottle.split('_')[1]} % of the mass"
    return "force at the base point (share → 0)"


def _fraction_sweep(out: Path) -> Path:
    """20 g bottles on parallel belts: the paper's model at several mass shares, and the base point."""
    objects = {}
    for i, share in enumerate((0.01, 0.05, 0.1, 0.2, None)):
        y = 0.25 * i
        objects[f"belt_{i}"] = {"module": "conveyor", "position": [0, y, 0], "length": 2.5, "speed": 1.0, "gain": 0.15}
        bottle = {"module": "bottle", "position": [0.04, y, 0], "mass": 0.02}
        name = "base_point"
        if share is not None:
            bottle.update(model="base_body", base_fraction=share)
            name = f"share_{round(100 * share)}"
        else:
            bottle["model"] = "base_point"
        objects[name] = bottle
    data = {"planthub": 1, "name": "tipping_base_fraction",
            "description": "20 g bottles at 1.0 m/s: the second body's mass share against the base-point model.",
            "run": {"duration": 2.0, "physics_rate": 150}, "objects": objects,
            "record": [f"{n}.body.orientation" for n, o in objects.items() if o["module"] == "bottle"]}
    target = out / "variants" / "tipping_base_fraction.yaml"
    target.write_text("# Made by `python -m hub report paper`.\n" + yaml.safe_dump(data, sort_keys=False),
                      encoding="utf-8")
    return target


# --- 3 ----------------------------------------------------------------------------------------
def _distances(out: Path, plots: bool) -> str:
    belts = [name for name, spec in yaml.safe_load(paper.DISTANCES.read_text())["objects"].items()
             if spec["module"] in ("conveyor", "curve")]
    along = {f"objects.{b}.grip": "along" for b in belts}
    coarse = {**along, **{f"objects.{b}.rail_tolerance": 0.005 for b in belts if b.startswith("c")}}
    variants = [
        ("ours: grip on the moving surface", paper.distances(_run(out, paper.DISTANCES, "constant_distances"))),
        ("the paper's law: grip along the belt only",
         paper.distances(_run(out, paper.DISTANCES, "constant_distances_along", along))),
        ("the paper's law, rails 5 mm off the arc",
         paper.distances(_run(out, paper.DISTANCES, "constant_distances_along_coarse", coarse))),
    ]
    rows = [["paper", f"{paper.PAPER['distance_min_cm']} – {paper.PAPER['distance_max_cm']}",
             f"{paper.PAPER['distance_variance_cm2']}", "", "", "", ""]]
    for label, d in variants:
        mn, mx, var = d.stats(d.manhattan)
        gmin, gmax, gvar = d.stats(d.gap)
        dev = d.stats(d.manhattan - d.reference)
        rows.append([label, f"{mn:.2f} – {mx:.2f}", f"{var:.3g}", f"{dev[0]:+.3f} – {dev[1]:+.3f}",
                     f"{gmin:.4f} – {gmax:.4f}", f"{gvar:.2g}",
                     f"{1000 * np.max(np.abs(d.lateral)):.1f} mm / {np.max(d.tilt):.2f}°"])
    ours = variants[0][1]
    if plots:
        t = ours.time
        manhattan = [Line(t, 100 * d.manhattan, label, width=1.0) for label, d in variants]
        manhattan.append(Line(t, 100 * ours.reference, "two points 20 cm apart on the centre line", "k:", 1.0))
        gaps = [Line(t, 100 * d.gap, label, width=1.0) for label, d in variants]
        draw(out / "distances.png", [
            Panel("Manhattan distance between the two bottles (the paper's measure)", "time (s)", "cm", manhattan),
            Panel("Distance along the loop's centre line", "time (s)", "cm", gaps)])
    laps = 0.5 * ours.time[-1] / ours.loop_length
    return f"""
## 3. Constant distances

Two bottles 20 cm apart on a closed loop of 1 left and 5 right 90° curves (radius 0.4 m) and 5
straights of 5.0, 1.0, 3.0, 1.2 and 0.2 m, belts at 0.5 m/s, 50 s (`constant_distances.yaml`;
the loop is {ours.loop_length:.3f} m long, the bottles go round {laps:.2f} times, and its end
meets its start within {1000 * ours.closure:.1g} mm). Distances in cm, variances in cm²:

{_table(["model", "Manhattan min – max", "variance", "Manhattan − geometry", "along the loop min – max",
         "variance", "largest offset / tilt"], rows)}

![distances over time](distances.png)

- **The paper's measure mixes geometry into the result.** On a curve two bottles 20 cm apart along
  the belt are a chord apart, and the Manhattan length of that chord depends on its direction:
  on our r = 0.4 m curves it swings between 20 and {100 * ours.reference.max():.1f} cm with no
  physics at all (dotted line). So we also measure the distance along the loop's centre line, and
  the Manhattan distance minus that geometric part.
- **Ours holds the spacing to within {100 * (ours.gap.max() - ours.gap.min()) * 10:.2f} mm over 50 s.** A real
  curved belt is a rotating surface; friction pulls a bottle towards the surface's velocity ω×r in
  both horizontal directions, so the bottle turns with the belt at its own radius, never touches
  a rail, and both bottles follow the same path exactly 60 ticks apart (20 cm at 0.5 m/s is a
  whole number of 1/150 s ticks). What remains is Bullet's contact: a sliding cylinder rides
  2 mm deep in its support and rocks by a few tenths of a degree, which moves its centre of mass
  by fractions of a millimetre.
- **The paper's law** drives only along the belt: a bottle entering a curve keeps going straight
  until the outer rail turns it, then slides along the polygon of rail boxes, losing speed at the
  impact and at the rail's corners. Each curve changes the spacing by up to a centimetre, and
  nothing restores it — on the straights both bottles run at belt speed again — so the spacing
  wanders curve by curve, and sideways velocity left over from a curve is never damped either.
  That is the paper's "susceptible to small geometric meanderings, especially during turns". The
  rail's polygon is not the cause: rails five times coarser (5 mm off the arc instead of 0.5 mm)
  give a spread of the same size ({_spread(variants[2][1])} instead of {_spread(variants[1][1])}).
"""


def _spread(d: paper.Distances) -> str:
    return f"{100 * (d.gap.max() - d.gap.min()):.1f} cm"


# --- cost -------------------------------------------------------------------------------------
def _cost() -> str:
    from hub.reports.cost import lod_costs

    costs = lod_costs(bottles=20, ticks=300, repeats=3)
    by = {(c.model, c.shape, c.on_belt): c.microseconds for c in costs}
    rows = []
    for model in ("simple", "base_point", "base_body"):
        rows.append([model] + [f"{by[(model, shape, on)]:.0f}" for on in (True, False) for shape in ("cylinder", "hull")])
    return f"""
## Cost of the bottle models

Physics world only (engine, belt field, state reads), 20 bottles in a row, µs per tick at
150 Hz, median of 3 runs on this machine (`make bench` measures it with more repeats):

{_table(["model", "on a belt: cylinder", "on a belt: hull", "off every belt: cylinder", "off: hull"], rows)}

The base-point model costs one numpy step for all bottles on a belt and nothing off one; the
paper's second body costs an extra body, a constraint and two state reads per bottle, on a belt
or not.
"""
