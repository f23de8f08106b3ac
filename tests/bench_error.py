"""`make bench`, speed against error: every setting's cost beside its error, scene by scene.

Each scene is run at its own settings (the *default*: what the scenario file says, itself the
project's defaults unless it says otherwise) and at one changed setting at a time — physics rate,
communication step, solver iterations, bottle model and shape, grip law, rest on or off, event-driven
points, the paper's explicit force law. Cost is wall time per simulated second (the median of
REPEATS runs of the step loop, building excluded); error is measured

- against the **analytical** solution where there is one: a free bottle's belt spin-up,
  v(t) = v_tar·(1 − e^(−k·t)) (the paper's first test), and its arrival at a light barrier;
- otherwise against a **reference run** of the same scene: 1 kHz and 50 solver iterations (the
  paper's loop also with its two-body bottle, `base_body`; the bottling plant at 300 Hz, the
  highest rate at which it is sound — see its scene). Metrics: bottle positions over time (RMS and max of the distance to the
  reference's at its times), event times (each trigger's and sink's events matched in order, the
  largest shift, and how many have no partner), and scene figures (queue depth into the gate, tilt).

A setting the run cannot survive (the explicit law past k·dt = 2 ends in the physics watch) is a
point marked *diverged*, with the watch's message. Nothing here asserts: tests/hard/ does.
"""
from __future__ import annotations

import math
import statistics
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hub.core.errors import SimulationError
from hub.reports import paper, runs
from hub.reports.compare import Recorded, compare
from hub.scenario.checker import load_scenario

from .bench_queue import queue_scene
from .helpers import ROOT
from .test_belt_bottle_sensor import analytical_enter_time

REPEATS = 3
PLANT = ROOT / "scenarios" / "bottling_plant.yaml"
REFERENCE = {"run.physics_rate": 1000, "run.solver_iterations": 50}


@dataclass(frozen=True)
class Setting:
    axis: str                 # what is varied: "physics rate", "solver iterations", …
    label: str                # its value, as the table shows it
    overrides: dict           # --set style overrides on top of the scene's own


DEFAULT = Setting("default", "scenario's own", {})


@dataclass
class Scene:
    name: str
    title: str
    path: Path
    record: list[str]                         # what every run records (numbers only)
    error: Callable                           # (run, reference or None) → {metric: value}
    headline: str                             # the metric the plot draws
    against: str                              # "analytical" or "reference"
    settings: list[Setting]
    base: dict = field(default_factory=dict)  # overrides every run of the scene gets
    reference: dict = field(default_factory=lambda: dict(REFERENCE))
    repeats: int = REPEATS                    # timed runs of each setting (the cost is their median)


@dataclass
class Point:
    setting: Setting
    cost: float | None            # wall s per simulated s (None: it diverged)
    errors: dict[str, float]
    diverged: str = ""            # the watch's message
    front: bool = False           # on the Pareto front of its scene

    @property
    def default(self) -> bool:
        return self.setting is DEFAULT


# --- what each scene measures -------------------------------------------------------------------
def bottle_names(run: runs.Run) -> list[str]:
    return sorted({c.rsplit(".", 3)[0] for c in run.columns if c.endswith(".body.position.x")})


def position_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """Distance of each bottle to where the reference has it, at the reference's times within both
    runs (the run's own samples interpolated linearly): RMS and max over bottles and times, mm."""
    t_ref, t = ref.time, run.time
    keep = (t_ref >= t[0]) & (t_ref <= t[-1])
    squares, worst = [], 0.0
    for name in bottle_names(ref):
        p_ref = ref.vec3(f"{name}.body.position")[keep]
        p = np.stack([np.interp(t_ref[keep], t, run.columns[f"{name}.body.position.{c}"]) for c in "xyz"], axis=1)
        d = np.linalg.norm(p - p_ref, axis=1)
        squares.append(d * d)
        worst = max(worst, float(d.max()))
    return {"position RMS mm": 1000 * math.sqrt(float(np.concatenate(squares).mean())), "position max mm": 1000 * worst}


MATCH_WITHIN = 5.0   # s: how far apart two runs' events may be and still be the same event (matched in order)


def event_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """Each of the reference's events matched to the same slot's and object's in the run, in time
    order (hub/reports/compare.py, within MATCH_WITHIN): the largest time shift (ms) and how many
    on either side have no partner."""
    mine, reference = Recorded.read(run.directory), Recorded.read(ref.directory)
    slots = sorted(set(mine.event_slots) | set(reference.event_slots))
    verdicts = compare(mine, reference, slots=slots, time_shift=MATCH_WITHIN).events if slots else []
    shift = max((abs(v.max_shift) for v in verdicts if v.max_shift is not None), default=0.0)
    return {"event shift ms": 1000 * shift, "unmatched events": float(sum(len(v.missing) + len(v.extra) for v in verdicts))}


