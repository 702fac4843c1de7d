"""The numerics of the ladder fit (see :mod:`spicethermal.fit.ladder` for the method): the settings,
the weighted data, the variable-projection least-squares :class:`Problem`, the starting
values from the relaxation spectrum and the checks that make an order acceptable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


#: Name of the order-selection criterion (see the module docstring).
CRITERION = "BIC"
#: An order is rejected when two of its time constants are closer than this factor.
MIN_TAU_RATIO = 2.0
#: An order is rejected when one of its stages carries less than this fraction of Rth.
MIN_STAGE_FRACTION = 0.002
#: An order is rejected when a stage's R, or the log-ratio of two neighbouring time constants,
#: is less than this many standard uncertainties from zero (the stage is not resolved).
MIN_SIGNIFICANCE = 2.0
#: An order is rejected when a time constant lies beyond [t_min / m, t_max · m], m this margin.
WINDOW_MARGIN = 100.0
#: Data with more points than this are averaged into log-spaced bins before fitting.
DENSE_POINTS = 400
#: Bins per decade of time used for dense data.
BINS_PER_DECADE = 40
#: Relative weighting: residuals are divided by sqrt(Zth² + f²), f this fraction of max Zth.
RELATIVE_FLOOR = 1e-4
#: Relative weighting of dense noisy data: where the noise of a bin exceeds this fraction of
#: Zth, its residual is weighted by the noise instead (absolute), so noise never dominates.
RELATIVE_PRECISION = 0.01

#: The order-selection rule in one sentence (stored with every automatic fit).
CRITERION_RULE = (
    f"lowest BIC = n ln(RSS/n) + k ln(n) (chi2 + k ln(n) with sigma given) among orders whose "
    f"time constants are >= {MIN_TAU_RATIO:g}x apart and >= {MIN_SIGNIFICANCE:g} standard "
    f"uncertainties apart in log, whose every stage carries >= {100 * MIN_STAGE_FRACTION:g} % "
    f"of Rth and >= {MIN_SIGNIFICANCE:g} standard uncertainties, and whose time constants lie "
    f"within {WINDOW_MARGIN:g}x of the data window")

SPECTRUM_PER_DECADE = 8
SEEDS_PER_ORDER = 2
PATIENCE = 1


# ------------------------------------------------------------------------ input checking
def as_data(t_s: ArrayLike, zth: ArrayLike, sigma: ArrayLike | None,
             rth: float | None) -> tuple[NDArray, NDArray, NDArray | None]:
    """The data as float arrays (copies), checked: equal lengths, at least 3 finite points,
    strictly increasing positive times, some positive Zth, positive finite ``sigma`` and
    ``rth``; a problem raises :class:`DataFormatError`."""
    try:
        t = np.array(t_s, dtype=float).ravel()  # copies: the result freezes its own arrays
        z = np.array(zth, dtype=float).ravel()
    except (TypeError, ValueError) as exc:
        raise DataFormatError(f"t_s/zth_k_per_w: not numeric ({exc})") from None
    if t.size != z.size:
        raise DataFormatError(f"t_s has {t.size} points but zth_k_per_w has {z.size}")
    if t.size < 3:
        raise DataFormatError(f"need at least 3 data points to fit a ladder, got {t.size}")
    for name, arr in (("t_s", t), ("zth_k_per_w", z)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise DataFormatError(f"{name}[{bad[0]}] = {arr[bad[0]]!r}: not a finite number")
    if t[0] <= 0:
        raise DataFormatError(f"t_s[0] = {t[0]!r}: times must be positive (Zth(0) = 0 is implied)")
    dec = np.flatnonzero(np.diff(t) <= 0)
    if dec.size:
        i = int(dec[0]) + 1
        raise DataFormatError(f"t_s[{i}] = {t[i]!r}: times must increase strictly "
                              f"(previous {t[i - 1]!r})")
    if not np.any(z > 0):
        raise DataFormatError("zth_k_per_w: no positive value, nothing to fit")
    s = None
    if sigma is not None:
        s = np.broadcast_to(np.asarray(sigma, dtype=float), t.shape).copy()
        bad = np.flatnonzero(~(np.isfinite(s) & (s > 0)))
        if bad.size:
            raise DataFormatError(f"sigma[{bad[0]}] = {s[bad[0]]!r}: must be positive and finite")
    if rth is not None and not (math.isfinite(rth) and rth > 0):
        raise DataFormatError(f"rth_k_per_w = {rth!r}: must be positive and finite")
    return t, z, s


def log_bins(t_s: NDArray, per_decade: int) -> tuple[NDArray, NDArray]:
    """Log-spaced bins of increasing times ``t_s`` (> 0), ``per_decade`` to a decade, each
    from ``10^(k/per_decade)``: the index of each bin's first sample and its sample count
    (average any column ``x`` with ``np.add.reduceat(x, start) / counts``).

    >>> start, counts = log_bins(np.array([1.0, 1.5, 2.0, 20.0]), 2)
    >>> start.tolist(), counts.tolist()
    ([0, 3], [3, 1])
    """
    idx = np.floor(np.log10(t_s) * per_decade + 1e-9).astype(np.int64)
    _, start = np.unique(idx, return_index=True)
    return start, np.diff(np.append(start, idx.size))


def bin_data(t: NDArray, z: NDArray, s: NDArray | None,
              per_decade: int) -> tuple[NDArray, NDArray, NDArray | None]:
    """Average dense data into log-spaced bins; bins holding one point keep it exactly."""
    start, counts = log_bins(t, per_decade)
    tb = np.add.reduceat(t, start) / counts
    zb = np.add.reduceat(z, start) / counts
    sb = None if s is None else np.sqrt(np.add.reduceat(s * s, start)) / counts
    return tb, zb, sb


def bin_noise(t: NDArray, z: NDArray, tf: NDArray) -> NDArray:
    """Standard error of each fitted point: 0 for sparse data (taken as exact, e.g. datasheet
    points); for dense data binned into ``tf``, the sample noise (from successive differences,
    robust) over the square root of the bin's sample count."""
    if tf.size == t.size:
        return np.zeros(tf.size)
    sigma = 1.4826 * float(np.median(np.abs(np.diff(z)))) / math.sqrt(2.0)
    return sigma / np.sqrt(log_bins(t, BINS_PER_DECADE)[1])


