"""`make bench`, the view: what recording every body costs (Arrow against CSV), and the bottling
plant's real-time factor with no viewer, with `planthub view` connected, and with a browser on it.

Each figure is a median over rounds that take turns in one run (this 2-core machine is noisy):
read the ratios.
"""
from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario
from modules.source import Source

from .helpers import ROOT

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
SECONDS = 40.0      # simulated: the line fills up to ~70 bottles
ROUNDS = 3


def _bottle_ids(scenario) -> list[str]:
    return [ident for spec in scenario.objects if spec.module is Source
            for ident, _ in Source.bottles(spec.name, spec.params, scenario.run.seed)]


def _timed_run(overrides: dict, out: Path) -> tuple[float, int]:
    """Wall µs per communication point of one run, and its points."""
    scenario = load_scenario(PLANT, {"run.duration": SECONDS, **overrides})
    with Run(scenario, out=out) as run:
        started = time.perf_counter()
        result = run.run()
        wall = time.perf_counter() - started
    points = result.ticks // scenario.run.substeps
    return 1e6 * wall / points, points


def body_recording() -> None:
    print(f"\n## Recording every body: the bottling plant, 0–{SECONDS:g} s, {ROUNDS} rounds taking turns\n")
    base = load_scenario(PLANT)
    ids = _bottle_ids(base)
    as_csv = [f"{i}.body.{slot}" for i in ids for slot in ("position", "orientation")]
    variants = {
        "no bodies recorded": {},
        "bodies.arrows (run.record_bodies: true)": {"run.record_bodies": True},
        f"recording.csv with {len(ids)} bottles' position and orientation": {"record": list(base_record(base)) + as_csv},
    }
    samples = {name: [] for name in variants}
    sizes = {}
    with tempfile.TemporaryDirectory() as tmp:
        for round_ in range(ROUNDS):
            for k, (name, overrides) in enumerate(variants.items()):
                out = Path(tmp) / f"{round_}_{k}"
                us, points = _timed_run(overrides, out)
                samples[name].append(us)
                sizes[name] = sum(f.stat().st_size for f in out.iterdir()
                                  if f.name in ("bodies.arrows", "recording.csv"))
    floor = statistics.median(samples["no bodies recorded"])
    print("| recorded | µs per point (median) | ratio to none | bodies.arrows + recording.csv, MB per 100 s simulated |")
    print("|---|---:|---:|---:|")
    for name, values in samples.items():
        mb = sizes[name] / 1e6 * (100.0 / SECONDS)
        print(f"| {name} | {statistics.median(values):.0f} | {statistics.median(values) / floor:.3f} | {mb:.1f} |")


def base_record(scenario) -> list[str]:
    return [f"{ref}" for ref, _ in scenario.record]


def main() -> int:
    body_recording()
    return 0


if __name__ == "__main__":
    sys.exit(main())