def first_event(run: runs.Run, slot: str, detail: str) -> float:
    return next(e.time for e in Recorded.read(run.directory).events if (e.slot, e.detail) == (slot, detail))


def arrival_error(run: runs.Run, _ref) -> dict[str, float]:
    """belt_bottle_sensor: the bottle's travel against x₀ + v_tar·(t − (1 − e^(−k·t))/k) at every
    recorded time (mm), and when it breaks the beam against the analytical time (ms; the trigger
    sees whole ticks, so this one is quantised to the tick)."""
    objects = {o.name: o.params for o in run.scenario.objects}
    v, k, x0 = objects["belt"]["speed"], objects["belt"]["k"], objects["bottle"]["position"][0]
    t = run.time
    travel = x0 + v * (t - (1.0 - np.exp(-k * t)) / k)
    enter = first_event(run, "barrier.trigger.on_enter", "bottle")
    return {"position error mm": 1000 * float(np.abs(run.columns["bottle.body.position.x"] - travel).max()),
            "arrival error ms": 1000 * abs(enter - analytical_enter_time(run.scenario))}


def spin_up_error(run: runs.Run, _ref) -> dict[str, float]:
    """The paper's first test: the largest |v − v_tar·(1 − e^(−k·t))| of its three bottles, % of v_tar."""
    return {"velocity error %": 100 * max(a.max_error for a in paper.acceleration(run))}


def tipping_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """The paper's second test: each bottle's largest inclination against the reference's, degrees."""
    ours = {t.bottle: t.first for t in paper.tipping(run)}
    theirs = {t.bottle: t.first for t in paper.tipping(ref)}
    return {"peak tilt error °": max(abs(ours[b] - theirs[b]) for b in theirs),
            "largest tilt °": max(ours.values())}


def loop_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """The paper's third test: the gap along the loop against the reference's, and the positions."""
    gap, gap_ref = paper.distances(run).gap, paper.distances(ref).gap
    t = ref.time[ref.time <= run.time[-1]]
    drift = np.abs(np.interp(t, run.time, gap) - gap_ref[:len(t)])
    return {"gap error mm": 1000 * float(drift.max()), **position_error(run, ref)}


def queue_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """A queue at a stopper: positions against the reference, and the first bottle's deepest reach
    into the gate (a 5 mm stopper: its upstream face 2.5 mm before its position)."""
    out = position_error(run, ref)
    stop = next(o.params["position"][0] for o in run.scenario.objects if o.name == "stop")
    reach = float(run.vec3("q0.body.position")[:, 0].max()) + 0.03
    out["depth into gate mm"] = 1000 * max(0.0, reach - (stop - 0.0025))
    return out


def plant_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    """The bottling plant: deliveries (each sink's `bin.taken`, by bottle) against the reference's —
    bottles delivered to another sink or by one run only, the largest delivery-time shift — and
    every other event as in `event_error`."""
    def taken(folder):
        return {e.detail: (e.slot, e.time) for e in Recorded.read(folder).events if e.slot.endswith(".bin.taken")}
    mine, theirs = taken(run.directory), taken(ref.directory)
    misrouted = sum(1 for b in mine.keys() | theirs.keys() if mine.get(b, ("",))[0] != theirs.get(b, ("",))[0])
    shift = max((abs(mine[b][1] - t) for b, (_, t) in theirs.items() if b in mine), default=0.0)
    return {"delivery shift ms": 1000 * shift, "not delivered alike": float(misrouted),
            "delivered": float(len(mine)), **event_error(run, ref)}


def stream_error(run: runs.Run, ref: runs.Run) -> dict[str, float]:
    return {**event_error(run, ref), **position_error(run, ref)}


# --- the scenes ---------------------------------------------------------------------------------
def rates(*hz: int) -> list[Setting]:
    return [Setting("physics rate", f"{r} Hz", {"run.physics_rate": r}) for r in hz]


def iterations(*n: int) -> list[Setting]:
    return [Setting("solver iterations", str(i), {"run.solver_iterations": i}) for i in n]


def explicit(*hz: int) -> list[Setting]:
    return [Setting("explicit law (paper)", f"{r} Hz", {"run.integrator": "explicit", "run.physics_rate": r}) for r in hz]