# ------------------------------------------------------------------------------ numerics
class Problem:
    """The weighted data and the model's residual/Jacobian for one parametrisation."""

    def __init__(self, t: NDArray, z: NDArray, w: NDArray, rth: float | None,
                 relative: bool = False) -> None:
        self.t, self.z, self.w, self.rth, self.relative = t, z, w, rth, relative
        self.wz = w * z
        self.n = t.size
        # parameter ranges that keep every exp() finite; solutions near them are rejected anyway
        lz = math.log(max(float(np.max(np.abs(z))), 1e-300))
        self.log_r_range = (lz - 60.0, lz + 25.0) if rth is None else (-60.0, 60.0)
        self.log_tau_range = (math.log(t[0]) - 25.0, math.log(t[-1]) + 25.0)

    # -- basis
    def phi(self, tau: NDArray) -> NDArray:
        return -np.expm1(-self.t[:, None] / tau[None, :])

    def project(self, tau: NDArray) -> tuple[NDArray, float]:
        """Best non-negative r for fixed τ (variable projection); returns (r, RSS)."""
        from scipy.optimize import nnls

        a = self.w[:, None] * self.phi(tau)
        b = self.wz
        if self.rth is not None:
            lam = 1e3 * max(float(np.linalg.norm(a, axis=0).max()), 1e-300)
            a = np.vstack([a, lam * np.ones(tau.size)])
            b = np.append(b, lam * self.rth)
        try:
            r, _ = nnls(a, b, maxiter=50 * tau.size + 100)
        except RuntimeError:  # pragma: no cover - NNLS iteration limit
            r = np.full(tau.size, (self.rth or float(np.max(self.z))) / tau.size)
        res = self.w * (self.phi(tau) @ r) - self.wz
        return r, float(res @ res)

    # -- log parametrisation: p = [a..., log τ...]
    def pack(self, r: NDArray, tau: NDArray) -> tuple[NDArray, int]:
        if self.rth is None:
            return np.concatenate([np.log(r), np.log(tau)]), -1
        ref = int(np.argmax(r))
        a = np.log(r) - math.log(r[ref])
        return np.concatenate([np.delete(a, ref), np.log(tau)]), ref

    def unpack(self, p: NDArray, m: int, ref: int) -> tuple[NDArray, NDArray]:
        k = m if self.rth is None else m - 1
        a = np.clip(p[:k], *self.log_r_range)
        tau = np.exp(np.clip(p[k:], *self.log_tau_range))
        if self.rth is None:
            return np.exp(a), tau
        a = np.insert(a, ref, 0.0)
        e = np.exp(a - a.max())
        return self.rth * e / e.sum(), tau

    def residual_jac(self, p: NDArray, m: int, ref: int) -> tuple[NDArray, NDArray]:
        r, tau = self.unpack(p, m, ref)
        x = self.t[:, None] / tau[None, :]
        e = np.exp(-x)
        ph = -np.expm1(-x)
        model = ph @ r
        res = self.w * model - self.wz
        d_logtau = -(r[None, :] * x * e)
        if self.rth is None:
            d_a = r[None, :] * ph
        else:
            d_a = r[None, :] * (ph - model[:, None] / self.rth)
            d_a = np.delete(d_a, ref, axis=1)
        jac = self.w[:, None] * np.hstack([d_a, d_logtau])
        return res, jac

    def refine(self, r0: NDArray, tau0: NDArray, tol: float = 1e-10,
               max_nfev_per_param: int = 30) -> Solution:
        """Levenberg-Marquardt on the log parameters from (r0, τ0)."""
        from scipy.optimize import least_squares

        m = tau0.size
        p0, ref = self.pack(r0, tau0)
        cache: dict[str, Any] = {}

        def fun(p: NDArray) -> NDArray:
            res, jac = self.residual_jac(p, m, ref)
            cache["p"], cache["jac"] = p.copy(), jac
            return res

        def jac(p: NDArray) -> NDArray:
            if "p" in cache and np.array_equal(cache["p"], p):
                return cache["jac"]
            return self.residual_jac(p, m, ref)[1]

        k = p0.size
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            sol = least_squares(fun, p0, jac=jac, method="lm", xtol=tol, ftol=tol, gtol=tol,
                                max_nfev=max_nfev_per_param * (k + 1))
        r, tau = self.unpack(sol.x, m, ref)
        ok = bool(np.all(np.isfinite(r)) and np.all(np.isfinite(tau)) and np.all(tau > 0)
                  and np.all(r > 0))
        if self.rth is not None and ok:
            r = r * (self.rth / r.sum())
        order = np.argsort(tau)
        r, tau = r[order], tau[order]
        res = self.w * (self.phi(tau) @ r) - self.wz if ok else np.full(self.n, np.inf)
        rss = float(res @ res)
        converged = ok and sol.status > 0
        msg = sol.message if ok else "parameters left the finite positive range"
        return Solution(r, tau, rss, converged, str(msg), int(sol.nfev))

    def covariance(self, r: NDArray, tau: NDArray, scale: float) -> NDArray:
        """Covariance of (r, τ): ``scale · N (Nᵀ JᵀJ N)⁻¹ Nᵀ`` with N the constraint null space."""
        m = tau.size
        x = self.t[:, None] / tau[None, :]
        jac = self.w[:, None] * np.hstack([-np.expm1(-x), -(r / tau)[None, :] * x * np.exp(-x)])
        if self.rth is None:
            null = np.eye(2 * m)
        else:
            c = np.concatenate([np.ones(m), np.zeros(m)])[None, :]
            _, _, vt = np.linalg.svd(c)
            null = vt[1:].T
        jn = jac @ null
        col = np.linalg.norm(jn, axis=0)
        if not (np.all(np.isfinite(jn)) and np.all(col > 0) and math.isfinite(scale)):
            return np.full((2 * m, 2 * m), np.inf)
        try:
            with np.errstate(all="ignore"):
                cov_n = np.linalg.pinv((jn / col).T @ (jn / col), rcond=1e-15, hermitian=True)
                cov = scale * null @ (cov_n / np.outer(col, col)) @ null.T
        except np.linalg.LinAlgError:  # pragma: no cover - degenerate Jacobian
            return np.full((2 * m, 2 * m), np.inf)
        return cov if np.all(np.isfinite(cov)) else np.full((2 * m, 2 * m), np.inf)


