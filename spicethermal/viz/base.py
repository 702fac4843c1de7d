"""What every figure shares: a Figure on the Agg canvas (no pyplot state), the Axes to draw
into, the atomic PNG writer and engineering-notation labels.

matplotlib is imported only when a function here is called.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

from ..io.files import atomic_open

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


# ------------------------------------------------------------------------------ common
def new_figure(width_in: float = 6.4, height_in: float = 4.0) -> Figure:
    """A matplotlib Figure on the Agg canvas (no pyplot, no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def axes(ax: Axes | None, width_in: float = 6.4, height_in: float = 4.0) -> Axes:
    """``ax`` itself, or the Axes of a new figure of the given size when ``ax`` is None."""
    return ax if ax is not None else new_figure(width_in, height_in).add_subplot()


def save_figure(fig: Figure, path: str | os.PathLike, dpi: int = 150) -> Path:
    """Write ``fig`` as a PNG file atomically and return the path."""
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=dpi)
    return Path(path)


def eng(x: float, unit: str) -> str:
    """``0.00213, "J/K"`` -> ``"2.13 mJ/K"``."""
    if x == 0 or not math.isfinite(x):
        return f"{x:g} {unit}"
    k = int(math.floor(math.log10(abs(x)) / 3))
    k = max(-4, min(2, k))
    prefix = {-4: "p", -3: "n", -2: "µ", -1: "m", 0: "", 1: "k", 2: "M"}[k]
    return f"{x / 10 ** (3 * k):.3g} {prefix}{unit}"


def finish(ax: Axes, xlabel: str, ylabel: str) -> Axes:
    """Label the axes, draw the grid (major and minor) and the legend; return ``ax``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax
