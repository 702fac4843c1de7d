"""Figures, organised by the paper's figure they reproduce (and extend).

matplotlib is imported only when a function here is called, and only its object-oriented API
is used (``Figure`` with the Agg canvas, no pyplot state), so nothing here changes a user's
backend. Functions that draw take ``ax=`` (an Axes to draw into; a new figure when omitted)
and return the Axes; ``figN(..., path)`` functions write a whole PNG figure atomically.

Contents
--------
* Fig. 7 — the ladder fit: :func:`plot_fit` (a), :func:`plot_residuals` (b),
  :func:`plot_ladder` (c), all three in :func:`fig7`.
* NID (T3Ster-style analysis): :func:`plot_spectrum_fit`, :func:`plot_spectrum`,
  :func:`fig_spectrum`; structure functions :func:`plot_cumulative_structure`,
  :func:`plot_differential_structure`, :func:`fig_structure` (separation marked).
* Diagnosis — residuals per data set :func:`plot_dataset_residuals`, before/after an effect
  :func:`fig_before_after`, candidates :func:`plot_candidates`, :func:`fig_candidates`,
  the RMS staircase of the iterative diagnosis :func:`plot_staircase`, :func:`fig_staircase`,
  the paper's Table 2 :func:`fig_table2_diagnosis`; all in :func:`diagnosis_figures`.
* Fig. 8 and Table 2 — duty-cycle impedance curves :func:`plot_r_duty`, :func:`fig8`; PWM
  residuals as grouped bars :func:`plot_table2` and heat map :func:`plot_table2_heatmap`, both in
  :func:`fig_table2`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .files import atomic_open

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Sequence

    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .calibration import Calibration
    from .compare import Comparison
    from .datasheet import Table1
    from .diagnose import Diagnosis, TableAnalysis
    from .drive import DriveResult
    from .fit import FitResult
    from .ladder import Cauer, Foster
    from .spectrum import Spectrum
    from .structure import Separation, StructureFunction

__all__ = ["fig7", "new_figure", "plot_fit", "plot_ladder", "plot_residuals", "save_figure"]


# ------------------------------------------------------------------------------ common
def new_figure(width_in: float = 6.4, height_in: float = 4.0) -> Figure:
    """A matplotlib Figure on the Agg canvas (no pyplot, no global state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _axes(ax: Axes | None, width_in: float = 6.4, height_in: float = 4.0) -> Axes:
    return ax if ax is not None else new_figure(width_in, height_in).add_subplot()


def save_figure(fig: Figure, path: str | os.PathLike, dpi: int = 150) -> Path:
    """Write ``fig`` as a PNG file atomically and return the path."""
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=dpi)
    return Path(path)


def _eng(x: float, unit: str) -> str:
    """``0.00213, "J/K"`` -> ``"2.13 mJ/K"``."""
    if x == 0 or not math.isfinite(x):
        return f"{x:g} {unit}"
    k = int(math.floor(math.log10(abs(x)) / 3))
    k = max(-4, min(2, k))
    prefix = {-4: "p", -3: "n", -2: "µ", -1: "m", 0: "", 1: "k", 2: "M"}[k]
    return f"{x / 10 ** (3 * k):.3g} {prefix}{unit}"


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
    >>> from spicethermal.fit import fit_foster
    >>> t = np.logspace(-4, 1, 51)
    >>> ax = plot_fit(fit_foster(t, 2 * (1 - np.exp(-t / 1e-2))))
    >>> ax.get_xscale()
    'log'
    """
    ax = _axes(ax)
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
    ax.set_xlabel("t (s)")
    ax.set_ylabel("Zth (K/W)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax


def plot_residuals(result: FitResult, ax: Axes | None = None) -> Axes:
    """Fig. 7(b): residuals data − fit (K/W) at every data point, with the ±rms band."""
    ax = _axes(ax, height_in=2.5)
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

    >>> from spicethermal.ladder import Foster
    >>> ax = plot_ladder(Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]))
    >>> sorted(" ".join(t.get_text().split()) for t in ax.texts if t.get_text()[0] == "R")
    ['R1 1 K/W', 'R2 2 K/W']
    """
    n = ladder.order
    ax = _axes(ax, width_in=max(4.0, 1.4 * n + 1.5), height_in=2.6)
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
            ax.text(xm, up + 0.22, f"R{i + 1}\n{_eng(ladder.r[i], 'K/W')}",
                    ha="center", va="bottom", fontsize=fs, linespacing=1.1)
            label = f"C{i + 1}\n{_eng(ladder.c[i], 'J/K')}"
            if tau:
                label += f"\nτ = {_eng(ladder.r[i] * ladder.c[i], 's')}"
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
            ax.text((x + xs[i + 1]) / 2, top + 0.22, f"R{i + 1}\n{_eng(ladder.r[i], 'K/W')}",
                    ha="center", va="bottom", fontsize=fs, linespacing=1.1)
            ax.text(x + 0.3, (top + bot) / 2, f"C{i + 1}\n{_eng(ladder.c[i], 'J/K')}",
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
                 f"{ladder.topology.capitalize()} network, Rth = {_eng(ladder.rth, 'K/W')}",
                 fontsize=9, loc="left")
    return ax