@dataclass(frozen=True)
class Solution:
    """One fit of one order: stages, residual sum of squares, convergence, covariance and why
    the order is not acceptable ('' when it is)."""

    r: NDArray
    tau: NDArray
    rss: float
    converged: bool
    message: str
    nfev: int
    cov: NDArray | None = None
    why: str = ""


# ------------------------------------------------------------------------------- seeds
def spectrum_clusters(prob: Problem, t_lo: float, t_hi: float) -> list[tuple[float, float]]:
    """NNLS relaxation spectrum on a log τ grid; returns clusters as (weight, log τ)."""
    grid = np.logspace(math.log10(t_lo) - 1, math.log10(t_hi) + 0.5,
                       int((math.log10(t_hi) - math.log10(t_lo) + 1.5) * SPECTRUM_PER_DECADE) + 1)
    r, _ = prob.project(grid)
    clusters: list[tuple[float, float]] = []
    i = 0
    while i < grid.size:
        if r[i] <= 0:
            i += 1
            continue
        j = i
        while j + 1 < grid.size and r[j + 1] > 0:
            j += 1
        wts = r[i:j + 1]
        clusters.append((float(wts.sum()), float(wts @ np.log(grid[i:j + 1]) / wts.sum())))
        i = j + 1
    return clusters


