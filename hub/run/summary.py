"""The run summary: what `planthub run` prints and writes to summary.json, and `Simulation.summary()` returns."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from hub.core.observer import SummarySection


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

    def lines(self) -> list[str]:
        rate = self.rate
        out = [f"planthub run {self.scenario}  ({self.path})",
               f"  simulated    {self.sim_seconds:.3f} s  ({self.ticks} ticks at {rate} Hz, "
               f"communication step {1000 * self.substeps / rate:.4g} ms)"]
        if self.wall_seconds is not None:
            details = [d for s in self.sections if (d := getattr(s, "wall_detail", lambda: "")())]
            full = "".join(f"; {d}" for d in details)
            out.append(f"  wall time    {self.wall_seconds:.3f} s  (real-time factor {self.realtime_factor:.1f}×{full})")
        for section in self.sections:   # a plant engineer's figures first, the event table after them
            out += section.lines()
        out.append(f"  events       {sum(s.count for s in self.events.values())}")
        width = max((len(k) for k in self.events), default=0)
        for slot, stats in self.events.items():
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
            "simulated": {"seconds": self.sim_seconds, "ticks": self.ticks, "physics_rate": self.rate,
                          "communication_step": self.substeps / self.rate},
            "wall": {"seconds": self.wall_seconds, "realtime_factor": self.realtime_factor,
                     **{k: v for s in self.sections for k, v in getattr(s, "wall_figures", dict)().items()}},
            "events": {slot: {"count": s.count, "first": s.first_tick / self.rate, "first_detail": s.first_detail}
                       for slot, s in self.events.items()},
            "files": self.files(),
            **{s.key: s.as_dict() for s in self.sections},
        }

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.as_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