# ----------------------------------------------------------------------------- Fig. 7
def fig7(result: FitResult, path: str | os.PathLike, cauer: bool = True,
         title: str | None = None) -> Path:
    """The paper's Fig. 7 for a fit: (a) fit over data, (b) residuals, (c) the ladder(s).

    (c) shows the fitted Foster network and, with ``cauer``, its exact Cauer equivalent.
    Written as a PNG to ``path`` (atomically); returns the path.

    >>> import numpy as np, tempfile, pathlib
    >>> from spicethermal.fit import fit_foster
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


# ------------------------------------------------------------ safe fast drive (drive.py)
__all__ += ["fig_drive", "plot_drive", "plot_drive_duty"]


def plot_drive(result: DriveResult, ax: Axes | None = None, constant: bool = True) -> Axes:
    """Predicted temperatures under the safe fast drive, on logarithmic time.

    The node (period average), the junction mean and its peak (mean + PWM ripple; the
    exact switched peaks for a linear model), ``t_max`` and the target band; with
    ``constant`` also the node and junction peak under the constant hold duty.

    >>> from spicethermal.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> from spicethermal.drive import optimize_drive
    >>> r = optimize_drive(ThermalModel(Foster.from_tau([10.0, 90.0], [1e-3, 1.0])), 90.0,
    ...                    50.0, p_max_w=1.0, two_phase=False)
    >>> plot_drive(r).get_xscale()
    'log'
    """
    ax = _axes(ax, 7.0, 4.2)
    tr = result.trace
    t = tr.t_s
    keep = t > 0
    name = "junction" if result.node == 0 else f"node {result.node}"
    ax.axhline(result.t_max_c, color="C3", lw=1.0, ls="--", label=f"t_max {result.t_max_c:g} °C")
    ax.axhspan(result.target_c - result.tol_k, result.target_c + result.tol_k, color="C2",
               alpha=0.2, lw=0, label=f"target {result.target_c:g} ± {result.tol_k:g} K")
    if tr.exact_t_s.size:
        ex = tr.exact_t_s > 0
        ax.plot(tr.exact_t_s[ex], tr.exact_peak_c[ex], "-", color="C3", lw=0.8, alpha=0.8,
                label="junction peak (exact switched)")
    else:
        ax.plot(t[keep], tr.junction_peak_c[keep], "-", color="C3", lw=0.8,
                label="junction peak (mean + ripple)")
    ax.plot(t[keep], tr.junction_mean_c[keep], "-", color="C1", lw=1.2, label="junction mean")
    if result.node != 0:
        ax.plot(t[keep], tr.node_c[keep], "-", color="C0", lw=1.8, label=f"{name} (drive)")
    if constant:
        ax.plot(t[keep], tr.constant_node_c[keep], ":", color="C0", lw=1.4,
                label=f"{name}, constant duty {result.hold_duty:.3f}")
        ax.plot(t[keep], tr.constant_junction_peak_c[keep], ":", color="C3", lw=1.0,
                label="junction peak, constant duty")
    for tt, style in ((result.time_to_target_s, "-"),
                      (result.constant_duty_time_to_target_s, ":")):
        if math.isfinite(tt) and tt > 0:
            ax.axvline(tt, color="C2", ls=style, lw=1.0)
    ax.set_xscale("log")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("temperature (°C)")
    ax.set_title(f"{result.method} drive: {result.time_to_target_s:.3g} s to target vs "
                 f"{result.constant_duty_time_to_target_s:.3g} s at constant duty "
                 f"(×{result.speedup:.3g})", fontsize=9, loc="left")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="x-small")
    return ax


def plot_drive_duty(result: DriveResult, ax: Axes | None = None) -> Axes:
    """The duty profile of the drive (steps) and the hold duty, on logarithmic time."""
    ax = _axes(ax, 7.0, 2.2)
    times = [t for t, _ in result.schedule]
    duties = [d for _, d in result.schedule]
    t_end = float(result.trace.t_s[-1])
    first = max(result.period_s, times[1] / 10 if len(times) > 1 else result.period_s)
    xs = [first, *times[1:], t_end]
    ys = [*duties, duties[-1]]
    ax.step(xs, ys, where="post", color="C0", lw=1.4, label="drive")
    ax.axhline(result.hold_duty, color="C0", ls=":", lw=1.0,
               label=f"hold duty {result.hold_duty:.3f}")
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.05)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("duty")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper right", fontsize="x-small")
    return ax


def fig_drive(result: DriveResult, path: str | os.PathLike) -> Path:
    """Temperatures over the duty profile, as a PNG written atomically to ``path``.

    >>> import tempfile, pathlib
    >>> from spicethermal.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> from spicethermal.drive import optimize_drive
    >>> r = optimize_drive(ThermalModel(Foster.from_tau([10.0, 90.0], [1e-3, 1.0])), 90.0,
    ...                    50.0, p_max_w=1.0, two_phase=False)
    >>> fig_drive(r, pathlib.Path(tempfile.mkdtemp()) / "drive.png").stat().st_size > 10000
    True
    """
    fig = new_figure(8.0, 6.5)
    grid = fig.add_gridspec(2, 1, height_ratios=[3.0, 1.3])
    ax_t = fig.add_subplot(grid[0])
    ax_d = fig.add_subplot(grid[1], sharex=ax_t)
    plot_drive(result, ax_t)
    plot_drive_duty(result, ax_d)
    ax_t.set_xlabel("")
    return save_figure(fig, path)


# --------------------------------------------------- Fig. 2 and Table 1 (the demo report)
def plot_calibration(cal: Calibration, ax: Axes | None = None) -> Axes:
    """V_tsp against temperature: the points and the fitted curve (paper Fig. 2)."""
    ax = ax if ax is not None else new_figure().add_subplot()
    t = np.asarray(cal.temp_c)
    grid = np.linspace(t.min(), t.max(), 200)
    ax.plot(t, np.asarray(cal.v_tsp_v) * 1e3, "o", color="C0", label="calibration points")
    ax.plot(grid, cal.voltage(grid) * 1e3, "-", color="C1",
            label=f"fit, K = {cal.k_factor_mv_per_k:.3f} mV/K")
    ax.set_xlabel("temperature (°C)")
    ax.set_ylabel("V_tsp (mV)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def fig_calibration(cal: Calibration, path: str | os.PathLike) -> Path:
    """Fig. 2: the calibration with its residuals in kelvin underneath.

    >>> import tempfile, pathlib
    >>> from spicethermal.calibration import Calibration
    >>> cal = Calibration.fit([20, 40, 60, 80], [0.60, 0.556, 0.5121, 0.468])
    >>> fig_calibration(cal, pathlib.Path(tempfile.mkdtemp()) / "c.png").exists()
    True
    """
    fig = new_figure(6.4, 5.2)
    grid = fig.add_gridspec(2, 1, height_ratios=[3, 1.3])
    ax = fig.add_subplot(grid[0])
    plot_calibration(cal, ax)
    ax.set_title("TSP calibration (Fig. 2)", fontsize=10, loc="left")
    ax2 = fig.add_subplot(grid[1], sharex=ax)
    ax2.axhline(0, color="0.5", lw=0.8)
    ax2.plot(np.asarray(cal.temp_c), cal.residuals_k, "o-", color="C3", ms=4)
    ax2.set_ylabel("residual (K)")
    ax2.set_xlabel("temperature (°C)")
    ax2.grid(True, alpha=0.3)
    return save_figure(fig, path)


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


# ------------------------------------- NID: time-constant spectrum and structure functions
__all__ += ["fig_spectrum", "fig_structure", "plot_cumulative_structure",
            "plot_differential_structure", "plot_spectrum", "plot_spectrum_fit"]


def plot_spectrum_fit(spectrum: Spectrum, ax: Axes | None = None,
                      derivative: bool = False) -> Axes:
    """The resampled Zth(t) (or its log-time derivative ``dZth/d ln t``) with the spectrum's
    forward model; the √t extension and the steady-state hold are shaded.

    >>> import numpy as np
    >>> from spicethermal.ladder import Foster
    >>> from spicethermal.spectrum import time_constant_spectrum
    >>> t = np.geomspace(1e-5, 10, 121)
    >>> s = time_constant_spectrum(t, Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]).zth(t))
    >>> plot_spectrum_fit(s, derivative=True).get_ylabel()
    'dZth/d(ln t) (K/W)'
    """
    ax = _axes(ax)
    t = np.asarray(spectrum.tau_s)
    data = spectrum.data_derivative_k_per_w if derivative else spectrum.data_zth_k_per_w
    model = spectrum.derivative(t) if derivative else spectrum.zth(t)
    if data is not None:
        ax.plot(t, data, "o", ms=2.5, mfc="none", color="C0", label="data (log-time grid)")
    ax.plot(t, model, "-", color="C3", lw=1.4, label=f"spectrum model ({spectrum.method})")
    lo, hi = spectrum.t_resolved_s
    ax.axvspan(t[0], lo, color="0.85", lw=0, label="extension / masked")
    ax.axvspan(hi, t[-1], color="0.85", lw=0)
    ax.set_xscale("log")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("dZth/d(ln t) (K/W)" if derivative else "Zth (K/W)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax


def plot_spectrum(spectrum: Spectrum, ax: Axes | None = None, label: str | None = None,
                  **style: Any) -> Axes:
    """Time-constant spectrum R(τ) in K/W per decade of τ, with the resolved window.

    >>> import numpy as np
    >>> from spicethermal.ladder import Foster
    >>> from spicethermal.spectrum import time_constant_spectrum
    >>> t = np.geomspace(1e-5, 10, 121)
    >>> s = time_constant_spectrum(t, Foster.from_tau([1.0], [1e-2]).zth(t))
    >>> plot_spectrum(s).get_xscale()
    'log'
    """
    ax = _axes(ax)
    per_decade = np.asarray(spectrum.r_density_k_per_w) * math.log(10)
    name = label if label is not None else (spectrum.label or spectrum.method)
    ax.plot(spectrum.tau_s, per_decade, lw=1.4,
            label=f"{name} (resolution {spectrum.resolution_decades:.2f} dec)", **style)
    lo, hi = spectrum.t_resolved_s
    ax.axvline(lo, color="0.5", lw=0.8, ls="--")
    ax.axvline(hi, color="0.5", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_xlabel("τ (s)")
    ax.set_ylabel("R(τ) (K/W per decade)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax


def fig_spectrum(spectra: Spectrum | Sequence[Spectrum], path: str | os.PathLike) -> Path:
    """Spectrum figure: (a) Zth data and model, (b) dZth/d ln t, (c) the spectrum R(τ);
    several spectra are overlaid in (c) (and (a), (b) show the first). Written as PNG."""
    items = list(spectra) if isinstance(spectra, list | tuple) else [spectra]
    fig = new_figure(8.0, 9.0)
    ax_a, ax_b, ax_c = fig.subplots(3, 1)
    plot_spectrum_fit(items[0], ax_a)
    plot_spectrum_fit(items[0], ax_b, derivative=True)
    for i, s in enumerate(items):
        plot_spectrum(s, ax_c, color=f"C{i}")
    ax_a.set_title("(a) Zth(t) on the log-time grid" + (f" — {items[0].label}"
                   if items[0].label else ""), fontsize=10, loc="left")
    ax_b.set_title("(b) derivative dZth/d(ln t)", fontsize=10, loc="left")
    ax_c.set_title("(c) time-constant spectrum (dashed: the window the data resolve)",
                   fontsize=10, loc="left")
    return save_figure(fig, path)


def plot_cumulative_structure(functions: StructureFunction | Sequence[StructureFunction],
                              ax: Axes | None = None, separation: Separation | None = None
                              ) -> Axes:
    """Cumulative structure function(s): ΣC (log) against ΣR from the junction outwards;
    the resolved part solid, the rest thin; a separation point marked.

    >>> from spicethermal.ladder import Cauer
    >>> from spicethermal.structure import StructureFunction
    >>> ax = plot_cumulative_structure(StructureFunction.from_ladder(Cauer([1, 2], [1e-3, 1])))
    >>> ax.get_yscale()
    'log'
    """
    ax = _axes(ax)
    items = list(functions) if isinstance(functions, list | tuple) else [functions]
    for i, sf in enumerate(items):
        color = f"C{i}"
        r, c = np.asarray(sf.r_k_per_w), np.asarray(sf.c_j_per_k)
        ok = sf.resolved()
        ax.step(r, c, where="pre", color=color, lw=0.7, alpha=0.5)
        rr, cc = np.where(ok, r, np.nan), np.where(ok, c, np.nan)
        ax.step(rr, cc, where="pre", color=color, lw=1.8,
                label=f"{sf.label or f'#{i + 1}'}: Rth = {sf.rth_k_per_w:.3g} K/W")
    if separation is not None and separation.r_k_per_w is not None:
        ax.axvline(separation.r_k_per_w, color="k", ls="--", lw=1.0)
        ax.plot([separation.r_k_per_w], [separation.c_j_per_k], "kD", ms=6,
                label=f"separation: ΣR = {separation.r_k_per_w:.3g} K/W "
                      f"(|Δlog ΣC| > {separation.threshold_decades:g})")
    ax.set_yscale("log")
    hi = max(float(np.max(np.asarray(sf.c_j_per_k)[sf.resolved()], initial=0)) for sf in items)
    lo = min(float(np.asarray(sf.c_j_per_k)[0]) for sf in items)
    if hi > lo > 0:
        ax.set_ylim(lo / 2, hi * 20)
    ax.set_xlabel("ΣR from the junction (K/W)")
    ax.set_ylabel("ΣC (J/K)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax


def plot_differential_structure(functions: StructureFunction | Sequence[StructureFunction],
                                ax: Axes | None = None, separation: Separation | None = None
                                ) -> Axes:
    """Differential structure function(s) K = dΣC/dΣR (log) against ΣR (resolved part)."""
    ax = _axes(ax)
    items = list(functions) if isinstance(functions, list | tuple) else [functions]
    for i, sf in enumerate(items):
        r, k = sf.differential()
        ok = sf.resolved()[1:]
        ax.plot(np.where(ok, r, np.nan), np.where(ok & (k > 0), k, np.nan), "-",
                color=f"C{i}", lw=1.4, label=sf.label or f"#{i + 1}")
    if separation is not None and separation.r_k_per_w is not None:
        ax.axvline(separation.r_k_per_w, color="k", ls="--", lw=1.0)
    ax.set_yscale("log")
    ax.set_xlabel("ΣR from the junction (K/W)")
    ax.set_ylabel("K = dΣC/dΣR (W²·s/K²)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax


def fig_structure(functions: StructureFunction | Sequence[StructureFunction],
                  path: str | os.PathLike, separation: Separation | None = None) -> Path:
    """Structure-function figure: (a) cumulative, (b) differential; with two curves the
    separation point is marked. Written as PNG; returns the path.

    >>> import tempfile, pathlib
    >>> from spicethermal.ladder import Cauer
    >>> from spicethermal.structure import StructureFunction, separation
    >>> a = StructureFunction.from_ladder(Cauer([0.2, 0.3, 1.0, 2.0], [0.01, 0.05, 0.1, 20]))
    >>> b = StructureFunction.from_ladder(Cauer([0.2, 0.3, 0.3, 2.0], [0.01, 0.05, 0.1, 20]))
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "sf.png"
    >>> fig_structure([a, b], out, separation(a, b)).stat().st_size > 10000
    True
    """
    fig = new_figure(8.0, 8.0)
    ax_a, ax_b = fig.subplots(2, 1, sharex=True)
    plot_cumulative_structure(functions, ax_a, separation)
    plot_differential_structure(functions, ax_b, separation)
    ax_a.set_title("(a) cumulative structure function (thin: outside the resolved range)",
                   fontsize=10, loc="left")
    ax_b.set_title("(b) differential structure function", fontsize=10, loc="left")
    ax_a.set_xlabel("")
    return save_figure(fig, path)


# ---------------------------------------------- diagnosis: before/after residuals (diagnose.py)
def _residual_axes_style(ax: Axes, dataset: str) -> None:
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.grid(True, which="both", alpha=0.3)
    if dataset == "pwm":
        ax.set_xscale("log")
        ax.set_xlabel("PWM frequency (Hz)")
    elif dataset == "calibration":
        ax.set_xlabel("calibration temperature (°C)")
    else:
        ax.set_xscale("log")
        ax.set_xlabel("time after the cut (s)")
    ax.set_ylabel("measured − model (K)")


def plot_dataset_residuals(comparison: Comparison, dataset: str, ax: Axes | None = None,
                           color: str | None = None) -> Axes:
    """Residuals (K) of one data set of a :class:`~spicethermal.compare.Comparison`: cooling
    curves against log time, the PWM grid against frequency (one line per duty), the
    calibration against temperature.

    >>> from spicethermal.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("cooling_1", {"t_s": 1e-3}, 30.0, 29.5),
    ...                 ComparisonPoint("cooling_1", {"t_s": 1e-2}, 29.0, 29.1)))
    >>> plot_dataset_residuals(c, "cooling_1").get_ylabel()
    'measured − model (K)'
    """
    ax = _axes(ax)
    sub = comparison.dataset(dataset)
    r = sub.residuals_k
    if dataset == "pwm":
        duties = sorted({p.at["duty"] for p in sub.points})
        for k, d in enumerate(duties):
            pts = sorted((p for p in sub.points if p.at["duty"] == d),
                         key=lambda p: p.at["freq_hz"])
            ax.plot([p.at["freq_hz"] for p in pts], [p.residual_k for p in pts], "o-",
                    color=f"C{k}", ms=4, label=f"D = {100 * d:g} %")
        if duties:
            ax.legend(fontsize=7)
    elif dataset == "calibration":
        ax.plot([p.at["temp_c"] for p in sub.points], r, "o-", color=color or "C3", ms=4)
    else:
        ax.plot([p.at["t_s"] for p in sub.points], r, "o-", color=color or "C0", ms=3, lw=0.8)
    _residual_axes_style(ax, dataset)
    return ax


def fig_before_after(before: Comparison, after: Comparison, path: str | os.PathLike,
                     titles: Sequence[str] = ("before", "after")) -> Path:
    """Residuals of every data set, before (left) and after (right) an effect is added, one
    row per data set with a shared vertical scale, so the error can be seen to fall.

    >>> import tempfile, pathlib
    >>> from spicethermal.compare import Comparison, ComparisonPoint
    >>> b = Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, 31.0),))
    >>> a = Comparison((ComparisonPoint("pwm", {"freq_hz": 1e3, "duty": 0.5}, 30.0, 30.1),))
    >>> fig_before_after(b, a, pathlib.Path(tempfile.mkdtemp()) / "ba.png").exists()
    True
    """
    names = list(dict.fromkeys([*before.datasets, *after.datasets]))
    names = [n for n in names if before.dataset(n) != after.dataset(n)] or names  # no twins
    fig = new_figure(9.0, 2.3 * max(len(names), 1) + 0.4)
    axes = fig.subplots(max(len(names), 1), 2, squeeze=False)
    for row, name in enumerate(names):
        lim = 0.0
        for col, (cmp, title) in enumerate(zip((before, after), titles, strict=True)):
            ax = axes[row][col]
            plot_dataset_residuals(cmp, name, ax)
            sub = cmp.dataset(name)
            if sub.points:
                lim = max(lim, sub.max_abs_k)
                ax.set_title(f"{title}: {name}, RMS {sub.rms_k:.3g} K", fontsize=9, loc="left")
        for col in (0, 1):
            if lim > 0:
                axes[row][col].set_ylim(-1.1 * lim, 1.1 * lim)
    return save_figure(fig, path)


def plot_candidates(result: Diagnosis, ax: Axes | None = None) -> Axes:
    """Pooled RMS of the baseline and of every candidate effect (log scale), the verdict's
    candidate highlighted, the improvement written on each bar."""
    ax = _axes(ax, 6.4, 3.2)
    names = ["baseline"] + [c.effect.name for c in result.candidates]
    values = [result.baseline.rms_k] + [c.rms_k for c in result.candidates]
    colors = ["0.6"] + ["C2" if c.effect.name == result.verdict_effect else "C0"
                        for c in result.candidates]
    y = np.arange(len(names))[::-1]
    ax.barh(y, values, color=colors)
    for yi, v, c in zip(y[1:], values[1:], result.candidates, strict=True):
        ax.text(v, yi, f" {c.improvement:.1f}×", va="center", fontsize=8)
    ax.set_yticks(y, names, fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("RMS over every data set (K)")
    ax.grid(True, axis="x", which="both", alpha=0.3)
    ax.set_title(f"verdict: {result.verdict_effect or 'none'}", fontsize=10, loc="left")
    return ax


def fig_candidates(result: Diagnosis, path: str | os.PathLike) -> Path:
    """:func:`plot_candidates` as a PNG file."""
    fig = new_figure(6.4, 0.45 * (len(result.candidates) + 1) + 1.2)
    plot_candidates(result, fig.add_subplot())
    return save_figure(fig, path)


def plot_staircase(result: Diagnosis, ax: Axes | None = None) -> Axes:
    """The RMS error falling with each effect added by the iterative diagnosis (log scale),
    each step labelled with its effect, form and improvement; the noise level dashed."""
    ax = _axes(ax, 6.4, 3.2)
    labels = ["baseline"] + [f"+ {s.chosen.effect.name}\n({s.chosen.effect.form})"
                             for s in result.steps]
    values = [result.baseline.rms_k] + [s.chosen.rms_k for s in result.steps]
    x = np.arange(len(values))
    ax.step(x, values, where="mid", color="C0")
    ax.plot(x, values, "o", color="C0")
    for xi, s in zip(x[1:], result.steps, strict=True):
        ax.annotate(f"{s.chosen.improvement:.3g}×", (xi, s.chosen.rms_k), fontsize=8,
                    textcoords="offset points", xytext=(4, 4))
    noise = float(np.sqrt(np.mean([v ** 2 for v in result.noise_k.values()])))
    ax.axhline(noise, color="0.5", ls="--", lw=1, label=f"noise ≈ {noise:.2g} K")
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("RMS over every data set (K)")
    ax.legend(fontsize="small")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.set_title("error after each added effect", fontsize=10, loc="left")
    return ax


def fig_staircase(result: Diagnosis, path: str | os.PathLike) -> Path:
    """:func:`plot_staircase` as a PNG file."""
    fig = new_figure(6.4, 3.4)
    plot_staircase(result, fig.add_subplot())
    return save_figure(fig, path)


def diagnosis_figures(result: Diagnosis, out_dir: str | os.PathLike) -> list[Path]:
    """The diagnosis figures, written into ``out_dir``: the RMS staircase of the steps
    (``diagnosis_steps.png``), the residuals before and after the effects found
    (``diagnosis_before_after.png``; after = the best candidate when no effect was found),
    before and after each step when there are several (``diagnosis_step_K.png``), the
    candidates (``diagnosis_candidates.png``) and, for a Table-2 diagnosis, Δ(f, D) with the
    explanations tried (``diagnosis_table2.png``).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [fig_staircase(result, out / "diagnosis_steps.png")]
    best = result.best or (result.candidates[0] if result.candidates else None)
    after = result.final if result.steps else (best.comparison if best is not None
                                                 else result.baseline)
    label = ("with " + ", ".join(result.effects) if result.steps else
             f"with {best.effect.name}" if best is not None else "(no candidate)")
    paths.append(fig_before_after(result.baseline, after, out / "diagnosis_before_after.png",
                                  ("baseline", label)))
    if len(result.steps) > 1:
        prev, prev_label = result.baseline, "baseline"
        for k, s in enumerate(result.steps, 1):
            name = f"+ {s.chosen.effect.name}"
            paths.append(fig_before_after(prev, s.chosen.comparison,
                                          out / f"diagnosis_step_{k}.png", (prev_label, name)))
            prev, prev_label = s.chosen.comparison, name
    if result.candidates:
        paths.append(fig_candidates(result, out / "diagnosis_candidates.png"))
    table2 = result.extra.get("table2")
    if table2 is not None:
        paths.append(fig_table2_diagnosis(table2, out / "diagnosis_table2.png"))
    return paths


