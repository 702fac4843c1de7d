"""The deconvolution behind the time-constant spectrum (:mod:`spicethermal.identify.spectrum`): the
NID kernel, Kennett's Bayesian (Richardson–Lucy) iteration, NNLS with Tikhonov regularisation
chosen by the discrepancy principle or the L-curve, and the resolution (FWHM) of each.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

#: Number of λ values of the sweep of ``"nnls"``.
LCURVE_POINTS = 24


def kernel(x: ArrayLike) -> NDArray:
    """The NID kernel ``w(x) = exp(x − eˣ)``: ``da/dz`` of one time constant, ``x = z − ζ``.

    >>> round(float(kernel(0.0)), 6)          # peak at t = τ: 1/e
    0.367879
    """
    x = np.asarray(x, dtype=float)
    return np.exp(x - np.exp(np.minimum(x, 700.0)))


def kernel_matrix(z: NDArray, zeta: NDArray) -> NDArray:
    """The kernel on a grid: ``W[i, j] = w(z_i − ζ_j) Δζ``, so that ``da/dz ≈ W R``."""
    dzeta = float(zeta[1] - zeta[0])
    return kernel(z[:, None] - zeta[None, :]) * dzeta


def bayes(w: NDArray, d: NDArray, iterations: int, background: float = 0.0) -> NDArray:
    """Kennett's Bayesian (Richardson–Lucy) iteration for ``d = W R``, ``R >= 0``.

    A constant ``background`` is added to data and model (RL with a known background), so
    that noisy samples of ``d`` near zero are used as they are instead of being clipped at
    zero, which would bias the spectrum upwards where it is small."""
    d = np.clip(d + background, 0.0, None)
    colsum = w.sum(axis=0)
    colsum[colsum <= 0] = np.inf
    wt = (w / colsum).T.copy()
    tiny = 1e-300
    r = np.full(w.shape[1], max(float(d.mean()), tiny))    # flat start (columns sum to ~1)
    for _ in range(int(iterations)):
        model = w @ r + background
        ratio = np.divide(d, model, out=np.zeros_like(d), where=model > tiny)
        r = r * (wt @ ratio)
    return r


def noise_sigma(d: NDArray) -> float:
    """Robust noise estimate of a smooth sampled curve: the MAD of its second differences
    (white noise of σ gives second differences of σ√6)."""
    if d.size < 5:
        return 0.0
    return float(1.4826 * np.median(np.abs(np.diff(d, 2))) / math.sqrt(6.0))


@functools.lru_cache(maxsize=32)
def bayes_resolution(points_per_decade: int, iterations: int) -> float:
    """FWHM (decades) of the Bayesian iteration's point-spread function: the spectrum it
    returns for one time constant (noise-free) in the middle of an 8-decade grid."""
    z = np.arange(-4 * points_per_decade, 4 * points_per_decade + 1) * (
        math.log(10) / points_per_decade)
    w = kernel_matrix(z, z)
    return fwhm_decades(z, bayes(w, kernel(z), iterations))


def fwhm_decades(x_ln: NDArray, y: NDArray) -> float:
    """Full width at half maximum of a single peak, in decades (x in ln units)."""
    i = int(np.argmax(y))
    half = 0.5 * y[i]
    lo = i
    while lo > 0 and y[lo] > half:
        lo -= 1
    hi = i
    while hi < y.size - 1 and y[hi] > half:
        hi += 1

    def cross(a: int, b: int) -> float:
        ya, yb = y[a], y[b]
        if ya == yb:
            return float(x_ln[a])
        return float(x_ln[a] + (half - ya) * (x_ln[b] - x_ln[a]) / (yb - ya))

    left = cross(lo, lo + 1) if y[lo] <= half else float(x_ln[0])
    right = cross(hi - 1, hi) if y[hi] <= half else float(x_ln[-1])
    return (right - left) / math.log(10)


def second_difference(n: int) -> NDArray:
    """The ``(n − 2) × n`` second-difference matrix (the Tikhonov seminorm ``‖D₂ R‖``)."""
    d2 = np.zeros((n - 2, n))
    idx = np.arange(n - 2)
    d2[idx, idx] = 1.0
    d2[idx, idx + 1] = -2.0
    d2[idx, idx + 2] = 1.0
    return d2


def nnls_tikhonov(w: NDArray, d: NDArray, rule: str = "discrepancy"
                   ) -> tuple[NDArray, float, dict[str, Any]]:
    """NNLS with second-difference Tikhonov regularisation over a sweep of λ; λ by the
    discrepancy principle (default) or at the L-curve corner."""
    from scipy.optimize import nnls

    n = w.shape[1]
    lmat = second_difference(n)
    scale = float(np.linalg.norm(w, 2))
    lambdas = scale * np.logspace(-4, 0, LCURVE_POINTS)
    sols, res, reg = [], [], []
    for lam in lambdas:
        a = np.vstack([w, lam * lmat])
        b = np.concatenate([d, np.zeros(n - 2)])
        x, _ = nnls(a, b, maxiter=50 * n)
        sols.append(x)
        res.append(max(float(np.linalg.norm(w @ x - d)), 1e-300))
        reg.append(max(float(np.linalg.norm(lmat @ x)), 1e-300))
    if rule == "discrepancy":
        # Morozov: the largest λ whose residual stays within one standard deviation of χ²
        # (‖r‖² ≤ ‖r₀‖² (1 + √(2/m)), m data) of the least-regularised fit's ‖r₀‖² = m σ̂²
        limit = res[0] * math.sqrt(1.0 + math.sqrt(2.0 / d.size))
        k = int(np.flatnonzero(np.asarray(res) <= limit)[-1])
    else:
        lr, lx, ll = np.log(res), np.log(reg), np.log(lambdas)
        d1r, d1x = np.gradient(lr, ll), np.gradient(lx, ll)
        d2r, d2x = np.gradient(d1r, ll), np.gradient(d1x, ll)
        kappa = (d1r * d2x - d2r * d1x) / np.power(d1r**2 + d1x**2 + 1e-300, 1.5)
        k = int(np.argmax(kappa[1:-1])) + 1
    info = {"lambda": float(lambdas[k]), "lambda_rel": float(lambdas[k] / scale),
            "lambda_rule": rule,
            "l_curve": {"lambda": lambdas.tolist(), "residual": list(map(float, res)),
                        "seminorm": list(map(float, reg))}}
    return sols[k], float(lambdas[k]), info
