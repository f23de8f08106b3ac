"""`planthub plot CAMPAIGN_DIR FIGURE… --against KEY`: a campaign's figures against one of its parameters, a line per combination of the others."""
from __future__ import annotations

import json
import logging
from pathlib import Path

from hub.cli.exits import OK, UsageError
from hub.core.errors import PlanthubError
from hub.core.numbers import is_number
from hub.core.registry import did_you_mean

_log = logging.getLogger("planthub.plot")

WALL = "wall_s"   # a case's wall time, beside the figures of its summary


def is_campaign(folder: Path) -> bool:
    return (folder / "campaign.json").is_file()


def plot_campaign(args) -> int:
    from hub.reports.plots import Line, Panel, draw

    path = args.run / "campaign.json"
    try:
        cases = json.loads(path.read_text(encoding="utf-8"))["cases"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise UsageError(f"{path}: not a campaign's results (`planthub campaign --out`): {exc}") from None
    keys = list(dict.fromkeys(k for case in cases for k in case.get("parameters", {})))
    if args.against is None:
        raise UsageError(f"{args.run} holds a campaign: say which parameter goes along the x axis with --against KEY "
                         f"({', '.join(keys) or 'it varies none'})")
    if args.against not in keys:
        raise UsageError(f"--against {args.against}: the campaign does not vary it{did_you_mean(args.against, keys)}")
    known = sorted({k for case in cases for k in case.get("figures", {})} | {WALL})
    for figure in args.slots:
        if figure not in known:
            raise UsageError(f"{figure}: no such figure in {path}{did_you_mean(figure, known)}; its figures: "
                             f"{', '.join(known)}")
    others = [k for k in keys if k != args.against   # those that vary name the lines
              and len({json.dumps(case.get("parameters", {}).get(k)) for case in cases}) > 1]
    panels, drawn = [], set()
    for figure in args.slots:
        series: dict[str, list[tuple[float, float]]] = {}
        for case in cases:
            parameters = case.get("parameters", {})
            x = parameters.get(args.against)
            y = case.get("wall_seconds") if figure == WALL else case.get("figures", {}).get(figure)
            if not is_number(x):
                raise UsageError(f"--against {args.against}: case {case.get('index')} has {x!r}, not a number")
            if not is_number(y):   # a case that did not run, or crashed before its summary
                continue
            label = ", ".join(f"{k}={json.dumps(parameters[k])}" for k in others if k in parameters)
            series.setdefault(label, []).append((x, y))
            drawn.add(case.get("index"))
        lines = [Line([p[0] for p in sorted(points)], [p[1] for p in sorted(points)], label=label, style="o-")
                 for label, points in series.items()]
        panels.append(Panel(figure, args.against, "", lines))
    skipped = len(cases) - len(drawn)
    out = args.out or args.run / "plot.png"
    if out.suffix.lower() != ".png":
        raise UsageError(f"--out {out}: planthub plot writes a PNG, so name a .png file")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        draw(out, panels, width=10.0, height_each=3.2)
    except OSError as exc:
        raise PlanthubError(f"cannot write {out}: {exc.strerror or exc}") from None
    _log.info(f"planthub plot: {', '.join(args.slots)} against {args.against}, {len(drawn)} cases"
              + (f" ({skipped} without the figures: not run or failed before their summary)" if skipped else ""))
    print(out)
    return OK