def fig_table2_diagnosis(analysis: TableAnalysis, path: str | os.PathLike) -> Path:
    """A measured-vs-simulated PWM table (the paper's Table 2) and the explanations tried:
    (a) both columns against frequency per duty, with the mean rise D·P·Rth; (b) Δ = measured
    − simulated (points) with the sample window's prediction (dashed) and the early-time
    one (dotted)."""
    a = analysis
    fig = new_figure(9.0, 3.8)
    ax1, ax2 = fig.subplots(1, 2)
    km = a.mean_model["measured"][0]
    for k, d in enumerate(sorted(set(a.duty.tolist()))):
        sel = a.duty == d
        order = np.argsort(a.freq_hz[sel])
        f = a.freq_hz[sel][order]
        color = f"C{k}"
        ax1.plot(f, a.exp_k[sel][order], "o-", color=color, ms=4, label=f"measured, D = {d:.0%}")
        ax1.plot(f, a.model_k[sel][order], "s--", color=color, ms=3, mfc="none",
                 label="simulated")
        ax1.axhline(km * d, color=color, lw=0.6, ls=":")
        ax2.plot(f, a.delta_k[sel][order], "o", color=color, ms=5, label=f"Δ, D = {d:.0%}")
        ax2.plot(f, a.paper_window_pred_k[sel][order], "--", color=color, lw=1.2)
        ax2.plot(f, a.early_pred_k[sel][order], ":", color=color, lw=1.2)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xlabel("PWM frequency (Hz)")
        ax.grid(True, which="both", alpha=0.3)
    ax1.set_ylabel("rise over the reference (K)")
    ax1.set_title("(a) readings; dotted: D·P·Rth", fontsize=9, loc="left")
    ax1.legend(fontsize=6, ncol=2)
    ax2.axhline(0.0, color="0.5", lw=0.8)
    ax2.set_ylabel("measured − simulated (K)")
    ax2.set_title(f"(b) Δ; dashed: {a.window_s * 1e6:g} µs window, dotted: early time",
                  fontsize=9, loc="left")
    ax2.legend(fontsize=7)
    return save_figure(fig, path)


