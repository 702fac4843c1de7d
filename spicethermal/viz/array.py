"""The array figures: a heat map of every dot of a Braille line over time, and the line as
it stands when its refresh is complete.

matplotlib is imported only when a function here is called.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from ..array.result import heat_rows
from .base import new_figure, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from pathlib import Path

    from matplotlib.axes import Axes

    from ..array.refresh import LineDrive

__all__ = ["fig_line_heatmap", "plot_line_heatmap", "plot_line_snapshot"]


def plot_line_heatmap(ld: LineDrive, ax: Axes, line: int = 0, which: str = "ours") -> Axes:
    """Every dot's heater temperature (period average) against time, one row per dot, cell by
    cell; the actuation temperature and the refresh time marked.

    Parameters
    ----------
    ld : LineDrive
        The planned line.
    ax : Axes
        Where to draw.
    line : int
        Which line of the text.
    which : str
        The drive: ``ours`` (crosstalk-aware) or ``naive`` (lone drives).

    Returns
    -------
    Axes
    """
    t, temps, labels = heat_rows(ld, line, which=which)
    lim = ld.drives[ld.columns[0]].limits
    mesh = ax.pcolormesh(t, np.arange(len(labels) + 1), temps[:, :-1], cmap="inferno",
                         vmin=lim.ambient_c, vmax=lim.t_max_c, shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label="heater temperature, period average (°C)")
    ax.contour(t, np.arange(len(labels)) + 0.5, temps, levels=[lim.actuation_c], colors="cyan",
               linewidths=0.6)
    refresh = ld.refresh(which)[line]
    if np.isfinite(refresh):
        ax.axvline(refresh, color="white", linestyle="--", linewidth=1.0,
                   label=f"refresh complete, {1e3 * refresh:.1f} ms")
        ax.legend(loc="upper left", fontsize="small")
    ax.set_xscale("log")
    dots = len(ld.drives[ld.columns[0]].model.ports)
    ticks = np.arange(0, len(labels), dots)
    ax.set_yticks(ticks + 0.5 * dots, [f"cell {k // dots + 1}" for k in ticks], fontsize=5)
    ax.invert_yaxis()
    ax.set_xlabel(f"time from the start of line {line + 1} (s)")
    what = {"ours": "crosstalk-aware drive", "naive": "naive lone drives",
            "constant": "constant hold"}[which]
    ax.set_title(f"{what}, line {line + 1}: {ld.lines[line]!r} — every dot of {ld.cells} cells "
                 f"(cyan: the actuation temperature {lim.actuation_c:g} °C)", fontsize="small")
    return ax


def plot_line_snapshot(ld: LineDrive, ax: Axes, line: int = 0) -> Axes:
    """The line of cells when the refresh of ``line`` is complete: each dot at its position,
    coloured by its temperature, ringed when it is up.

    Parameters
    ----------
    ld : LineDrive
        The planned line.
    ax : Axes
        Where to draw.
    line : int
        Which line.

    Returns
    -------
    Axes
    """
    first = ld.drives[ld.columns[0]]
    lim = first.limits
    when = ld.starts[line] + ld.refresh_s[line] if np.isfinite(ld.refresh_s[line]) \
        else ld.starts[line]
    ports = first.model.ports
    width = max(p.x_mm or 0.0 for p in ports) + 3.5
    xs, ys, cs, up = [], [], [], []
    for c, col in enumerate(ld.columns):
        ev = ld.drives[col].ours
        k = min(int(np.searchsorted(ev.t_s, when)), ev.t_s.size - 1)
        for i, p in enumerate(ports):
            xs.append(c * (width + 2.5) + (p.x_mm or 0.0))
            ys.append(-(p.y_mm or 0.0))
            cs.append(ev.mean_c[k, i])
            up.append(cs[-1] >= lim.actuation_c)
    ax.scatter(xs, ys, c=cs, cmap="inferno", vmin=lim.ambient_c, vmax=lim.t_max_c, s=14)
    ax.scatter(np.array(xs)[up], np.array(ys)[up], facecolors="none", edgecolors="cyan", s=40,
               linewidths=0.6)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(f"at {1e3 * (when - ld.starts[line]):.1f} ms: raised dots ringed",
                 fontsize="small")
    return ax


def fig_line_heatmap(ld: LineDrive, path: str | os.PathLike, line: int = 0) -> Path:
    """The heat maps of the crosstalk-aware and of the naive drive and the snapshot of a line,
    as a PNG written atomically to ``path``.

    Parameters
    ----------
    ld : LineDrive
        The planned line.
    path : str or os.PathLike
        The PNG file.
    line : int
        Which line.

    Returns
    -------
    Path
    """
    fig = new_figure(10.0, 11.0)
    grid = fig.add_gridspec(3, 1, height_ratios=[4.0, 4.0, 1.0])
    plot_line_heatmap(ld, fig.add_subplot(grid[0]), line)
    plot_line_heatmap(ld, fig.add_subplot(grid[1]), line, "naive")
    plot_line_snapshot(ld, fig.add_subplot(grid[2]), line)
    return save_figure(fig, path)
