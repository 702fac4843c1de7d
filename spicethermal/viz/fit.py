"""Figures of the ladder fit and of the bench: Fig. 7 (fit, residuals, the ladder drawn as a
schematic), Fig. 2 (the TSP calibration) and Table 1 (datasheet against measurement).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..core.ladder import Cauer, Foster
    from ..fit.ladder import FitResult
    from ..identify.calibration import Calibration
    from ..identify.datasheet import Table1

from .base import axes, eng, finish, new_figure, save_figure


# ------------------------------------------------------------------ Fig. 7 (a), (b)
def _data_style(n: int, curve: bool) -> dict[str, Any]:
    """Markers for log-spaced data; for dense data a broad band (curve) or fine dots."""
    if n <= 200:
        return {"marker": "o", "ls": "none", "ms": 3.5 if curve else 3,
                "mfc": "none" if curve else None}
    if curve:
        return {"ls": "-", "lw": 5, "alpha": 0.35, "solid_capstyle": "butt"}
    return {"marker": ".", "ls": "none", "ms": 1.5, "alpha": 0.6}


def plot_fit(result: FitResult, ax: Axes | None = None, stages: bool = True) -> Axes:
    """Fig. 7(a): the data and the fitted Zth(t) on logarithmic time.

    ``stages`` also draws each Foster stage's contribution ``r_i (1 - exp(-t/τ_i))``.

    >>> import numpy as np
    >>> from spicethermal.fit.ladder import fit_foster
    >>> t = np.logspace(-4, 1, 51)
    >>> ax = plot_fit(fit_foster(t, 2 * (1 - np.exp(-t / 1e-2))))
    >>> ax.get_xscale()
    'log'
    """
    ax = axes(ax)
    t = np.asarray(result.t_s)
    tt = np.geomspace(t[0], t[-1], 400)
    f = result.foster
    ax.plot(t, result.zth_k_per_w, color="C0", label=f"data ({t.size} points)",
            **_data_style(t.size, curve=True))
    ax.plot(tt, f.zth(tt), "-", color="C3", lw=1.6,
            label=f"Foster fit, order {f.order}, Rth = {f.rth:.4g} K/W")
    if stages and f.order > 1:
        for i, (r, tau) in enumerate(zip(f.r, f.tau, strict=True), 1):
            ax.plot(tt, r * -np.expm1(-tt / tau), ":", lw=0.9, color="0.45",
                    label="stages" if i == 1 else None)
    ax.set_xscale("log")
    return finish(ax, "t (s)", "Zth (K/W)")


def plot_residuals(result: FitResult, ax: Axes | None = None) -> Axes:
    """Fig. 7(b): residuals data − fit (K/W) at every data point, with the ±rms band."""
    ax = axes(ax, height_in=2.5)
    t = np.asarray(result.t_s)
    rms = result.rms_k_per_w
    ax.axhline(0.0, color="0.3", lw=0.8)
    ax.axhspan(-rms, rms, color="C0", alpha=0.12, lw=0, label=f"±rms = {rms:.3g} K/W")
    ax.plot(t, result.residuals, color="C0", **_data_style(t.size, curve=False))
    ax.set_xscale("log")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("data − fit (K/W)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    if result.rth_k_per_w > 0:
        sec = ax.secondary_yaxis("right", functions=(
            lambda y: 100 * y / result.rth_k_per_w, lambda p: p * result.rth_k_per_w / 100))
        sec.set_ylabel("% of Rth")
    return ax


# ---------------------------------------------------------------------- Fig. 7 (c)
_WIRE: dict[str, Any] = {"color": "k", "lw": 1.2, "solid_capstyle": "round"}


def _resistor(ax: Axes, x0: float, x1: float, y: float) -> None:
    """Horizontal zig-zag resistor between (x0, y) and (x1, y)."""
    a, b = x0 + 0.25 * (x1 - x0), x0 + 0.75 * (x1 - x0)
    xs = np.linspace(a, b, 9)
    ys = y + 0.12 * np.array([0, 1, -1, 1, -1, 1, -1, 1, 0])
    ax.plot([x0, a, *xs[1:-1], b, x1], [y, y, *ys[1:-1], y, y], **_WIRE)


def _capacitor_h(ax: Axes, x0: float, x1: float, y: float) -> None:
    """Horizontal capacitor (vertical plates) between (x0, y) and (x1, y)."""
    xm, gap, h = (x0 + x1) / 2, 0.06, 0.2
    ax.plot([x0, xm - gap], [y, y], **_WIRE)
    ax.plot([xm + gap, x1], [y, y], **_WIRE)
    for xp in (xm - gap, xm + gap):
        ax.plot([xp, xp], [y - h, y + h], **_WIRE)


def _capacitor_v(ax: Axes, x: float, y0: float, y1: float) -> None:
    """Vertical capacitor (horizontal plates) between (x, y0) and (x, y1), y0 > y1."""
    ym, gap, w = (y0 + y1) / 2, 0.06, 0.22
    ax.plot([x, x], [y0, ym + gap], **_WIRE)
    ax.plot([x, x], [ym - gap, y1], **_WIRE)
    for yp in (ym - gap, ym + gap):
        ax.plot([x - w, x + w], [yp, yp], **_WIRE)


def _dot(ax: Axes, x: float, y: float) -> None:
    ax.plot([x], [y], "o", color="k", ms=3.5)


def _terminal(ax: Axes, x: float, y: float, text: str, side: str) -> None:
    ax.plot([x], [y], "o", mfc="white", mec="k", ms=6, zorder=3)
    ax.text(x + (-0.15 if side == "left" else 0.15), y, text, ha="right" if side == "left"
            else "left", va="center", fontsize=9, fontweight="bold")


def plot_ladder(ladder: Foster | Cauer, ax: Axes | None = None, title: str | None = None,
                tau: bool = True) -> Axes:
    """Fig. 7(c): a schematic of the network with its R (K/W) and C (J/K) values.

    Foster: parallel RC stages in series from TJ to TREF. Cauer: resistors in a chain from
    TJ, capacitors from each node to TREF. Heat flow P enters at TJ.

    >>> from spicethermal.core.ladder import Foster
    >>> ax = plot_ladder(Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]))
    >>> sorted(" ".join(t.get_text().split()) for t in ax.texts if t.get_text()[0] == "R")
    ['R1 1 K/W', 'R2 2 K/W']
    """
    n = ladder.order
    ax = axes(ax, width_in=max(4.0, 1.4 * n + 1.5), height_in=2.6)
    fs = 8 if n <= 6 else 6.5
    if ladder.topology == "foster":
        y, up, dn = 0.0, 0.65, -0.65
        ax.plot([-0.6, 0.0], [y, y], **_WIRE)
        for i in range(n):
            x0, x1 = 2.0 * i, 2.0 * i + 1.6
            for yy in (up, dn):
                ax.plot([x0, x0, x0 + 0.2], [y, yy, yy], **_WIRE)
                ax.plot([x1 - 0.2, x1, x1], [yy, yy, y], **_WIRE)
            _resistor(ax, x0 + 0.2, x1 - 0.2, up)
            _capacitor_h(ax, x0 + 0.2, x1 - 0.2, dn)
            _dot(ax, x0, y)
            _dot(ax, x1, y)
            ax.plot([x1, x1 + 0.4], [y, y], **_WIRE)
            xm = (x0 + x1) / 2
            ax.text(xm, up + 0.22, f"R{i + 1}\n{eng(ladder.r[i], 'K/W')}",
                    ha="center", va="bottom", fontsize=fs, linespacing=1.1)
            label = f"C{i + 1}\n{eng(ladder.c[i], 'J/K')}"
            if tau:
                label += f"\nτ = {eng(ladder.r[i] * ladder.c[i], 's')}"
            ax.text(xm, dn - 0.3, label, ha="center", va="top", fontsize=fs, linespacing=1.1)
        _terminal(ax, -0.6, y, "TJ", "left")
        _terminal(ax, 2.0 * n, y, "TREF", "right")
        ax.set_ylim(-2.3, 1.7)
        ax.set_xlim(-1.6, 2.0 * n + 1.2)
    else:
        top, bot = 1.0, -1.0
        xs = [2.0 * i for i in range(n + 1)]
        ax.plot([-0.6, 0.0], [top, top], **_WIRE)
        for i in range(n):
            x = xs[i]
            _dot(ax, x, top)
            _capacitor_v(ax, x, top, bot)
            _dot(ax, x, bot)
            _resistor(ax, x, xs[i + 1], top)
            ax.text((x + xs[i + 1]) / 2, top + 0.22, f"R{i + 1}\n{eng(ladder.r[i], 'K/W')}",
                    ha="center", va="bottom", fontsize=fs, linespacing=1.1)
            ax.text(x + 0.3, (top + bot) / 2, f"C{i + 1}\n{eng(ladder.c[i], 'J/K')}",
                    ha="left", va="center", fontsize=fs, linespacing=1.1)
        ax.plot([xs[-1], xs[-1]], [top, bot], **_WIRE)
        ax.plot([-0.6, xs[-1] + 0.6], [bot, bot], **_WIRE)
        _terminal(ax, -0.6, top, "TJ", "left")
        _terminal(ax, xs[-1] + 0.6, bot, "TREF", "right")
        ax.set_ylim(-1.6, 2.1)
        ax.set_xlim(-1.6, xs[-1] + 1.8)
    ax.annotate("P", xy=(-0.35, 0.0 if ladder.topology == "foster" else 1.0),
                xytext=(-0.35, 0.55 if ladder.topology == "foster" else 1.55),
                ha="center", fontsize=8, arrowprops={"arrowstyle": "->", "lw": 1.0})
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title if title is not None else
                 f"{ladder.topology.capitalize()} network, Rth = {eng(ladder.rth, 'K/W')}",
                 fontsize=9, loc="left")
    return ax


# ----------------------------------------------------------------------------- Fig. 7
def fig7(result: FitResult, path: str | os.PathLike, cauer: bool = True,
         title: str | None = None) -> Path:
    """The paper's Fig. 7 for a fit: (a) fit over data, (b) residuals, (c) the ladder(s).

    (c) shows the fitted Foster network and, with ``cauer``, its exact Cauer equivalent.
    Written as a PNG to ``path`` (atomically); returns the path.

    >>> import numpy as np, tempfile, pathlib
    >>> from spicethermal.fit.ladder import fit_foster
    >>> t = np.logspace(-4, 1, 51)
    >>> res = fit_foster(t, 2 * (1 - np.exp(-t / 1e-2)) + (1 - np.exp(-t / 1.0)))
    >>> fig7(res, pathlib.Path(tempfile.mkdtemp()) / "fig7.png").stat().st_size > 10000
    True
    """
    n = result.order
    ladders: list[Foster | Cauer] = [result.foster]
    if cauer:
        ladders.append(result.foster.to_cauer())
    wide = n > 4
    fig = new_figure(10.0, 9.0 if wide and cauer else 7.5)
    rows = [3.0, 1.6] + ([1.6] * len(ladders) if wide else [1.8])
    grid = fig.add_gridspec(len(rows), 1 if wide else len(ladders), height_ratios=rows)
    ax_a = fig.add_subplot(grid[0, :])
    ax_b = fig.add_subplot(grid[1, :], sharex=ax_a)
    plot_fit(result, ax_a)
    plot_residuals(result, ax_b)
    ax_a.set_xlabel("")
    ax_a.set_title("(a) fit over the data" + (f" — {title}" if title else ""), fontsize=10,
                   loc="left")
    ax_b.set_title("(b) residuals", fontsize=10, loc="left")
    for k, lad in enumerate(ladders):
        ax_c = fig.add_subplot(grid[2 + k, 0] if wide else grid[2, k])
        plot_ladder(lad, ax_c)
        ax_c.set_title(("(c) " if k == 0 else "") + ax_c.get_title(loc="left"), fontsize=9,
                       loc="left")
    return save_figure(fig, path)


# --------------------------------------------------- Fig. 2 and Table 1 (the demo report)
def calibration_law(cal: Calibration) -> str:
    """The law a calibration converts by, as a legend says it.

    >>> from spicethermal.identify.calibration import Calibration
    >>> calibration_law(Calibration.fit([20, 40, 60, 80], [0.6, 0.56, 0.52, 0.48]))
    'linear law, K = -2.000 mV/K'
    """
    if cal.degree == 1:
        return f"linear law, K = {cal.k_factor_mv_per_k:.3f} mV/K"
    return f"quadratic law, K = {cal.k_factor_mv_per_k:.3f} mV/K at mid-range"


def plot_calibration(cal: Calibration, ax: Axes | None = None) -> Axes:
    """V_tsp against temperature: the points and the law used, linear or quadratic (paper
    Fig. 2); the voltage axis spans the points with a margin."""
    ax = ax if ax is not None else new_figure().add_subplot()
    t = np.asarray(cal.temp_c)
    grid = np.linspace(t.min(), t.max(), 200)
    ax.plot(t, np.asarray(cal.v_tsp_v) * 1e3, "o", color="C0", label="calibration points")
    ax.plot(grid, cal.voltage(grid) * 1e3, "-", color="C1", label=calibration_law(cal))
    v = np.asarray(cal.v_tsp_v) * 1e3
    pad = 0.08 * (float(np.ptp(v)) or 1.0)
    ax.set_ylim(float(v.min()) - pad, float(v.max()) + pad)
    ax.set_xlabel("temperature (°C)")
    ax.set_ylabel("V_tsp (mV)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def calibration_figure(cal: Calibration) -> Figure:
    """Fig. 2: the points and the law used; the bow, what the points and the law depart from
    the best straight line in K (flat for a linear law, the quadratic's curvature otherwise,
    invisible on the voltage scale); the law's residuals in K.

    >>> from spicethermal.identify.calibration import Calibration
    >>> cal = Calibration.fit([20, 40, 60, 80, 100], [0.6, 0.5595, 0.5185, 0.477, 0.435], 2)
    >>> fig = calibration_figure(cal)
    >>> [ax.get_ylabel() for ax in fig.get_axes()]
    ['V_tsp (mV)', 'bow (K)', 'residual (K)']
    >>> fig.get_axes()[0].get_legend().get_texts()[1].get_text()[:15]
    'quadratic law, '
    """
    fig = new_figure(6.4, 6.4)
    grid = fig.add_gridspec(3, 1, height_ratios=[3, 1.4, 1.3])
    ax = fig.add_subplot(grid[0])
    plot_calibration(cal, ax)
    ax.set_xlabel("")  # the temperature axis is labelled once, under the last panel
    ax.set_title("TSP calibration (Fig. 2)", fontsize=10, loc="left")
    t, v = np.asarray(cal.temp_c), np.asarray(cal.v_tsp_v)
    line = np.polynomial.Polynomial.fit(t, v, 1).convert()  # the best straight line
    slope = float(line.coef[1])
    ts = np.linspace(t.min(), t.max(), 200)
    bow = fig.add_subplot(grid[1], sharex=ax)
    bow.axhline(0, color="0.5", lw=0.8)
    bow.plot(t, (v - line(t)) / slope, "o", color="C0", ms=4)
    bow.plot(ts, (cal.voltage(ts) - line(ts)) / slope, "-", color="C1")
    bow.set_ylabel("bow (K)")
    bow.grid(True, alpha=0.3)
    ax2 = fig.add_subplot(grid[2], sharex=ax)
    ax2.axhline(0, color="0.5", lw=0.8)
    ax2.plot(t, cal.residuals_k, "o-", color="C3", ms=4)
    ax2.set_ylabel("residual (K)")
    ax2.set_xlabel("temperature (°C)")
    ax2.grid(True, alpha=0.3)
    return fig


def fig_calibration(cal: Calibration, path: str | os.PathLike) -> Path:
    """Fig. 2 (:func:`calibration_figure`) written to ``path``.

    >>> import tempfile, pathlib
    >>> from spicethermal.identify.calibration import Calibration
    >>> cal = Calibration.fit([20, 40, 60, 80], [0.60, 0.556, 0.5121, 0.468])
    >>> fig_calibration(cal, pathlib.Path(tempfile.mkdtemp()) / "c.png").exists()
    True
    """
    return save_figure(calibration_figure(cal), path)


def fig_table1(table: Table1, path: str | os.PathLike) -> Path:
    """Measured vs datasheet r(t) on log time, with the error in percent underneath."""
    fig = new_figure(6.4, 5.2)
    grid = fig.add_gridspec(2, 1, height_ratios=[3, 1.3])
    ax = fig.add_subplot(grid[0])
    t = np.asarray(table.t_s)
    ax.loglog(t, table.datasheet_r, "s-", color="0.3", label="datasheet")
    ax.loglog(t, table.measured_r, "o-", color="C0", label="measured (this bench)")
    if table.reference_r is not None:
        ax.loglog(t, table.reference_r, "^--", color="C2", label="the paper's bench")
    ax.set_ylabel("r(t) = Zth / Rth (1)")
    ax.set_title(f"{table.device}: thermal impedance vs datasheet (Table 1)", fontsize=10,
                 loc="left")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax2 = fig.add_subplot(grid[1], sharex=ax)
    ax2.axhline(0, color="0.5", lw=0.8)
    ax2.semilogx(t, table.error_percent, "o-", color="C0", label="this bench")
    if table.reference_error_percent is not None:
        ax2.semilogx(t, table.reference_error_percent, "^--", color="C2", label="paper")
    ax2.set_ylabel("error (%)")
    ax2.set_xlabel("time (s)")
    ax2.grid(True, which="both", alpha=0.3)
    return save_figure(fig, path)