# ========================================== PWM: Fig. 8 and Table 2 (pwmsim.py, compare.py)
__all__ += ["FIG8_DUTIES", "fig8", "fig_table2", "plot_r_duty", "plot_table2",
            "plot_table2_heatmap"]

#: The duty cycles of the paper's Fig. 8.
FIG8_DUTIES = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)


def plot_r_duty(ladder: Foster | Cauer, duties: Sequence[float] = FIG8_DUTIES,
                t_s: Sequence[float] | None = None, ax: Axes | None = None,
                eq3: bool = True, exact: bool = True) -> Axes:
    """Fig. 8: duty-cycle impedance curves Zth,D(t) = Rth · r_D(t) in K/W on log-log axes, one
    colour per duty.

    Dashed: the paper's eq. 3, ``D + (1 − D) r(t)``; solid: the exact periodic-steady-state
    peak per watt for pulses of width t at duty D (:func:`spicethermal.pwm.r_duty_exact`).
    ``t_s`` (pulse widths) defaults to a decade below the fastest to a decade above the slowest
    time constant.

    >>> from spicethermal.ladder import Foster
    >>> ax = plot_r_duty(Foster.from_tau([1.0, 2.0], [1e-3, 1.0]), duties=(0.0, 0.5))
    >>> len(ax.get_lines()), ax.get_xscale(), ax.get_yscale()
    (4, 'log', 'log')
    """
    from .pwm import r_duty_eq3, r_duty_exact

    ax = _axes(ax, 6.4, 4.6)
    if t_s is None:
        taus = ladder.time_constants()
        t = np.logspace(math.log10(taus[0]) - 1, math.log10(taus[-1]) + 1, 300)
    else:
        t = np.asarray(t_s, dtype=float)
    cmap = _duty_colours(len(duties))
    for k, d in enumerate(duties):
        label = f"D = {d:g}"
        if exact:
            ax.plot(t, ladder.rth * r_duty_exact(ladder, t, d), "-", color=cmap[k], lw=1.3,
                    label=label)
        if eq3:
            ax.plot(t, ladder.rth * r_duty_eq3(ladder, t, d), "--", color=cmap[k], lw=1.0,
                    label=None if exact else label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("pulse width t (s)")
    ax.set_ylabel("Zth,D(t) = Rth · r_D(t) (K/W)")
    kinds = " and ".join(x for x, on in (("exact (solid)", exact), ("eq. 3 (dashed)", eq3)) if on)
    ax.set_title(f"Impedance curves for duty cycles D, {kinds}; Rth = "
                 f"{_eng(ladder.rth, 'K/W')}", fontsize=9, loc="left")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="x-small", ncol=2, loc="lower right")
    return ax