MODELS = [Setting("bottle model", m, {"defaults.bottle.model": m}) for m in ("base_point", "base_body")] + [
    Setting("bottle shape", "hull", {"defaults.bottle.shape": "hull"})]
GRIP = [Setting("grip law", "along (paper)", {"defaults.conveyor.grip": "along", "defaults.curve.grip": "along"})]
REST = [Setting("rest", "off", {"run.sleep_after": 0})]
EVENTS = [Setting("event-driven points", "on", {"run.event_driven": True})]
# Free transport (hub/physics/transport.py) is every scene's default: the engine moving the bottles instead.
FREE = [Setting("transport", "engine (not free)", {"defaults.bottle.transport": "engine"})]
# The bottling plant: free transport off, and looking less or further ahead than 6 ticks.
PLANT_TRANSPORT = [Setting("transport", "engine (not free)", {"defaults.source.transport": "engine"}),
                   Setting("free look-ahead", "4 ticks", {"defaults.source.lookahead": 4}),
                   Setting("free look-ahead", "8 ticks", {"defaults.source.lookahead": 8})]


def steps(*seconds: float) -> list[Setting]:
    return [Setting("communication step", f"{1000 * s:.0f} ms", {"run.communication_step": s}) for s in seconds]


def scenes() -> list[Scene]:
    paper_dir = ROOT / "scenarios" / "paper"
    queue = queue_scene(40, 0.2)
    return [
        Scene("spin_up", "Belt spin-up (the paper's acceleration test: k = 1, 4, 16/s)", paper_dir / "acceleration.yaml",
              [f"bottle_{k}.body.{s}" for k in ("k1", "k4", "k16") for s in ("velocity", "position")],
              spin_up_error, "velocity error %", "analytical",
              [DEFAULT, *rates(60, 100, 300, 1000), *explicit(60, 150, 300), *iterations(5, 50), *MODELS, *GRIP, *REST]),
        Scene("arrival", "A free bottle's arrival at a light barrier (belt_bottle_sensor, k = 16/s)",
              ROOT / "scenarios" / "belt_bottle_sensor.yaml", ["bottle.body.position"],
              arrival_error, "position error mm", "analytical",
              [DEFAULT, *rates(60, 100, 300, 1000), *explicit(60, 150, 1000), *iterations(5, 50), *MODELS, *GRIP,
               *steps(0.1), *FREE, Setting("stiff field k = 150/s", "exact, 60 Hz", {"objects.belt.k": 150.0, "run.physics_rate": 60}),
               Setting("stiff field k = 150/s", "explicit, 60 Hz",
                       {"objects.belt.k": 150.0, "run.physics_rate": 60, "run.integrator": "explicit"})]),
        Scene("tipping", "Tipping torque (the paper's second test: 20–80 g at 1 m/s)", paper_dir / "tipping_torque.yaml",
              [f"{m}_{g}.body.{s}" for m in ("paper", "point") for g in (20, 35, 50, 65, 80)
               for s in ("orientation", "position")] + ["centre_20.body.position", "centre_80.body.position",
                                                         "centre_20.body.orientation", "centre_80.body.orientation"],
              tipping_error, "peak tilt error °", "reference",
              [DEFAULT, *rates(60, 100, 300), *explicit(150), *iterations(5, 10, 50), *REST]),
        Scene("loop", "Constant distances on the paper's loop (two bottles, 20 s of its 50)",
              paper_dir / "constant_distances.yaml",
              ["lead.body.position", "follow.body.position", "lead.body.tilt", "follow.body.tilt"],
              loop_error, "position RMS mm", "reference",
              [DEFAULT, *rates(50, 100, 300, 500), *explicit(150), *iterations(5, 50), *MODELS, *GRIP, *REST],
              base={"run.duration": 20.0}, reference={"run.physics_rate": 1000, "run.solver_iterations": 50,
                                                      "defaults.bottle.model": "base_body"}),
        Scene("queue", "A 40-bottle queue pressed against a closed stopper (μ = 0.2, 6 s)", queue,
              [f"q{n}.body.position" for n in range(40)], queue_error, "position RMS mm", "reference",
              [DEFAULT, *rates(60, 300), *iterations(5, 10, 50), *MODELS, *REST]),
        Scene("switch", "A switch diverting a stream (switch.yaml)", ROOT / "scenarios" / "switch.yaml",
              ["a.body.position", "b.body.position", "main_end.count.total", "branch_end.count.total"],
              stream_error, "event shift ms", "reference",
              [DEFAULT, *rates(60, 300), *explicit(150), *iterations(5, 50), *MODELS, *GRIP, *REST, *EVENTS, *steps(0.1),
               *FREE]),
        Scene("separator", "The separator cycling a queue of eight (separator.yaml)", ROOT / "scenarios" / "separator.yaml",
              [f"b{n}.body.position" for n in range(1, 9)], stream_error, "event shift ms", "reference",
              [DEFAULT, *rates(60, 300), *iterations(5, 10, 50), *MODELS, *REST, *EVENTS, *steps(0.1)]),
        Scene("plant", "The bottling plant, its first 60 s (15 deliveries; routing in the hub)", PLANT,
              ["sink_A.count.total"], plant_error, "delivery shift ms", "reference",
              [DEFAULT, *rates(100), *explicit(150), *iterations(10, 50), *REST, *EVENTS, *PLANT_TRANSPORT],
              base={"run.duration": 60.0, "objects.control.runs": "hub"}, repeats=2,
              # Not 1 kHz: above 300 Hz the plant is not sound (measured 2 December 2026, first 60 s):
              # at 600 Hz with 20 iterations it delivers 7 bottles, not 15; at 600 Hz and 1 kHz with
              # 50 a bottle is thrown out of the world and the physics watch ends the run.
              # The reference moves every bottle in the engine: free transport is measured against full physics.
              reference={"run.physics_rate": 300, "run.solver_iterations": 50, "defaults.source.transport": "engine"}),
    ]


