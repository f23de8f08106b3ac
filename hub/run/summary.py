"""The run summary: what `planthub run` prints and writes to summary.json, and `Simulation.summary()` returns."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from modules.plant.summary import NO_DESTINATION, PlantSummary

SHOWN = 10   # names printed per list (misrouted, on the line, jams); summary.json lists them all


@dataclass(frozen=True)
class RunSummary:
    """One run: time simulated and taken, events, where the files went, and the plant's figures
    (None for a scene without sinks and sources). Everything but `wall_seconds` is the same for
    equal runs."""

    scenario: str
    path: Path
    ticks: int
    rate: int
    substeps: int
    wall_seconds: float | None           # None: not measured (a Simulation stepped by hand)
    events: dict                         # slot → hub.recorder.EventStats, in order of first appearance
    recorded: int                        # slots in recording.csv
    out: Path | None                     # the run folder, None: nothing written
    plant: PlantSummary | None

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
            busy = self.plant.busy if self.plant is not None else None
            full = (f"; {busy.realtime_factor:.1f}× while {busy.at_least} or more bottles were on the line, "
                    f"{busy.sim_seconds:.1f} s" if busy is not None and busy.realtime_factor else "")
            out.append(f"  wall time    {self.wall_seconds:.3f} s  (real-time factor {self.realtime_factor:.1f}×{full})")
        if self.plant is not None:   # a plant engineer's figures first, the event table after them
            out += plant_lines(self.plant)
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
                     "full_line": None if self.plant is None or self.plant.busy is None else self.plant.busy.as_dict()},
            "events": {slot: {"count": s.count, "first": s.first_tick / self.rate, "first_detail": s.first_detail}
                       for slot, s in self.events.items()},
            "files": self.files(),
            "plant": None if self.plant is None else self.plant.as_dict(),
        }

    def write(self, path: Path) -> None:
        path.write_text(json.dumps(self.as_dict(), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")


def plant_lines(p: PlantSummary) -> list[str]:
    """The plant block of the printed summary (README, "Outputs")."""
    sources = [f"placed at the start {p.placed}"] if p.placed else []
    sources += [f"released by {name} {n}" for name, n in p.released.items()]
    out = [f"  bottles in   {p.bottles_in}  ({', '.join(sources)})" if sources else f"  bottles in   {p.bottles_in}",
           f"  delivered    {p.delivered}" + (f"  ({_counts(p.by_destination)})" if p.delivered else "")]
    width = max((len(s.name) for s in p.sinks), default=0)
    for sink in p.sinks:
        lane = "" if sink.accepts is None else f"  lane for {', '.join(sink.accepts)}"
        wrong = f", {sink.misrouted} misrouted" if sink.misrouted else ""
        counts = f"  ({_counts(sink.by_destination)})" if sink.total else ""
        out.append(f"    {sink.name:<{width}}  {sink.total:>4}{counts}{lane}{wrong}")
    if p.misrouted is None:
        out.append("  misrouted    not judged (no sink says which destinations its lane is for: give sinks `accepts`)")
    else:
        out.append(f"  misrouted    {len(p.misrouted) or 'none'}")
        out += _listed([f"{m.bottle} (for {_dest(m.destination)}) at {m.sink}, {m.time:.3f} s" for m in p.misrouted])
    if len(p.on_line) <= SHOWN:   # few: by name; many: how many on each belt
        where = ", ".join(f"{b.bottle} on {b.belt}" if b.belt else f"{b.bottle} off the belts" for b in p.on_line)
    else:
        belts: dict[str, int] = {}
        for b in p.on_line:
            belts[b.belt or ""] = belts.get(b.belt or "", 0) + 1
        off = belts.pop("", 0)
        where = ", ".join([f"{name} {n}" for name, n in sorted(belts.items())] + ([f"off the belts {off}"] if off else []))
    most = f"at most {p.most_on_line}, at {p.most_on_line_at:.1f} s" if p.most_on_line else ""
    details = "; ".join(part for part in (where, most) if part)
    out.append(f"  on the line  {len(p.on_line) or 'none'}" + (f"  ({details})" if details else ""))
    steady = p.steady_per_minute
    pace = (f"; {steady:.2f} /min from the first delivery at {p.delivery_times[0]:.3f} s "
            f"to the last at {p.delivery_times[-1]:.3f} s" if steady is not None else "")
    out.append(f"  throughput   {p.per_minute:.2f} /min over {p.start:g}–{p.end:g} s  ({p.delivered} delivered{pace})")
    rule = f"standing still over {p.jam_after:g} s on a running belt, not held at a closed gate"
    out.append(f"  jams         {len(p.jams) or 'none'}  ({rule})")
    out += _listed([f"{j.bottle} on {j.belt} since {j.since:.3f} s, "
                    + (f"for {j.seconds(p.end):.2f} s until {j.until:.3f} s" if j.until is not None
                       else f"still at the end ({j.seconds(p.end):.2f} s)") for j in p.jams])
    return out


def _dest(destination: str) -> str:
    return destination if destination != NO_DESTINATION else "no destination"


def _counts(by: dict[str, int]) -> str:
    return ", ".join(f"{_dest(d)} {n}" for d, n in by.items())


def _listed(items: list[str]) -> list[str]:
    out = [f"    {item}" for item in items[:SHOWN]]
    if len(items) > SHOWN:
        out.append(f"    … and {len(items) - SHOWN} more (summary.json lists all)")
    return out