def _duty_colours(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    return [cmap(x) for x in np.linspace(0.0, 0.9, max(n, 1))]


def fig8(ladder: Foster | Cauer, path: str | os.PathLike,
         duties: Sequence[float] = FIG8_DUTIES, title: str | None = None) -> Path:
    """The paper's Fig. 8 for ``ladder`` as a PNG (atomically); returns the path.

    >>> import tempfile, pathlib
    >>> from spicethermal.ladder import Foster
    >>> f = Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0])
    >>> fig8(f, pathlib.Path(tempfile.mkdtemp()) / "fig8.png").stat().st_size > 10000
    True
    """
    fig = new_figure(7.0, 5.0)
    ax = plot_r_duty(ladder, duties, ax=fig.add_subplot())
    if title:
        ax.set_title(f"{title}\n{ax.get_title(loc='left')}", fontsize=9, loc="left")
    return save_figure(fig, path)


def _pwm_grid(comparison: Comparison) -> tuple[list[float], list[float], np.ndarray]:
    """Frequencies, duties and the Δ matrix (NaN where a cell has no point) of the pwm set."""
    pts = comparison.dataset("pwm").points
    if not pts:
        from .errors import DataFormatError

        raise DataFormatError("the comparison has no pwm points to plot")
    freqs = sorted({p.at["freq_hz"] for p in pts})
    duties = sorted({p.at["duty"] for p in pts})
    delta = np.full((len(freqs), len(duties)), np.nan)
    for p in pts:
        delta[freqs.index(p.at["freq_hz"]), duties.index(p.at["duty"])] = p.residual_k
    return freqs, duties, delta


def plot_table2(comparison: Comparison, ax: Axes | None = None) -> Axes:
    """Table 2 as grouped bars: Δ = T_exp − T_mod (K) per frequency, one bar per duty.

    >>> from spicethermal.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("pwm", {"freq_hz": 500.0, "duty": 0.2}, 27.2, 27.56),
    ...                 ComparisonPoint("pwm", {"freq_hz": 25e3, "duty": 0.8}, 37.7, 37.1)))
    >>> len(plot_table2(c).patches)
    4
    """
    freqs, duties, delta = _pwm_grid(comparison)
    ax = _axes(ax, 7.0, 3.8)
    x = np.arange(len(freqs))
    width = 0.8 / len(duties)
    colours = _duty_colours(len(duties))
    for k, d in enumerate(duties):
        ax.bar(x + (k - (len(duties) - 1) / 2) * width, np.nan_to_num(delta[:, k]), width,
               color=colours[k], label=f"D = {100 * d:g} %")
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xticks(x, [f"{f / 1e3:g}" for f in freqs])
    ax.set_xlabel("frequency (kHz)")
    ax.set_ylabel("Δ = T_exp − T_mod (K)")
    ax.set_title(f"PWM readings, measured − model (rms {comparison.dataset('pwm').rms_k:.2f} K, "
                 f"engine {comparison.engine})", fontsize=9, loc="left")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize="x-small")
    return ax


