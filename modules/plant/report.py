"""The plant block of the printed run summary (README, "The plant summary")."""
from __future__ import annotations

SHOWN = 10   # names printed per list (rejected, misrouted, on the line, jams); summary.json lists them all
NO_DESTINATION = ""   # the destination of a bottle that has none (a `bottle` object): "" in JSON too


def plant_lines(p) -> list[str]:
    """The plant block of the printed summary (README, "Outputs")."""
    sources = [f"placed at the start {p.placed}"] if p.placed else []
    sources += [f"released by {name} {n}" for name, n in p.released.items()]
    out = [f"  bottles in   {p.bottles_in}  ({', '.join(sources)})" if sources else f"  bottles in   {p.bottles_in}",
           f"  delivered    {p.delivered}" + (f"  ({_counts(p.by_destination)})" if p.delivered else "")]
    width = max((len(s.name) for s in p.sinks), default=0)
    out += _sinks([s for s in p.sinks if not s.rejects], width)
    if p.rejected is not None:   # a plant with a reject lane: its sinks, then each bottle rejected
        out.append(f"  rejected     {len(p.rejected) or 'none'}")
        out += _sinks([s for s in p.sinks if s.rejects], width)
        out += _listed([f"{r.bottle} (for {_dest(r.destination)}) at {r.sink}, {r.time:.3f} s" for r in p.rejected])
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


def _sinks(sinks, width: int) -> list[str]:
    out = []
    for sink in sinks:
        lane = "  rejects" if sink.rejects else "" if sink.accepts is None else f"  lane for {', '.join(sink.accepts)}"
        wrong = f", {sink.misrouted} misrouted" if sink.misrouted else ""
        counts = f"  ({_counts(sink.by_destination)})" if sink.total else ""
        out.append(f"    {sink.name:<{width}}  {sink.total:>4}{counts}{lane}{wrong}")
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
