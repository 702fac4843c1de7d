"""Closed forms of the ``temperature-coefficient`` form ``junction`` (every resistance on the
junction temperature, ``R = R0 (1 + α (Tj − T0))``), exact:

* steady state: ``θ = P Rth0 s`` and ``s = 1 + α (Tref + θ − T0)`` give
  ``s = (1 + α (Tref − T0)) / (1 − α P Rth0)`` (:func:`tc_steady_scale`);
* cooling curve: every resistance scales with the same ``s(Tj)``, so with the power off the
  network is linear in the warped time ``u`` with ``dt/du = s``; ``θ(u) = e^{−Au} θ(0)`` and
  ``t(u) = (1 + α(Tref − T0)) u + α Σ vᵢ τᵢ (1 − e^{−u/τᵢ})``, inverted by Newton's method
  (:func:`tc_cooling_rise`; the nonlinear solution itself, not a linearisation);
* PWM: the ladder frozen at the self-consistent mean junction temperature
  (:func:`tc_frozen_ladder`; the resistance ripple is α times the temperature ripple).

The other forms are in :mod:`spicethermal.fit.tcforward`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import SimulationError
from ..core.ladder import Cauer, Foster
from ..effects.temperature_coefficient import FLOOR

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


def as_foster(ladder: Foster | Cauer) -> Foster:
    """``ladder`` as a Foster network (converted exactly when it is a Cauer one).

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder.

    Returns
    -------
    Foster
        Its Foster form.
    """
    return ladder if isinstance(ladder, Foster) else ladder.to_foster()


def tc_steady_scale(rth0: float, alpha: float, t0_c: float, tref_c: float,
                    power_w: float) -> float:
    """Self-consistent resistance factor ``s`` of a ladder (Rth0 at T0) under constant power.

    Parameters
    ----------
    rth0 : float
        Rth at ``t0_c`` (K/W).
    alpha : float
        Temperature coefficient (1/K).
    t0_c, tref_c : float
        Temperature of R0 and reference temperature (°C).
    power_w : float
        Constant power (W).

    Returns
    -------
    float
        ``s = (1 + α (Tref − T0)) / (1 − α P Rth0)``.

    >>> round(tc_steady_scale(100.0, -2e-3, 25.0, 25.0, 0.5), 6)
    0.909091
    """
    s = (1 + alpha * (tref_c - t0_c)) / (1 - alpha * power_w * rth0)
    if not (math.isfinite(s) and s > FLOOR):
        raise SimulationError(f"temperature coefficient {alpha:g}/K at {power_w:g} W has no "
                              f"steady state (thermal runaway or R below 5 % of R0)")
    return s


def tc_cooling_rise(ladder: Foster | Cauer, alpha: float, t0_c: float, tref_c: float,
                    power_w: float, t_s: ArrayLike) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, with ``R(T) = R0 (1 + α (Tj − T0))``.

    Exact (warped-time solution, module docstring). ``ladder`` holds R0.

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    alpha, t0_c, tref_c, power_w : float
        As in :func:`tc_steady_scale`.
    t_s : array_like
        Times after the cut (s).

    Returns
    -------
    ndarray
        Junction rise over ``tref_c`` at ``t_s``.

    >>> f = Foster.from_tau([10.0], [1.0])
    >>> r = tc_cooling_rise(f, 0.0, 25.0, 25.0, 2.0, [0.0, 1.0])
    >>> [round(float(x), 9) for x in r] == [20.0, round(20 * math.exp(-1), 9)]
    True
    """
    f = as_foster(ladder)
    r0, tau0 = np.asarray(f.r), np.asarray(f.tau)
    t = np.asarray(t_s, dtype=float)
    s_ss = tc_steady_scale(f.rth, alpha, t0_c, tref_c, power_w)
    v0 = power_w * r0 * s_ss
    a = 1 + alpha * (tref_c - t0_c)
    if alpha == 0:
        return (v0 * np.exp(-t[:, None] / tau0)).sum(axis=1)
    s_lo, s_hi = sorted((s_ss, a))
    if s_lo <= FLOOR:
        raise SimulationError("temperature coefficient makes a resistance vanish")
    u = t / (0.5 * (s_lo + s_hi))
    for _ in range(60):
        e = np.exp(-u[:, None] / tau0)
        tu = a * u + alpha * (v0 * tau0 * (1 - e)).sum(axis=1)
        su = a + alpha * (v0 * e).sum(axis=1)
        step = (tu - t) / su
        u = np.clip(u - step, t / s_hi, t / s_lo)
        if np.all(np.abs(step) <= 1e-13 * (u + 1e-300)):
            break
    return (v0 * np.exp(-u[:, None] / tau0)).sum(axis=1)


def tc_frozen_ladder(ladder: Foster | Cauer, alpha: float, t0_c: float, tref_c: float,
                     mean_power_w: float) -> Foster:
    """The ladder at the self-consistent mean junction temperature under ``mean_power_w``
    (every R and τ times ``s``; C unchanged).

    Parameters
    ----------
    ladder : Foster or Cauer
        The ladder at ``t0_c``.
    alpha, t0_c, tref_c : float
        As in :func:`tc_steady_scale`.
    mean_power_w : float
        Mean power (W).

    Returns
    -------
    Foster
        The frozen ladder.

    >>> tc_frozen_ladder(Foster.from_tau([10.0], [1.0]), 0.01, 25.0, 25.0, 5.0).rth
    20.0
    """
    f = as_foster(ladder)
    s = tc_steady_scale(f.rth, alpha, t0_c, tref_c, mean_power_w)
    return Foster.from_tau(np.asarray(f.r) * s, np.asarray(f.tau) * s)