def _with_step(scenario_path: Path, overrides: dict) -> dict:
    """A scene with a communication step that is no whole number of ticks at a new rate gets the
    nearest whole number (at least one tick; none of the scenes swept here needs it). A scene
    without one communicates at every tick at every rate, its reference too (at 1 kHz: every ms),
    so its event shifts hold the coupling's latency as well as the physics'."""
    rate = overrides.get("run.physics_rate")
    if rate is None or "run.communication_step" in overrides:
        return overrides
    step = load_scenario(scenario_path).run
    seconds = step.substeps / step.physics_rate
    if step.substeps == 1 or math.isclose(seconds * rate, round(seconds * rate)):
        return overrides
    return {**overrides, "run.communication_step": max(1, round(seconds * rate)) / rate}


def measure(scene: Scene, setting: Setting, out: Path, reference: runs.Run | None) -> Point:
    overrides = {"record": scene.record, **scene.base, **setting.overrides}
    overrides = _with_step(scene.path, overrides)
    walls, first = [], None
    for n in range(scene.repeats):
        folder = out / f"{setting.axis}-{setting.label}-{n}".replace(" ", "_").replace("/", "_")
        try:
            done = runs.run(scene.path, folder, overrides)
        except SimulationError as exc:   # the physics watch ended it: the setting is not sound here
            return Point(setting, None, {}, diverged=str(exc).splitlines()[0])
        first = first or done
        walls.append(done.wall_seconds)
    simulated = float(first.time[-1])   # where the run ended (a plant may end at its orders)
    return Point(setting, statistics.median(walls) / simulated, scene.error(first, reference))


def pareto(points: list[Point], metric: str) -> None:
    """Mark the points no other point beats in both cost and `metric` (lower is better in each)."""
    alive = [p for p in points if p.cost is not None and metric in p.errors]
    for p in alive:
        p.front = not any(q is not p and q.cost <= p.cost and q.errors[metric] <= p.errors[metric]
                          and (q.cost < p.cost or q.errors[metric] < p.errors[metric]) for q in alive)


def sweep(scene: Scene, progress=print) -> tuple[list[Point], Point | None]:
    """Every setting of the scene, measured; the reference run's own point (its cost) where there is one."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        reference = None
        ref_point = None
        if scene.against == "reference":
            overrides = _with_step(scene.path, {"record": scene.record, **scene.base, **scene.reference})
            reference = runs.run(scene.path, tmp / "reference", overrides)
            sim = reference.scenario.run.end_tick / reference.scenario.run.physics_rate
            ref_point = Point(Setting("reference", ", ".join(f"{k.split('.')[-1]} {v}" for k, v in scene.reference.items()),
                                      scene.reference), reference.wall_seconds / sim, {})
        points = []
        for setting in scene.settings:
            points.append(measure(scene, setting, tmp, reference))
            progress(f"  {scene.name}: {setting.axis} {setting.label}")
    pareto(points, scene.headline)
    return points, ref_point
