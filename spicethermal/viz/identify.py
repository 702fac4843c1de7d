"""Figures of the network identification (NID, T3Ster-style): the time-constant spectrum and
its fit, cumulative and differential structure functions with the separation marked.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Sequence

    from matplotlib.axes import Axes

    from ..identify.spectrum import Spectrum
    from ..identify.structure import Separation, StructureFunction

from .base import axes, finish, new_figure, save_figure

# ------------------------------------- NID: time-constant spectrum and structure functions

def plot_spectrum_fit(spectrum: Spectrum, ax: Axes | None = None,
                      derivative: bool = False) -> Axes:
    """The resampled Zth(t) (or its log-time derivative ``dZth/d ln t``) with the spectrum's
    forward model; the √t extension and the steady-state hold are shaded.

    >>> import numpy as np
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.identify.spectrum import time_constant_spectrum
    >>> t = np.geomspace(1e-5, 10, 121)
    >>> s = time_constant_spectrum(t, Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]).zth(t))
    >>> plot_spectrum_fit(s, derivative=True).get_ylabel()
    'dZth/d(ln t) (K/W)'
    """
    ax = axes(ax)
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
    return finish(ax, "t (s)", "dZth/d(ln t) (K/W)" if derivative else "Zth (K/W)")


def plot_spectrum(spectrum: Spectrum, ax: Axes | None = None, label: str | None = None,
                  **style: Any) -> Axes:
    """Time-constant spectrum R(τ) in K/W per decade of τ, with the resolved window.

    >>> import numpy as np
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.identify.spectrum import time_constant_spectrum
    >>> t = np.geomspace(1e-5, 10, 121)
    >>> s = time_constant_spectrum(t, Foster.from_tau([1.0], [1e-2]).zth(t))
    >>> plot_spectrum(s).get_xscale()
    'log'
    """
    ax = axes(ax)
    per_decade = np.asarray(spectrum.r_density_k_per_w) * math.log(10)
    name = label if label is not None else (spectrum.label or spectrum.method)
    ax.plot(spectrum.tau_s, per_decade, lw=1.4,
            label=f"{name} (resolution {spectrum.resolution_decades:.2f} dec)", **style)
    lo, hi = spectrum.t_resolved_s
    ax.axvline(lo, color="0.5", lw=0.8, ls="--")
    ax.axvline(hi, color="0.5", lw=0.8, ls="--")
    ax.set_xscale("log")
    return finish(ax, "τ (s)", "R(τ) (K/W per decade)")


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

    >>> from spicethermal.core.ladder import Cauer
    >>> from spicethermal.identify.structure import StructureFunction
    >>> ax = plot_cumulative_structure(StructureFunction.from_ladder(Cauer([1, 2], [1e-3, 1])))
    >>> ax.get_yscale()
    'log'
    """
    ax = axes(ax)
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
    return finish(ax, "ΣR from the junction (K/W)", "ΣC (J/K)")


def plot_differential_structure(functions: StructureFunction | Sequence[StructureFunction],
                                ax: Axes | None = None, separation: Separation | None = None
                                ) -> Axes:
    """Differential structure function(s) K = dΣC/dΣR (log) against ΣR (resolved part)."""
    ax = axes(ax)
    items = list(functions) if isinstance(functions, list | tuple) else [functions]
    for i, sf in enumerate(items):
        r, k = sf.differential()
        ok = sf.resolved()[1:]
        ax.plot(np.where(ok, r, np.nan), np.where(ok & (k > 0), k, np.nan), "-",
                color=f"C{i}", lw=1.4, label=sf.label or f"#{i + 1}")
    if separation is not None and separation.r_k_per_w is not None:
        ax.axvline(separation.r_k_per_w, color="k", ls="--", lw=1.0)
    ax.set_yscale("log")
    return finish(ax, "ΣR from the junction (K/W)", "K = dΣC/dΣR (W²·s/K²)")


def fig_structure(functions: StructureFunction | Sequence[StructureFunction],
                  path: str | os.PathLike, separation: Separation | None = None) -> Path:
    """Structure-function figure: (a) cumulative, (b) differential; with two curves the
    separation point is marked. Written as PNG; returns the path.

    >>> import tempfile, pathlib
    >>> from spicethermal.core.ladder import Cauer
    >>> from spicethermal.identify.structure import StructureFunction, separation
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
