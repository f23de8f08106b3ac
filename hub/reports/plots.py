"""PNG line plots for reports and `planthub plot`, drawn with matplotlib (imported only when something draws)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hub.core.errors import PlanthubError


@dataclass
class Line:
    x: object
    y: object
    label: str = ""
    style: str = "-"
    width: float = 1.5
    steps: bool = False   # a value held from one sample to the next (a bool, a count, a name): drawn as steps


@dataclass
class Marks:
    """Vertical lines across a panel at the times `x`: when events happened."""
    x: list[float]
    label: str = ""
    color: str = "tab:red"


@dataclass
class Panel:
    title: str
    xlabel: str
    ylabel: str
    lines: list[Line] = field(default_factory=list)
    marks: list[Marks] = field(default_factory=list)
    integers: bool = False   # ticks at whole numbers only (a bool's 0 and 1, a count)


def _pyplot():
    try:
        import matplotlib
    except ImportError as exc:
        raise PlanthubError("drawing a plot needs matplotlib, pinned in requirements.txt: run `make venv` "
                            "(`planthub report`: or pass --no-plots)") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw(path: Path, panels: list[Panel], width: float = 8.0, height_each: float = 3.2, *,
         share_x: bool = False, xlim: tuple[float, float] | None = None) -> Path:
    """Panels stacked top to bottom, each with its lines and a legend, saved as PNG of
    width × (height_each · panels) inches at 100 dpi. `share_x`: one time axis, labelled under the
    last panel only; `xlim`: the x range shown."""
    plt = _pyplot()
    from matplotlib.ticker import MaxNLocator

    fig, axes = plt.subplots(len(panels), 1, figsize=(width, height_each * len(panels)), squeeze=False,
                             sharex=share_x)
    last = len(panels) - 1
    for i, (ax, panel) in enumerate(zip(axes[:, 0], panels)):
        for line in panel.lines:
            ax.plot(line.x, line.y, line.style, label=line.label, linewidth=line.width,
                    drawstyle="steps-post" if line.steps else "default")
        for marks in panel.marks:
            # One collection for all of a group's times: a plant logs thousands of events.
            ax.vlines(marks.x, 0, 1, transform=ax.get_xaxis_transform(), colors=marks.color,
                      linestyles="--", linewidth=0.8, alpha=0.7, label=marks.label)
        ax.set_title(panel.title)
        if not share_x or i == last:
            ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        if panel.integers:
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, alpha=0.3)
        if any(line.label for line in panel.lines) or any(marks.label for marks in panel.marks):
            ax.legend(fontsize=8)
    if xlim is not None:
        for ax in axes[:, 0]:
            ax.set_xlim(*xlim)
    fig.tight_layout()
    # Fixed metadata: the same numbers give the same file.
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)
    return path