def reduce_clusters(clusters: list[tuple[float, float]], m: int) -> NDArray:
    """m seed time constants from the spectrum clusters (merge smallest or split largest)."""
    cl = sorted(clusters, key=lambda c: c[1])
    while len(cl) > m:
        k = min(range(len(cl)), key=lambda i: cl[i][0])
        if k == 0:
            nb = 1
        elif k == len(cl) - 1:
            nb = k - 1
        else:
            nb = k - 1 if cl[k][1] - cl[k - 1][1] < cl[k + 1][1] - cl[k][1] else k + 1
        w = cl[k][0] + cl[nb][0]
        merged = (w, (cl[k][0] * cl[k][1] + cl[nb][0] * cl[nb][1]) / w)
        lo, hi = sorted((k, nb))
        cl = cl[:lo] + [merged] + cl[hi + 1:]
    while len(cl) < m:
        k = max(range(len(cl)), key=lambda i: cl[i][0])
        w, lt = cl[k]
        cl = cl[:k] + [(w / 2, lt - 0.7), (w / 2, lt + 0.7)] + cl[k + 1:]
    return np.exp(np.array([c[1] for c in cl]))


def grown_seeds(tau: NDArray, t_lo: float, t_hi: float) -> list[NDArray]:
    """Seeds of order m + 1 from an order-m solution: a stage added in each gap, or split."""
    lt = np.log(np.sort(tau))
    new = [lt[0] - 1.5, lt[-1] + 1.5, *((lt[:-1] + lt[1:]) / 2)]
    seeds = [np.exp(np.sort(np.append(lt, x))) for x in new]
    for i in range(lt.size):
        split = np.concatenate([np.delete(lt, i), [lt[i] - 0.7, lt[i] + 0.7]])
        seeds.append(np.exp(np.sort(split)))
    lo, hi = math.log(t_lo / 10), math.log(t_hi * 10)
    return [np.exp(np.clip(np.log(s), lo, hi)) for s in seeds]


# ----------------------------------------------------------------------------- checks
def guard(r: NDArray, tau: NDArray, cov: NDArray, t_lo: float, t_hi: float,
           relative: bool = False) -> str:
    """Why an order is not acceptable, or '' if it is (``relative``: a stage's share is of
    Zth at its own time constant, as the log-domain fit sees it)."""
    m = tau.size
    rth = float(r.sum())
    var = np.diag(cov)
    if m > 1:
        ratios = tau[1:] / tau[:-1]
        i = int(np.argmin(ratios))
        if ratios[i] < MIN_TAU_RATIO:
            return (f"time constants of stages {i + 1} and {i + 2} within a factor "
                    f"{ratios[i]:.2f} (< {MIN_TAU_RATIO:g}): one time constant split in two")
    scale = (Foster.from_tau(r, tau).zth(np.asarray(tau)) if relative
             else np.full(m, rth))
    share = r / scale
    i = int(np.argmin(share))
    if share[i] < MIN_STAGE_FRACTION:
        of = "Zth at its time constant" if relative else "Rth"
        return (f"stage {i + 1} carries {100 * share[i]:.3g} % of {of} "
                f"(< {100 * MIN_STAGE_FRACTION:g} %): fits noise")
    if tau[0] < t_lo / WINDOW_MARGIN or tau[-1] > t_hi * WINDOW_MARGIN:
        bad = 1 if tau[0] < t_lo / WINDOW_MARGIN else m
        return (f"time constant of stage {bad} ({tau[bad - 1]:.3g} s) lies far outside the data "
                f"window [{t_lo:.3g}, {t_hi:.3g}] s: not identifiable")
    with np.errstate(divide="ignore", invalid="ignore"):
        z_r = r / np.sqrt(var[:m])
        if m > 1:
            ct = cov[m:, m:] / np.outer(tau, tau)  # covariance of ln τ
            d = np.diag(ct)
            var_gap = d[1:] + d[:-1] - 2 * np.diag(ct, 1)
            z_gap = np.log(tau[1:] / tau[:-1]) / np.sqrt(np.clip(var_gap, 0, None))
        else:
            z_gap = np.array([np.inf])
    i = int(np.nanargmin(z_r)) if np.all(np.isfinite(var)) else 0
    if not np.all(np.isfinite(var)) or z_r[i] < MIN_SIGNIFICANCE:
        return (f"stage {i + 1}'s resistance is not significant ({z_r[i]:.2g} standard "
                f"uncertainties, < {MIN_SIGNIFICANCE:g})")
    j = int(np.argmin(z_gap))
    if z_gap[j] < MIN_SIGNIFICANCE:
        return (f"time constants of stages {j + 1} and {j + 2} are not significantly different "
                f"({z_gap[j]:.2g} standard uncertainties, < {MIN_SIGNIFICANCE:g})")
    return ""