def plot_table2_heatmap(comparison: Comparison, ax: Axes | None = None) -> Axes:
    """Table 2 as a heat map of Δ (K) over frequency × duty, values written in the cells;
    a diverging colour scale centred on 0 (red: the bench reads hotter than the model).

    >>> from spicethermal.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("pwm", {"freq_hz": 500.0, "duty": 0.2}, 27.2, 27.56),
    ...                 ComparisonPoint("pwm", {"freq_hz": 25e3, "duty": 0.8}, 37.7, 37.1)))
    >>> len(plot_table2_heatmap(c).texts)
    2
    """
    freqs, duties, delta = _pwm_grid(comparison)
    ax = _axes(ax, 4.2, 4.2)
    limit = float(np.nanmax(np.abs(delta))) or 1.0
    image = ax.imshow(delta, cmap="RdBu_r", vmin=-limit, vmax=limit, aspect="auto",
                      origin="lower")
    for i in range(len(freqs)):
        for k in range(len(duties)):
            if np.isfinite(delta[i, k]):
                ax.text(k, i, f"{delta[i, k]:+.2f}", ha="center", va="center", fontsize=8,
                        color="white" if abs(delta[i, k]) > 0.6 * limit else "black")
    ax.set_xticks(range(len(duties)), [f"{100 * d:g} %" for d in duties])
    ax.set_yticks(range(len(freqs)), [f"{f / 1e3:g}" for f in freqs])
    ax.set_xlabel("duty (%)")
    ax.set_ylabel("frequency (kHz)")
    ax.figure.colorbar(image, ax=ax, label="Δ = T_exp − T_mod (K)")
    return ax


def fig_table2(comparison: Comparison, path: str | os.PathLike,
               title: str | None = None) -> Path:
    """Grouped bars and heat map of the PWM residuals side by side, as a PNG; returns the path.

    >>> import tempfile, pathlib
    >>> from spicethermal.compare import Comparison, ComparisonPoint
    >>> c = Comparison(tuple(ComparisonPoint("pwm", {"freq_hz": f, "duty": d}, 30.0, 30.0 + d)
    ...                      for f in (500.0, 1e3) for d in (0.2, 0.8)))
    >>> fig_table2(c, pathlib.Path(tempfile.mkdtemp()) / "t2.png").stat().st_size > 10000
    True
    """
    fig = new_figure(11.0, 4.2)
    grid = fig.add_gridspec(1, 2, width_ratios=[1.7, 1.0])
    plot_table2(comparison, fig.add_subplot(grid[0]))
    plot_table2_heatmap(comparison, fig.add_subplot(grid[1]))
    if title:
        fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)
