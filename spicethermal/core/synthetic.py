"""Synthetic measurements from known ladders, for tests and studies.

:func:`synthetic_cooling` is what a bench would record when power is cut from the steady
state of a known ladder: exact closed form, plus optional white noise and an electrical
transient at early times. :func:`mur880e_foster` is a Foster ladder whose r(t) matches the
MUR880E datasheet points of the paper's Table 1 (to 0.04 %), the device of its §5.

>>> f = mur880e_foster()
>>> round(f.rth, 6), [round(float(x), 3) for x in f.r_norm([1e-4, 1.0])]
(1.51, [0.06, 0.9])
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .errors import DataFormatError
from .ladder import Foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from .ladder import Cauer

#: Stages of :func:`mur880e_foster`: R_i (K/W) and tau_i (s), fitted to the datasheet r(t)
#: points of Table 1 (1e-5 ... 1 s), continued as sqrt(t) below 10 us and saturating by 10 s.
MUR880E_R_K_PER_W = (0.009657, 0.03906, 0.1707, 0.3813, 0.2939, 0.615383)
MUR880E_TAU_S = (8.769e-07, 2.5e-05, 0.0004348, 0.005406, 0.06919, 0.7119)


def mur880e_foster() -> Foster:
    """A 6-stage Foster ladder for the MUR880E junction-to-case impedance, Rth = 1.51 K/W.

    Its r(t) matches the datasheet column of the paper's Table 1 within 0.04 % at the six
    times 1e-5 ... 1 s (checked in tests).
    """
    return Foster.from_tau(MUR880E_R_K_PER_W, MUR880E_TAU_S)


def synthetic_cooling(foster: Foster | Cauer, power_w: float, t_s: ArrayLike,
                      noise_k: float = 0.0, seed: int = 0, transient_s: float = 0.0, *,
                      ambient_c: float = 25.0,
                      transient_k: float | None = None) -> tuple[NDArray, NDArray]:
    """Cooling curve of a ladder after ``power_w`` is cut from its steady state.

    ``tj_c(t) = ambient_c + power_w · Σ R_i e^{-t/τ_i}`` (so the junction temperature just
    before the cut is ``ambient_c + power_w · Rth``), plus, optionally:

    * white Gaussian noise of standard deviation ``noise_k`` (seeded by ``seed``);
    * an electrical transient that masks the first ``transient_s``: the reading is pulled
      low by ``transient_k · exp(-5 t / transient_s)`` (default ``transient_k`` = a quarter
      of the total rise), so it first rises (unphysical for a cooling curve) and is back
      within e⁻⁵ ≈ 0.7 % of that offset at ``t = transient_s`` (a negative ``transient_k``
      makes the reading too hot instead).

    Parameters
    ----------
    foster : the ladder (a Foster or Cauer network).
    power_w : heating power before the cut, W.
    t_s : sample times after the cut, s.

    Returns
    -------
    (t_s, tj_c) : float arrays.

    Examples
    --------
    >>> t, tj = synthetic_cooling(Foster.from_tau([1.0], [1e-3]), 2.0, [0.0, 1e-3])
    >>> [round(float(x), 6) for x in tj]
    [27.0, 25.735759]
    """
    t = np.asarray(t_s, dtype=float).ravel()
    if not (np.isfinite(power_w) and power_w > 0):
        raise DataFormatError(f"power_w = {power_w!r}: must be > 0")
    if np.any(~np.isfinite(t)) or np.any(t < 0):
        raise DataFormatError("t_s: times must be finite and >= 0")
    if noise_k < 0 or transient_s < 0:
        raise DataFormatError("noise_k and transient_s must be >= 0")
    tj = ambient_c + power_w * foster.cooling(t)
    if transient_s > 0:
        amp = 0.25 * power_w * foster.rth if transient_k is None else float(transient_k)
        tj = tj - amp * np.exp(-5.0 * t / transient_s)
    if noise_k > 0:
        tj = tj + np.random.default_rng(seed).normal(0.0, noise_k, t.size)
    return t, tj
