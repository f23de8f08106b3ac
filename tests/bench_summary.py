"""What the plant summary costs per tick (`python -m tests.bench_summary [SCENARIO --seconds S]`): runs with and without it, alternately."""
from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import yaml

from hub.run.assembly import Run
from hub.scenario.checker import load_scenario
from modules.plant.summary import PlantTally


def queue_scene(bottles: int, held: bool) -> Path:
    """`bottles` standing on running belts, in queues of five (longer queues climb over each other
    and the rails): at closed stoppers (held), or against a high end wall (jammed) — the most work
    for the jam watch, as every bottle stands."""
    lines = ["planthub: 1", "run: {duration: 60, physics_rate: 300}", "objects:"]
    for k in range(bottles // 5):
        y = 0.2 * k
        lines += [f"  belt{k}: {{module: conveyor, position: [0, {y:.1f}, 0], length: 0.6, width: 0.07}}",
                  f"  sink{k}: {{module: sink, position: [1.0, {y:.1f}, 0.05], accepts: [A]}}"]
        if held:
            lines.append(f"  stop{k}: {{module: stopper, position: [0.5, {y:.1f}, 0], width: 0.07}}")
        else:
            lines.append(f"  wall{k}: {{module: conveyor, position: [0.565, {y - 0.1:.1f}, 0], yaw: 90, length: 0.2, "
                         f"rail_height: 0.12, speed: 0}}")
        lines += [f"  q{k}_{i}: {{module: bottle, position: [{0.4 - i * 0.07:.2f}, {y:.1f}, 0]}}" for i in range(5)]
    path = Path(tempfile.mkdtemp()) / f"queues{bottles}{'held' if held else 'jammed'}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


class Timed:
    """An observer that passes each point on to `tally` and adds the time spent in it to `spent[0]`."""

    def __init__(self, tally: PlantTally, spent: list[float]):
        self.tally, self.spent = tally, spent

    def observe(self, tick, signals, events) -> None:
        started = time.perf_counter()
        self.tally.observe(tick, signals, events)
        self.spent[0] += time.perf_counter() - started

    def close(self, reason: str) -> None:
        self.tally.close(reason)


def measure(path: Path, ticks: int, settle: int, repeats: int, overrides=None) -> tuple[float, float, float]:
    """(µs per tick without the summary, with it, of which inside its looks), medians of `repeats`,
    each pair run alternately after `settle` ticks that are not timed."""
    scenario = load_scenario(path, overrides)
    bare, watched, inside = [], [], []
    for _ in range(repeats):
        for with_summary in (False, True):
            with Run(scenario) as run:
                # The tally the plant's sources and sinks contribute to every Run: taken out of the run
                # without the summary, and timed inside it with.
                observers = run.master.observers
                tally = next((o for o in observers if isinstance(o, PlantTally)), None)
                if tally is not None:
                    observers.remove(tally)
                spent = [0.0]
                if with_summary:
                    observers.append(Timed(tally or PlantTally(run.plant), spent))
                run.run(until_tick=settle)
                started = time.perf_counter()
                spent[0] = 0.0
                run.run(until_tick=settle + ticks)
                us = (time.perf_counter() - started) / ticks * 1e6
            (watched if with_summary else bare).append(us)
            if with_summary:
                inside.append(spent[0] / ticks * 1e6)
    return statistics.median(bare), statistics.median(watched), statistics.median(inside)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("scenario", nargs="?", type=Path, help="a plant scenario (default: the queue scenes)")
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds timed per run")
    parser.add_argument("--settle", type=float, default=5.0, help="simulated seconds run first, untimed")
    parser.add_argument("--repeats", type=int, default=5, help="runs of each kind; the medians are shown")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scenario value, as planthub run --set does")
    args = parser.parse_args(argv)
    print("| scene | bottles standing | run µs/tick | with summary µs/tick | in its looks µs/tick | share |")
    print("|---|---:|---:|---:|---:|---:|")
    scenes = [(args.scenario, "-")] if args.scenario else [
        (queue_scene(n, held), f"{n} {'held at a stopper' if held else 'jammed'}")
        for n in (10, 50, 100) for held in (True, False)]
    for path, label in scenes:
        rate = load_scenario(path).run.physics_rate
        overrides = {k: yaml.safe_load(v) for k, _, v in (o.partition("=") for o in args.overrides)}
        bare, watched, inside = measure(path, round(args.seconds * rate), round(args.settle * rate), args.repeats,
                                        overrides)
        print(f"| {path.stem} | {label} | {bare:.0f} | {watched:.0f} | {inside:.1f} | {100 * inside / bare:.1f} % |",
              flush=True)


if __name__ == "__main__":
    main()
