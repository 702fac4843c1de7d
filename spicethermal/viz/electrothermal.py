"""Figures of the heater as an electrothermal part (issue #46): the diode law fitted to the
bench's forward points, and Vf, I and Tj over a few PWM periods of the bench circuit.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .base import new_figure, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from ..engines.circuit import CircuitRun
    from ..fit.diode import DiodeFit
    from ..io.datasets import ForwardTable


def fig_circuit(run: CircuitRun, path: str | os.PathLike, title: str = "") -> Path:
    """Vf, I and Tj of the heater in the bench circuit over the run's periods, the sample
    window at the end (three panels sharing the time axis, ms).

    Parameters
    ----------
    run : CircuitRun
        A run of :class:`~spicethermal.engines.circuit.CircuitPwm`.
    path : str or os.PathLike
        The PNG file to write.
    title : str
        The figure's title.

    Returns
    -------
    Path
        The path written.
    """
    fig = new_figure(7.0, 6.0)
    top, mid, low = fig.subplots(3, 1, sharex=True)
    t_ms = run.t_s * 1e3
    top.plot(t_ms, run.vf_v, color="C0", lw=1.0)
    top.set_ylabel("Vf (V)")
    mid.plot(t_ms, run.i_a * 1e3, color="C1", lw=1.0)
    mid.set_ylabel("I (mA)")
    low.plot(t_ms, run.tj_c, color="C3", lw=1.0, label="junction")
    st = run.state
    low.axhline(run.ambient_c + st.reading_k, color="k", lw=0.8, ls="--",
                label=f"bench reading: {run.ambient_c + st.reading_k:.3f} °C")
    low.set_ylabel("Tj (°C)")
    low.set_xlabel("time from the periodic steady state (ms)")
    low.legend(loc="lower left", fontsize="small")
    for ax in (top, mid, low):
        ax.grid(True, alpha=0.3)
    top.set_title(title or f"{st.freq_hz:g} Hz, duty {st.duty:g}, {st.power_w:g} W, heating "
                  f"current {run.i_heat_a * 1e3:.4g} mA ({run.dialect})", loc="left",
                  fontsize="medium")
    return save_figure(fig, path)


def fig_diode_fit(fit: DiodeFit, forward: ForwardTable, path: str | os.PathLike,
                  title: str = "") -> Path:
    """The forward points against current at each temperature with the fitted law, and their
    residuals (mV).

    Parameters
    ----------
    fit : DiodeFit
        The law fitted to ``forward`` (:func:`spicethermal.fit.diode.fit_electrical`).
    forward : ForwardTable
        The bundle's forward points.
    path : str or os.PathLike
        The PNG file to write.
    title : str
        The figure's title.

    Returns
    -------
    Path
        The path written.
    """
    fig = new_figure(7.0, 5.2)
    ax, res = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    temps = np.unique(np.round(forward.temp_c, 1))
    i_all = forward.i_a
    grid = np.geomspace(i_all.min() / 1.5, i_all.max() * 1.5, 100)
    for k, t in enumerate(temps):
        sel = np.abs(forward.temp_c - t) < 0.05
        color = f"C{k % 10}"
        tj = float(np.median(fit.junction_c[sel & (forward.t_pulse_s == 0)])) \
            if forward.t_pulse_s is not None and np.any(sel & (forward.t_pulse_s == 0)) \
            else float(t)
        ax.plot(grid, fit.law.voltage(grid, tj), color=color, lw=1.0)
        ax.plot(i_all[sel], forward.vf_v[sel], "o", color=color, ms=4, label=f"{t:g} °C")
        res.plot(i_all[sel], fit.residual_v[sel] * 1e3, "o", color=color, ms=4)
    ax.set_xscale("log")
    ax.set_ylabel("Vf (V)")
    ax.legend(loc="upper left", fontsize="small", title="fixture")
    ax.grid(True, which="both", alpha=0.3)
    res.axhline(0, color="k", lw=0.8)
    res.set_xlabel("current (A)")
    res.set_ylabel("residual (mV)")
    res.grid(True, which="both", alpha=0.3)
    ax.set_title(title or f"diode law: N = {fit.law.n:.3f}, RS = {fit.law.rs_ohm:.3g} Ω; "
                 f"residual {fit.rms_v['forward'] * 1e3:.2g} mV rms", loc="left",
                 fontsize="medium")
    return save_figure(fig, path)
