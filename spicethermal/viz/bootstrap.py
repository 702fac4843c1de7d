"""Figures of the bootstrap's bands (:mod:`spicethermal.fit.bootstrap`): the fitted Zth(t), the
time-constant spectrum and the cumulative structure functions, each with its band.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from .base import new_figure, save_figure
from .fit import plot_fit, plot_residuals
from .identify import (
    plot_cumulative_structure,
    plot_differential_structure,
    plot_spectrum,
    plot_spectrum_fit,
)

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ..fit.bootstrap import Band, FitBootstrap, SpectrumBootstrap
    from ..fit.result import FitResult
    from ..identify.spectrum import Spectrum
    from ..identify.structure import Separation, StructureFunction


def shade(ax: Axes, band: Band, color: str = "C0", label: str | None = None) -> None:
    """Draw ``band`` on ``ax`` as a translucent area.

    Parameters
    ----------
    ax : matplotlib Axes
        Where to draw.
    band : Band
        The band.
    color : str
        Its colour.
    label : str, optional
        Legend text (default: the level).

    Examples
    --------
    >>> import numpy as np
    >>> from spicethermal.fit.bootstrap import Band
    >>> from spicethermal.viz.base import axes
    >>> ax = axes(None, 4.0, 3.0)
    >>> shade(ax, Band(np.arange(3.0), np.zeros(3), np.ones(3)))
    >>> ax.get_legend_handles_labels()[1]
    ['95 % bootstrap band']
    """
    ax.fill_between(band.x, band.lo, band.hi, color=color, alpha=0.25, lw=0,
                    label=label or f"{100 * band.level:g} % bootstrap band")


def fig_fit_band(result: FitResult, fb: FitBootstrap, path: str | os.PathLike,
                 title: str | None = None) -> Path:
    """The fit (data, ladder, stages) with its bootstrap band, and the residuals, as a PNG
    written atomically to ``path``.

    Parameters
    ----------
    result : FitResult
        The fit.
    fb : FitBootstrap
        Its bootstrap (:func:`spicethermal.fit.bootstrap.fit_bootstrap`).
    path : path-like
        The PNG.
    title : str, optional
        Above the upper panel.

    Returns
    -------
    Path
        The PNG written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.fit.bootstrap import fit_bootstrap
    >>> from spicethermal.fit.ladder import fit_foster
    >>> t = np.logspace(-4, 1, 40)
    >>> z = Foster.from_tau([1.0, 2.0], [1e-3, 1.0]).zth(t)
    >>> fit = fit_foster(t, z + np.random.default_rng(1).normal(0, 3e-3, t.size))
    >>> png = pathlib.Path(tempfile.mkdtemp()) / "band.png"
    >>> fig_fit_band(fit, fit_bootstrap(fit, n=5), png).stat().st_size > 10000
    True
    """
    fig = new_figure(7.0, 6.5)
    ax_a, ax_b = fig.subplots(2, 1, height_ratios=(3, 1.4))
    plot_fit(result, ax_a)
    shade(ax_a, fb.zth, "C3", f"{100 * fb.zth.level:g} % band ({fb.n} resamples)")
    ax_a.legend(loc="upper left", fontsize="small")
    if title:
        ax_a.set_title(title, fontsize=10, loc="left")
    plot_residuals(result, ax_b)
    return save_figure(fig, path)


def fig_spectrum_band(spectrum: Spectrum, sb: SpectrumBootstrap,
                      path: str | os.PathLike) -> Path:
    """The spectrum figure (Zth and model, derivative, R(τ)) with the band on R(τ), as a PNG
    written atomically to ``path``.

    Parameters
    ----------
    spectrum : Spectrum
        The time-constant spectrum.
    sb : SpectrumBootstrap
        Its bootstrap (:func:`spicethermal.fit.bootstrap.spectrum_bootstrap`).
    path : path-like
        The PNG.

    Returns
    -------
    Path
        The PNG written.
    """
    fig = new_figure(8.0, 9.0)
    ax_a, ax_b, ax_c = fig.subplots(3, 1)
    plot_spectrum_fit(spectrum, ax_a)
    plot_spectrum_fit(spectrum, ax_b, derivative=True)
    plot_spectrum(spectrum, ax_c)
    shade(ax_c, sb.spectrum, "C0", f"{100 * sb.spectrum.level:g} % band ({sb.n} resamples)")
    ax_c.legend(fontsize="small")
    return save_figure(fig, path)


def fig_structure_band(functions: Sequence[StructureFunction], bands: Sequence[Band | None],
                       path: str | os.PathLike, separation: Separation | None = None) -> Path:
    """Cumulative and differential structure functions, bands on the cumulative ones, as a
    PNG written atomically to ``path``.

    Parameters
    ----------
    functions : sequence of StructureFunction
        The structure functions.
    bands : sequence of Band or None
        One band per function (None: none drawn).
    path : path-like
        The PNG.
    separation : Separation, optional
        Where two functions separate, marked.

    Returns
    -------
    Path
        The PNG written.
    """
    fig = new_figure(7.5, 8.0)
    ax_a, ax_b = fig.subplots(2, 1)
    plot_cumulative_structure(list(functions), ax_a, separation)
    for i, band in enumerate(bands):
        if band is not None:
            shade(ax_a, band, f"C{i}")
    ax_a.legend(fontsize="small")
    plot_differential_structure(list(functions), ax_b)
    return save_figure(fig, path)
