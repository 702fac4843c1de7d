"""The early-time correction made visible: the cooling record against √t near the cut, the
masked electrical transient, the √t fit window and the fitted line back to Tj(0)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..io.files import atomic_open

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike

    from ..identify.curves import EarlyTimeFix


def fig_early_time(t_s: ArrayLike, tj_c: ArrayLike, early: EarlyTimeFix,
                   path: str | os.PathLike, title: str | None = None) -> Path:
    """Tj against √t up to 3× the end of the fit window: samples, masked span (grey), fit
    window (green), the fit ``T0 − k √t`` extended to t = 0 and its ``T0``. Written as a PNG
    (atomically); returns the path.

    >>> import tempfile, pathlib
    >>> from spicethermal.identify.curves import ZthCurve
    >>> t = np.geomspace(1e-6, 1.0, 400)
    >>> z = ZthCurve.from_cooling(t, 40 - 20 * np.sqrt(t), 1.0, tref_steady_c=25.0,
    ...                           mask_s=1e-4)
    >>> p = fig_early_time(t, 40 - 20 * np.sqrt(t), z.early,
    ...                    pathlib.Path(tempfile.mkdtemp()) / "e.png")
    >>> p.stat().st_size > 10000
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    t = np.asarray(t_s, dtype=float)
    tj = np.asarray(tj_c, dtype=float)
    if t.shape != tj.shape or t.size == 0:
        raise DataFormatError("early-time figure: t_s and tj_c must be equally long")
    lo, hi = early.fit_window_s
    show = (t > 0) & (t <= 3 * hi)
    x = np.sqrt(t[show])
    fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    masked = t[show] < early.masked_s[1]
    ax.plot(x[~masked], tj[show][~masked], ".", ms=2.5, color="C0", label="record")
    if masked.any():
        ax.plot(x[masked], tj[show][masked], ".", ms=2.5, color="0.6",
                label=f"masked ({early.masked_points} samples)")
        ax.axvspan(0.0, np.sqrt(early.masked_s[1]), color="0.9", zorder=0)
    ax.axvspan(np.sqrt(lo), np.sqrt(hi), color="C2", alpha=0.15, zorder=0,
               label=f"fit window {lo:.3g}..{hi:.3g} s")
    xs = np.linspace(0.0, float(x.max()) if x.size else np.sqrt(hi), 100)
    ax.plot(xs, early.t0_c - early.slope_k_per_sqrt_s * xs, "-", color="C3", lw=1.2,
            label=f"T0 − k√t: T0 = {early.t0_c:.4g} °C, k = {early.slope_k_per_sqrt_s:.4g} K/√s")
    ax.plot([0.0], [early.t0_c], "o", color="C3")
    ax.set_xlabel("√t (√s)")
    ax.set_ylabel("Tj (°C)")
    ax.set_xlim(left=0.0)
    ax.set_title(title or f"early-time correction (rms {early.fit_rms_k:.3g} K over "
                          f"{early.fit_points} samples)", fontsize=9, loc="left")
    ax.legend(fontsize=8)
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=120)
    plt.close(fig)
    return Path(path)
