"""A hall of bottling lines side by side: scenarios/bottling_plant.yaml copied `lines` times into one
scenario, each copy's objects named `l<i>_<name>` and moved `SPACING` m along y, its flows wired
within the copy, its bottles' ids begun with `L<i>`. With ten lines about 1000 bottles are on the
lines from 80 s on (tests/bench_hall.py measures it; tests/test_hall.py checks what it builds)."""
from __future__ import annotations

from pathlib import Path

import yaml

from .helpers import ROOT

PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
SPACING = 4.5          # m: one line spans y = -0.1 … 3.9 (the lanes' sinks)
POINTS = ("position", "pick", "place", "home")   # an object's places in the plant (modules' parameters)


def hall(lines: int, duration: float, runs: str = "hub") -> dict:
    """The hall as a scenario document: `lines` copies of the bottling plant, run for `duration` s,
    its routing participants run where `runs` says (hub, child or bus). The plant's record and
    expectations (of one line) and its order count are left out."""
    plant = yaml.safe_load(PLANT.read_text())
    objects, flows = {}, []
    for line in range(lines):
        prefix = f"l{line}_"
        for key, params in plant["objects"].items():
            params = dict(params)
            for point in POINTS:
                if point in params:
                    x, y, z = params[point]
                    params[point] = [x, y + line * SPACING, z]
            if "after" in params:
                params["after"] = prefix + params["after"]
            if params["module"] == "source":
                params["prefix"] = f"L{line}{params.get('prefix', key)}"
            if params["module"] == "participant":
                params["runs"] = runs
            objects[prefix + key] = params
        for flow in plant["flows"]:
            flows.append({end: prefix + flow[end] for end in ("from", "to")})
    run = {k: v for k, v in plant["run"].items() if k != "orders"}
    run["duration"] = duration
    return {"planthub": 1, "name": f"hall_of_{lines}", "description": f"{lines} bottling lines side by side",
            "run": run, **({"defaults": plant["defaults"]} if "defaults" in plant else {}),
            "objects": objects, "flows": flows}


def write_hall(path: Path, lines: int, duration: float, runs: str = "hub") -> Path:
    path.write_text(yaml.safe_dump(hall(lines, duration, runs), sort_keys=False))
    return path
