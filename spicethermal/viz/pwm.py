"""Figures of PWM operation: the safe fast drive (drive.py), the duty-cycle impedance family
(Fig. 8) and the measured-vs-simulated Table 2 as grouped bars and a heat map.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Sequence

    from matplotlib.axes import Axes

    from ..analysis.compare import Comparison
    from ..core.ladder import Cauer, Foster

from ..core.errors import DataFormatError
from ..engines.pwm import r_duty_eq3, r_duty_exact
from .base import axes, eng, new_figure, save_figure

# ------------------------------------------------------------ safe fast drive (drive.py)

class DriveResult(Protocol):
    """What the figures read of a drive (:class:`spicethermal.drive.result.DriveResult`: the
    figures know its shape, not its module, which draws itself through them)."""

    node: int
    t_max_c: float
    target_c: float
    tol_k: float
    hold_duty: float
    schedule: Sequence[tuple[float, float]]
    method: str
    time_to_target_s: float
    constant_duty_time_to_target_s: float
    trace: Any  # a DriveTrace: t_s, node_c, junction_mean_c, junction_peak_c, ...

    @property
    def speedup(self) -> float: ...

    @property
    def period_s(self) -> float: ...


def plot_drive(result: DriveResult, ax: Axes | None = None, constant: bool = True) -> Axes:
    """Predicted temperatures under the safe fast drive, on logarithmic time.

    The node (period average), the junction mean and its peak (mean + PWM ripple; the
    exact switched peaks for a linear model), ``t_max`` and the target band; with
    ``constant`` also the node and junction peak under the constant hold duty.

    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> from spicethermal.drive.optimize import optimize_drive
    >>> r = optimize_drive(ThermalModel(Foster.from_tau([10.0, 90.0], [1e-3, 1.0])), 90.0,
    ...                    50.0, p_max_w=1.0, two_phase=False)
    >>> plot_drive(r).get_xscale()
    'log'
    """
    ax = axes(ax, 7.0, 4.2)
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
    ax = axes(ax, 7.0, 2.2)
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
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.model import ThermalModel
    >>> from spicethermal.drive.optimize import optimize_drive
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


# ========================================== PWM: Fig. 8 and Table 2 (pwmsim.py, compare.py)
#: The duty cycles of the paper's Fig. 8.
FIG8_DUTIES = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)


def plot_r_duty(ladder: Foster | Cauer, duties: Sequence[float] = FIG8_DUTIES,
                t_s: Sequence[float] | None = None, ax: Axes | None = None,
                eq3: bool = True, exact: bool = True) -> Axes:
    """Fig. 8: duty-cycle impedance curves Zth,D(t) = Rth · r_D(t) in K/W on log-log axes, one
    colour per duty.

    Dashed: the paper's eq. 3, ``D + (1 − D) r(t)``; solid: the exact periodic-steady-state
    peak per watt for pulses of width t at duty D (:func:`spicethermal.engines.pwm.r_duty_exact`).
    ``t_s`` (pulse widths) defaults to a decade below the fastest to a decade above the slowest
    time constant.

    >>> from spicethermal.core.ladder import Foster
    >>> ax = plot_r_duty(Foster.from_tau([1.0, 2.0], [1e-3, 1.0]), duties=(0.0, 0.5))
    >>> len(ax.get_lines()), ax.get_xscale(), ax.get_yscale()
    (4, 'log', 'log')
    """
    ax = axes(ax, 6.4, 4.6)
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
                 f"{eng(ladder.rth, 'K/W')}", fontsize=9, loc="left")
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
    >>> from spicethermal.core.ladder import Foster
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

        raise DataFormatError("the comparison has no pwm points to plot")
    freqs = sorted({p.at["freq_hz"] for p in pts})
    duties = sorted({p.at["duty"] for p in pts})
    delta = np.full((len(freqs), len(duties)), np.nan)
    for p in pts:
        delta[freqs.index(p.at["freq_hz"]), duties.index(p.at["duty"])] = p.residual_k
    return freqs, duties, delta


def plot_table2(comparison: Comparison, ax: Axes | None = None) -> Axes:
    """Table 2 as grouped bars: Δ = T_exp − T_mod (K) per frequency, one bar per duty.

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("pwm", {"freq_hz": 500.0, "duty": 0.2}, 27.2, 27.56),
    ...                 ComparisonPoint("pwm", {"freq_hz": 25e3, "duty": 0.8}, 37.7, 37.1)))
    >>> len(plot_table2(c).patches)
    4
    """
    freqs, duties, delta = _pwm_grid(comparison)
    ax = axes(ax, 7.0, 3.8)
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

    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
    >>> c = Comparison((ComparisonPoint("pwm", {"freq_hz": 500.0, "duty": 0.2}, 27.2, 27.56),
    ...                 ComparisonPoint("pwm", {"freq_hz": 25e3, "duty": 0.8}, 37.7, 37.1)))
    >>> len(plot_table2_heatmap(c).texts)
    2
    """
    freqs, duties, delta = _pwm_grid(comparison)
    ax = axes(ax, 4.2, 4.2)
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
    >>> from spicethermal.analysis.compare import Comparison, ComparisonPoint
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
