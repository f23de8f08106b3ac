"""The run summary: what `planthub run` prints and writes to summary.json, and `Simulation.summary()` returns."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from hub.core.observer import SummarySection
from hub.logic.component import LogicComponent
from hub.run.ending import Ending

#: The most kinds of event the printed summary lists one a line without -v (the bottling plant has 70).
TABLE_ROWS = 12


def logic_components(components) -> frozenset[str]:
    """`object.component` of every component that is logic, not plant: a LogicComponent (an FMU,
    a participant, an actuator's state logic) or a component named `logic` (a connector's gate).
    Their events (`sw.logic.WorkingPosStartAnim_got`) are the logic's inner workings; the printed
    event table leaves them to `-v` and shows what the plant did — sensors, actuators, sinks,
    sources, clocks. summary.json keeps every event, each marked."""
    return frozenset(f"{c.obj}.{c.name}" for c in components if isinstance(c, LogicComponent) or c.name == "logic")


@dataclass(frozen=True)
class RunSummary:
    """One run: time simulated and taken, events, where the files went, and the sections its
    observers contribute (the plant's figures, for a plant). Everything but `wall_seconds` is the
    same for equal runs."""

    scenario: str
    path: Path
    ticks: int
    rate: int
    substeps: int
    wall_seconds: float | None           # None: not measured (a Simulation stepped by hand)
    events: dict                         # slot → hub.recorder.EventStats, in order of first appearance
    recorded: int                        # slots in recording.csv
    out: Path | None                     # the run folder, None: nothing written
    sections: tuple[SummarySection, ...] = ()
    ended: Ending | None = None          # None: the run goes on (a summary taken mid-run)
    logic: frozenset[str] = frozenset()  # `object.component` of the logic components (logic_components)
    restarts: tuple = ()                 # isolated FMUs restarted (hub/logic/isolated.py Restart), in order

    @property
    def plant(self):
        """The plant's figures (hub/core/module.py PLANT), or None for a scene that is no plant."""
        return self.section("plant")

    def section(self, key: str):
        return next((s for s in self.sections if s.key == key), None)

    @property
    def sim_seconds(self) -> float:
        return self.ticks / self.rate

    @property
    def realtime_factor(self) -> float | None:
        if self.wall_seconds is None:
            return None
        return self.sim_seconds / self.wall_seconds if self.wall_seconds > 0 else float("inf")

    def files(self) -> dict[str, str]:
        if self.out is None:
            return {}
        return {"recording": str(self.out / "recording.csv"), "events": str(self.out / "events.csv"),
                "summary": str(self.out / "summary.json")}

    def is_logic(self, slot: str) -> bool:
        """Whether an event slot (`object.component.slot`) belongs to a logic component."""
        return slot.rpartition(".")[0] in self.logic

    def lines(self, verbose: bool = False) -> list[str]:
        """The printed summary: how the run ended and the sections' figures (the plant's) first,
        then time, events and files. The event table lists the plant's events; `verbose`, also
        the logic's (is_logic)."""
        rate = self.rate
        out = [f"planthub run {self.scenario}  ({self.path})"]
        if self.ended is not None:
            out.append(self.ended.line())
        for n, restart in enumerate(self.restarts):
            out.append(f"  {'restarted' if n == 0 else '':<12} {restart.line()}")
        for section in self.sections:
            out += section.lines()
        out.append(f"  simulated    {self.sim_seconds:.3f} s  ({self.ticks} ticks at {rate} Hz, "
                   f"communication step {1000 * self.substeps / rate:.4g} ms)")
        if self.wall_seconds is not None:
            details = [d for s in self.sections if (d := getattr(s, "wall_detail", lambda: "")())]
            full = "".join(f"; {d}" for d in details)
            out.append(f"  wall time    {self.wall_seconds:.3f} s  (real-time factor {self.realtime_factor:.1f}×{full})")
        shown = {k: s for k, s in self.events.items() if verbose or not self.is_logic(k)}
        hidden = sum(s.count for k, s in self.events.items() if k not in shown)
        note = f"  ({hidden} of them inside the logic, listed with -v)" if hidden else ""
        if not verbose and len(shown) > TABLE_ROWS:   # a plant's table would bury the summary
            note = f"  (from {len(self.events)} slots, listed with -v and in events.csv)"
            shown = {}
        out.append(f"  events       {sum(s.count for s in self.events.values())}{note}")
        width = max((len(k) for k in shown), default=0)
        for slot, stats in shown.items():
            detail = f"  ({stats.first_detail})" if stats.first_detail else ""
            out.append(f"    {slot:<{width}}  {stats.count:>4}×  first at {stats.first_tick / rate:.4f} s{detail}")
        if self.out is not None:
            out += [f"  recording    {self.out / 'recording.csv'}  ({self.recorded} slots)",
                    f"  event log    {self.out / 'events.csv'}",
                    f"  summary      {self.out / 'summary.json'}"]
        return out

    def as_dict(self) -> dict:
        return {
            "scenario": self.scenario,
            "file": str(self.path),
            "ended": self.ended.as_dict() if self.ended is not None else None,
            "simulated": {"seconds": self.sim_seconds, "ticks": self.ticks, "physics_rate": self.rate,
                          "communication_step": self.substeps / self.rate},
            "wall": {"seconds": self.wall_seconds, "realtime_factor": self.realtime_factor,
                     **{k: v for s in self.sections for k, v in getattr(s, "wall_figures", dict)().items()}},
            "events": {slot: {"count": s.count, "first": s.first_tick / self.rate, "first_detail": s.first_detail,
                              "logic": self.is_logic(slot)}
                       for slot, s in self.events.items()},
            "files": self.files(),
            **({"restarts": [{"instance": r.instance, "time": r.time, "from": r.since, "steps": r.steps,
                              "cause": r.cause} for r in self.restarts]} if self.restarts else {}),
            **{s.key: s.as_dict() for s in self.sections},
        }

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.as_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
