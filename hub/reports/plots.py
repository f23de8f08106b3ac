"""PNG line plots for reports, drawn with matplotlib (imported only when a report draws)."""
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


@dataclass
class Panel:
    title: str
    xlabel: str
    ylabel: str
    lines: list[Line] = field(default_factory=list)


def _pyplot():
    try:
        import matplotlib
    except ImportError as exc:
        raise PlanthubError("drawing a report needs matplotlib, pinned in requirements.txt: "
                            "run `make venv` (or pass --no-plots)") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw(path: Path, panels: list[Panel], width: float = 8.0, height_each: float = 3.2) -> Path:
    """Panels stacked top to bottom, each with its lines and a legend, saved as PNG."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(panels), 1, figsize=(width, height_each * len(panels)), squeeze=False)
    for ax, panel in zip(axes[:, 0], panels):
        for line in panel.lines:
            ax.plot(line.x, line.y, line.style, label=line.label, linewidth=line.width)
        ax.set_title(panel.title)
        ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        ax.grid(True, alpha=0.3)
        if any(line.label for line in panel.lines):
            ax.legend(fontsize=8)
    fig.tight_layout()
    # Fixed metadata: the same numbers give the same file.
    fig.savefig(path, dpi=100, metadata={"Software": None})
    plt.close(fig)
    return path
