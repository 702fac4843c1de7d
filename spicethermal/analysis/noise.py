"""Noise of every data set, estimated so that no structure under test can inflate it.

* a **cooling curve**: the scatter of the model's residuals about their own local quadratic in
  ``log t`` (7 readings at a time, each residual divided by ``√(1 − h)`` with ``h`` its
  leverage; robust: the largest tenth left out, :func:`trimmed_scale`): a smooth misfit, which
  is what a missing effect leaves, is absorbed by the local quadratic; a kink or a transient
  over a few readings is left out;
* the **steady readings**: the sensor's noise, the median of the curves';
* the **PWM grid**: the scatter of the residuals about a quadratic in ``log f`` for each duty
  (four frequencies or more per duty), at most the sensor's; else the sensor's;
* the **calibration**: the scatter of its readings about the polynomial in T of the lowest
  degree that a higher degree does not improve (F-test, :data:`~.rules.POLY_P`): a TSP's bow
  is the structure under test and never counts as noise;

each at least :data:`~.rules.NOISE_FLOOR_K` and the readings' resolution over √12 (a reading
quantised in steps of ``q`` scatters by at least ``q/√12``).

>>> rng = np.random.default_rng(1)
>>> t = np.geomspace(1e-4, 100, 400)
>>> r = 0.05 * rng.standard_normal(400) + 0.3 * np.log10(t) ** 2  # a smooth misfit
>>> round(curve_noise(t, r, r), 2)
0.05
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import cache
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import fdtrc, ndtri

from ..effects.base import CALIBRATION, PWM, STEADY
from ..fit.measurement import BundleData
from .rules import LOCAL_WINDOW, NOISE_FLOOR_K, NOISE_KEPT, POLY_MAX_DEGREE, POLY_P

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["calibration_degree", "curve_noise", "noise_estimates", "resolution", "trimmed_scale"]

#: Residuals used at most per curve (evenly thinned): the estimate needs no more.
MAX_POINTS = 2000


def resolution(readings: NDArray) -> float:
    """The step ``q`` of quantised readings (0 when they are not quantised): every gap
    between distinct values is a whole number of steps, and the readings span at least 20
    steps (a few evenly spaced values, such as calibration temperatures, are no quantisation).

    Parameters
    ----------
    readings : ndarray

    Returns
    -------
    float

    >>> resolution(np.round(np.linspace(1.0, 9.0, 50) / 0.25) * 0.25)
    0.25
    >>> resolution(np.arange(20.0, 80.0, 5.0))  # evenly spaced, not quantised
    0.0
    """
    u = np.unique(np.asarray(readings, dtype=float))
    if u.size < 8:
        return 0.0
    d = np.diff(u)
    q = float(np.min(d))
    if q <= 0:
        return 0.0
    ratio = d / q
    if np.all(np.abs(ratio - np.round(ratio)) < 0.02 * ratio) and np.median(ratio) < 20 \
            and (u[-1] - u[0]) >= 20 * q:
        return q
    return 0.0


def _floor(readings: NDArray) -> float:
    return max(NOISE_FLOOR_K, resolution(readings) / math.sqrt(12.0))


def _local_quadratic_residuals(x: NDArray, r: NDArray, window: int) -> NDArray:
    """Each residual minus the quadratic fitted to its window, over ``√(1 − h)``."""
    n = x.size
    out = np.empty(n)
    for i in range(n):
        a = max(0, min(i - window // 2, n - window))
        xs = x[a:a + window] - x[i]
        v = np.vander(xs, 3)
        coef, *_ = np.linalg.lstsq(v, r[a:a + window], rcond=None)
        h = float(v[i - a] @ np.linalg.pinv(v.T @ v) @ v[i - a])
        out[i] = (r[i] - float(v[i - a] @ coef)) / math.sqrt(max(1.0 - h, 1e-3))
    return out


def curve_noise(t_s: NDArray, residual_k: NDArray, readings: NDArray) -> float:
    """Noise (K) of one cooling curve from its model residuals (module docstring).

    Parameters
    ----------
    t_s, residual_k, readings : ndarray
        Times, residuals and the readings themselves (for their resolution).

    Returns
    -------
    float
    """
    t = np.asarray(t_s, dtype=float)
    r = np.asarray(residual_k, dtype=float)
    if t.size > MAX_POINTS:
        keep = np.linspace(0, t.size - 1, MAX_POINTS).astype(int)
        t, r = t[keep], r[keep]
    floor = _floor(readings)
    if t.size < LOCAL_WINDOW:
        return max(float(np.std(r)) if r.size > 1 else floor, floor)
    e = _local_quadratic_residuals(np.log(t), r, LOCAL_WINDOW)
    return max(trimmed_scale(e), floor)


def trimmed_scale(e: NDArray) -> float:
    """Standard deviation of white Gaussian noise from the values ``e``, robust to a few
    outliers: the root mean square of the smallest :data:`~.rules.NOISE_KEPT` of them in
    size, corrected for the trimming (``σ² = mean(kept²) / c`` with
    ``c = 1 − 2 q φ(q) / p`` for the kept fraction ``p``, ``q = Φ⁻¹((1 + p) / 2)``). Far more
    efficient than the median absolute deviation (about 80 % against 37 %), which matters on
    a few tens of readings.

    Parameters
    ----------
    e : ndarray

    Returns
    -------
    float

    >>> round(trimmed_scale(np.random.default_rng(0).normal(0, 2.0, 20000)), 1)
    2.0
    """
    a = np.sort(np.abs(np.asarray(e, dtype=float)))
    keep = max(2, int(round(NOISE_KEPT * a.size)))
    frac = keep / a.size
    c = 1.0
    if frac < 1:
        q = float(ndtri(0.5 * (1 + frac)))  # the normal quantile and density there
        c = 1 - 2 * q * (math.exp(-q**2 / 2.0) / math.sqrt(2 * math.pi)) / frac
    return math.sqrt(float(np.mean(a[:keep] ** 2)) / c)


def calibration_degree(temp_c: NDArray, read_c: NDArray) -> tuple[int, float, float]:
    """The degree of the calibration's law in T that the points support, the scatter (K)
    about it, and the bow: how much that degree lowers the criterion against a line, on the
    points alone (χ² in that scatter, at least :data:`~.rules.NOISE_FLOOR_K`, less ``ln n``
    a coefficient; 0 for a line). The degree is the lowest that no higher one improves at
    significance :data:`~.rules.POLY_P` (F-test), at most :data:`~.rules.POLY_MAX_DEGREE`,
    which keeps a bow out of the scatter; an effect named on the bow needs the bow itself to
    pass the criterion's margin, stronger evidence (docs/diagnosis.md §7).

    Parameters
    ----------
    temp_c, read_c : ndarray

    Returns
    -------
    tuple of int, float and float

    >>> t = np.linspace(20, 100, 9)
    >>> calibration_degree(t, t + 1e-3 * (t - 60) ** 2)[0]
    2
    """
    t = np.asarray(temp_c, dtype=float)
    y = np.asarray(read_c, dtype=float)
    x = (t - t.mean()) / max(float(np.ptp(t)), 1e-9)
    n, top = t.size, min(POLY_MAX_DEGREE, t.size - 2)  # a degree tested leaves a dof at least
    exact = n * (1e-12 * float(np.max(np.abs(y), initial=1.0))) ** 2  # the readings' rounding

    @cache
    def rss(d: int) -> float:  # a residual within the rounding is none
        return max(float(np.sum((y - np.polyval(np.polyfit(x, y, d), x)) ** 2)), exact)

    def improves(d: int, up: int) -> bool:  # does degree ``up`` lower degree ``d``'s residual?
        f = (rss(d) - rss(up)) / (up - d) / (rss(up) / (n - up - 1))
        return rss(d) > exact and bool(fdtrc(up - d, n - up - 1, f) < POLY_P)

    degree = 1  # the lowest that no higher degree improves: an odd law has no even term
    while degree < top and any(improves(degree, up) for up in range(degree + 1, top + 1)):
        degree += 1
    dof = n - degree - 1
    scatter = math.sqrt(rss(degree) / dof) if dof > 0 else 0.0
    bow = (rss(1) - rss(degree)) / max(scatter, NOISE_FLOOR_K) ** 2 - (degree - 1) * math.log(n)
    return degree, scatter, bow if degree > 1 else 0.0


def _pwm_noise(data: BundleData, residual: NDArray, sensor: float) -> float:
    p = data.pwm
    parts, dof = [], 0
    for d in np.unique(p.duty):
        on = p.duty == d
        if np.unique(p.freq_hz[on]).size < 4:
            continue
        x = np.log(p.freq_hz[on])
        r = residual[on]
        parts.append(float(np.sum((r - np.polyval(np.polyfit(x, r, 2), x)) ** 2)))
        dof += int(on.sum()) - 3
    floor = _floor(p.tj_c)
    if dof < 3:
        return max(sensor, floor)
    return max(min(math.sqrt(sum(parts) / dof), sensor), floor)


def noise_estimates(data: BundleData, predictions: Mapping[str, NDArray]) -> dict[str, float]:
    """Noise (K) of every data set of ``data`` given a model's ``predictions``.

    Parameters
    ----------
    data : BundleData
    predictions : mapping of data set name to the model's predictions

    Returns
    -------
    dict of str to float
    """
    out = {c.name: curve_noise(c.t_s, c.tj_c - predictions[c.name], c.tj_c) for c in data.cooling}
    curves = [out[c.name] for c in data.cooling]
    sensor = float(np.median(curves)) if curves else NOISE_FLOOR_K
    if data.steady_curves:
        out[STEADY] = max(sensor, NOISE_FLOOR_K)
    if data.pwm is not None:
        out[PWM] = _pwm_noise(data, data.pwm.tj_c - predictions[PWM],
                              sensor if curves else math.inf)
        if not math.isfinite(out[PWM]):
            out[PWM] = max(float(np.std(data.pwm.tj_c - predictions[PWM])), NOISE_FLOOR_K)
    if data.calibration is not None:
        cal = data.calibration
        out[CALIBRATION] = max(calibration_degree(cal.temp_c, cal.read_c)[1],
                               _floor(cal.read_c))
    return out
