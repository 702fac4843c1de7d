"""Time-constant spectrum of a thermal impedance curve: network identification by deconvolution.

NID (Székely, JESD51-14 practice; what Simcenter T3Ster Master and PyRth do) describes the heat
path by a continuous distribution of time constants. With ``z = ln t`` and ``ζ = ln τ``,

    Zth(t) = ∫ R(ζ) (1 − exp(−t/e^ζ)) dζ,     da/dz = ∫ R(ζ) w(z − ζ) dζ,
    w(x) = exp(x − e^x),   ∫ w = 1,

so the derivative of the curve in log time, ``a'(z) = dZth/d(ln t)``, is the spectrum ``R(ζ)``
(K/W per unit ln τ) blurred by the fixed kernel ``w``; deconvolving it gives the spectrum.

Steps of :func:`time_constant_spectrum`:

1. **Log-time resampling.** The curve is put on a uniform ``z`` grid (``points_per_decade``)
   by :meth:`~spicethermal.identify.curves.ZthCurve.resample_log` (local linear fits in log-time
   bins for dense data). Before the first sample the curve is extended by the √t law of 1-D
   diffusion (as the early-time correction of the cooling curve already assumed) for
   ``pre_decades``; after the last sample it is held at its final value (steady state) for
   ``post_decades``, which tells the deconvolution that no longer time constants exist.
2. **Derivative** ``da/dz`` by a Savitzky–Golay filter (local quadratic over
   :data:`SG_WINDOW` grid points, ±0.115 in ln t at 40 points per decade).
3. **Deconvolution** on the same grid (``ζ_j = z_j``), by one of

   * ``"bayes"`` (default) — the Bayesian iteration of Kennett, Prestwich and Robinson
     (1978), used by Székely for NID and by PyRth: the multiplicative, non-negative
     Richardson–Lucy update ``R ← R · Wᵀ(a′ / W R) / Wᵀ1``. Its regularisation is the number
     of iterations; default :data:`BAYES_ITERATIONS`. A constant background of
     :data:`BACKGROUND_SIGMAS` noise standard deviations of ``a′`` (robust estimate from its
     second differences) is added to data and model, so that noisy samples near zero are
     used as they are rather than clipped at zero (clipping biases the spectrum upwards).
   * ``"nnls"`` — non-negative least squares with Tikhonov regularisation of the second
     difference, ``min ‖W R − a′‖² + λ² ‖D₂ R‖²`` with ``R ≥ 0``, over a logarithmic sweep
     of ``λ``. Default choice of λ: Morozov's discrepancy principle with the noise taken from
     the least-regularised fit — the largest λ whose ``‖W R − a′‖²`` exceeds that fit's by at
     most one standard deviation of χ² (a factor ``1 + √(2/m)``, m data). Or
     ``lambda_rule="lcurve"``: the corner (largest curvature) of the L-curve
     ``(log ‖W R − a′‖, log ‖D₂ R‖)``, which on noisy data tends to over-smooth.

**Resolution** (stored in :attr:`Spectrum.resolution_decades`): the full width at half
maximum, in decades of τ, of the spectrum the same method with the same settings returns for
a single time constant in the middle of the grid (its point-spread function; noise-free
data for ``"bayes"``, the model-resolution matrix for ``"nnls"``). Two time constants closer
than about this cannot be told apart.

The resistance the grid cannot hold (Zth at the grid's first point, a few mK/W) is added to
the first cell, so ΣR is not below the curve's final value.

A :class:`Spectrum` lumps into a Foster ladder of any order (:meth:`Spectrum.to_foster`),
which goes to Cauer and to a ``.lib`` through the existing code
(:mod:`spicethermal.core.ladder`, :mod:`spicethermal.identify.structure`).

>>> from spicethermal.core.ladder import Foster
>>> true = Foster.from_tau([1.0, 2.0], [1e-3, 1e-1])
>>> t = np.geomspace(1e-5, 10, 241)
>>> s = time_constant_spectrum(t, true.zth(t))
>>> round(s.rth_k_per_w, 3)
3.0
>>> [float(f"{x:.2g}") for x in s.peaks_s()]      # the two time constants
[0.001, 0.1]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..core.errors import DataFormatError
from ..core.ladder import Foster
from .curves import ZthCurve
from .deconvolution import (
    bayes,
    bayes_resolution,
    fwhm_decades,
    kernel,
    kernel_matrix,
    nnls_tikhonov,
    noise_sigma,
    second_difference,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


__all__ = ["BAYES_ITERATIONS", "POINTS_PER_DECADE", "Spectrum", "kernel",
           "log_derivative", "time_constant_spectrum"]

#: Default grid density of the spectrum (points per decade of t and τ).
POINTS_PER_DECADE = 40
#: Default number of Bayesian iterations (PyRth uses 1000 at about 15 points per decade).
#: Chosen on the 4-layer recovery study (bench/bench_spectrum.py): at 0.1 % noise, 2000
#: iterations (resolution 0.11 decade) keep every seed's structure function within 1 % of
#: Rth, while 4000 (0.09 decade) start to split single time constants into noise doublets.
BAYES_ITERATIONS = 2000
#: Background of the Bayesian iteration, in noise standard deviations of da/dz.
BACKGROUND_SIGMAS = 3.0
#: Savitzky–Golay window of the derivative (grid points; quadratic fit).
SG_WINDOW = 5
#: Default extension before the first sample (√t law) and after the last (steady state).
PRE_DECADES = 1.0
POST_DECADES = 1.0

Method = Literal["bayes", "nnls"]


@dataclass(frozen=True, eq=False)
class Spectrum:
    """A time-constant spectrum ``R(ζ)``, density in K/W per unit ``ln τ``, on a log grid.

    Immutable. Build it with :func:`time_constant_spectrum`.

    Attributes
    ----------
    tau_s : grid of time constants (s), uniform in ``ln τ``.
    r_density_k_per_w : ``R(ζ)`` at the grid, K/W per unit ln τ (multiply by ln 10 for
        K/W per decade); ``Σ R Δζ`` is the total Rth.
    method : ``"bayes"`` or ``"nnls"``.
    resolution_decades : FWHM of the method's point-spread function, decades of τ.
    t_resolved_s : the time window the data resolve (first reliable sample, last sample);
        time constants outside it come from the √t extension and the steady-state hold.
    params : the settings used (iterations or λ, grid, extension).
    label : name of the source curve.
    data_zth_k_per_w, data_derivative_k_per_w : the resampled (and extended) curve and its
        derivative ``dZth/d(ln t)`` at ``t = tau_s`` (the grids coincide), if known.
    """

    tau_s: NDArray
    r_density_k_per_w: NDArray
    method: str
    resolution_decades: float
    t_resolved_s: tuple[float, float]
    params: dict[str, Any] = field(default_factory=dict)
    label: str = ""
    data_zth_k_per_w: NDArray | None = field(default=None, repr=False)
    data_derivative_k_per_w: NDArray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        tau = np.array(self.tau_s, dtype=float).ravel()
        dens = np.array(self.r_density_k_per_w, dtype=float).ravel()
        if tau.size < 3 or dens.size != tau.size:
            raise DataFormatError("Spectrum: tau_s and r_density_k_per_w need the same size >= 3")
        if np.any(~np.isfinite(tau)) or np.any(tau <= 0) or np.any(np.diff(tau) <= 0):
            raise DataFormatError("Spectrum: tau_s must be positive and increasing")
        step = np.diff(np.log(tau))
        if np.ptp(step) > 1e-6 * step[0]:
            raise DataFormatError("Spectrum: tau_s must be uniform in ln tau")
        if np.any(~np.isfinite(dens)) or np.any(dens < 0):
            raise DataFormatError("Spectrum: r_density_k_per_w must be finite and >= 0")
        for name, arr in (("tau_s", tau), ("r_density_k_per_w", dens)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        for name in ("data_zth_k_per_w", "data_derivative_k_per_w"):
            value = getattr(self, name)
            if value is not None:
                arr = np.array(value, dtype=float).ravel()
                if arr.size != tau.size:
                    raise DataFormatError(f"Spectrum: {name} must match tau_s in size")
                arr.setflags(write=False)
                object.__setattr__(self, name, arr)
        object.__setattr__(self, "t_resolved_s", tuple(float(x) for x in self.t_resolved_s))
        object.__setattr__(self, "params", dict(self.params))

    # -- views --------------------------------------------------------------------------
    @property
    def d_zeta(self) -> float:
        """Grid step in ln τ."""
        return float(math.log(self.tau_s[1] / self.tau_s[0]))

    @property
    def r_k_per_w(self) -> NDArray:
        """Resistance of each grid cell, ``R(ζ_j) Δζ`` (K/W)."""
        return self.r_density_k_per_w * self.d_zeta

    @property
    def rth_k_per_w(self) -> float:
        """Total thermal resistance of the spectrum, ``∫ R dζ`` (K/W)."""
        return float(np.sum(self.r_k_per_w))

    def zth(self, t_s: ArrayLike) -> NDArray:
        """Zth(t) (K/W) of the spectrum (its forward model), at any times > 0."""
        t = np.asarray(t_s, dtype=float)
        return (self.r_k_per_w * -np.expm1(-t[..., None] / self.tau_s)).sum(axis=-1)

    def derivative(self, t_s: ArrayLike) -> NDArray:
        """``dZth/d(ln t)`` (K/W) of the spectrum at ``t_s``."""
        z = np.log(np.asarray(t_s, dtype=float))
        return (self.r_k_per_w * kernel(z[..., None] - np.log(self.tau_s))).sum(axis=-1)

    def peaks_s(self, min_fraction: float = 0.02) -> NDArray:
        """Time constants (s) at the local maxima of the spectrum that carry at least
        ``min_fraction`` of Rth within ±half the resolution (a lumped-stage estimate)."""
        d = self.r_density_k_per_w
        inner = np.flatnonzero((d[1:-1] > d[:-2]) & (d[1:-1] >= d[2:])) + 1
        half = max(1, int(round(0.5 * self.resolution_decades * math.log(10) / self.d_zeta)))
        out = []
        for i in inner:
            lo, hi = max(0, i - half), min(d.size, i + half + 1)
            if d[lo:hi].sum() * self.d_zeta >= min_fraction * self.rth_k_per_w:
                w = d[lo:hi]
                out.append(math.exp(np.sum(w * np.log(self.tau_s[lo:hi])) / np.sum(w)))
        return np.asarray(out)

    def to_foster(self, n_per_decade: float = 10.0, *, order: int | None = None,
                  min_fraction: float = 1e-6) -> Foster:
        """Lump the spectrum into a Foster ladder.

        The τ axis is cut into cells of ``1/n_per_decade`` decade (aligned to whole decades);
        each cell becomes one stage with ``r = Σ R Δζ`` over the cell and ``τ`` the
        R-weighted geometric mean of the cell, so ΣR = Rth and each cell's mean ln τ are kept.
        Cells with less than ``min_fraction`` of Rth are merged into the next stage.

        With ``order``, those stages are then merged pairwise, each time the neighbouring
        pair whose merge adds the least R-weighted variance of ln τ (Ward's criterion
        ``r_i r_j / (r_i + r_j) · (ln τ_i − ln τ_j)²``), until ``order`` stages remain.

        >>> from spicethermal.core.ladder import Foster
        >>> t = np.geomspace(1e-5, 10, 241)
        >>> s = time_constant_spectrum(t, Foster.from_tau([1.0, 2.0], [1e-3, 1e-1]).zth(t))
        >>> f = s.to_foster(order=2)
        >>> [round(x, 2) for x in f.r], bool(np.allclose(f.tau, [1e-3, 1e-1], rtol=0.02))
        ([1.0, 2.0], True)
        """
        if not (isinstance(n_per_decade, int | float) and math.isfinite(n_per_decade)
                and n_per_decade > 0):
            raise DataFormatError(f"n_per_decade = {n_per_decade!r}: must be > 0")
        if order is not None and (isinstance(order, bool) or int(order) != order or order < 1):
            raise DataFormatError(f"order = {order!r}: must be a positive integer")
        r = self.r_k_per_w
        total = float(r.sum())
        if not total > 0:
            raise DataFormatError("Spectrum: empty (zero Rth): no ladder")
        zeta = np.log(self.tau_s)
        cell = np.floor(np.log10(self.tau_s) * n_per_decade + 1e-9).astype(int)
        rs: list[float] = []
        zs: list[float] = []
        carry_r, carry_m = 0.0, 0.0
        for k in np.unique(cell):
            sel = cell == k
            rk = float(r[sel].sum()) + carry_r
            mk = float(np.sum(r[sel] * zeta[sel])) + carry_m
            if rk < min_fraction * total:
                carry_r, carry_m = rk, mk
                continue
            rs.append(rk)
            zs.append(mk / rk)
            carry_r, carry_m = 0.0, 0.0
        if not rs:  # pragma: no cover - total > 0 leaves at least one cell
            raise DataFormatError("Spectrum: no cell carries resistance: no ladder")
        rs[-1] += carry_r
        if order is not None:
            while len(rs) > order:
                ra, za = np.asarray(rs), np.asarray(zs)
                cost = ra[:-1] * ra[1:] / (ra[:-1] + ra[1:]) * np.diff(za) ** 2
                i = int(np.argmin(cost))
                rm = rs[i] + rs[i + 1]
                zs[i] = (rs[i] * zs[i] + rs[i + 1] * zs[i + 1]) / rm
                rs[i] = rm
                del rs[i + 1], zs[i + 1]
        return Foster.from_tau(rs, np.exp(zs))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"format": "spicethermal-spectrum/1", "label": self.label, "method": self.method,
                "resolution_decades": self.resolution_decades,
                "t_resolved_s": list(self.t_resolved_s), "rth_k_per_w": self.rth_k_per_w,
                "params": self.params, "tau_s": self.tau_s.tolist(),
                "r_density_k_per_w": self.r_density_k_per_w.tolist()}

    def __str__(self) -> str:
        return (f"{self.label or 'spectrum'}: {self.method}, {self.tau_s.size} points "
                f"{self.tau_s[0]:.3g}..{self.tau_s[-1]:.3g} s, Rth = {self.rth_k_per_w:.4g} K/W, "
                f"resolution {self.resolution_decades:.2f} decades, data resolve "
                f"{self.t_resolved_s[0]:.3g}..{self.t_resolved_s[1]:.3g} s")


# ----------------------------------------------------------------------------- pipeline
def _as_curve(source: ZthCurve | ArrayLike, zth_k_per_w: ArrayLike | None) -> ZthCurve:
    if isinstance(source, ZthCurve):
        if zth_k_per_w is not None:
            raise DataFormatError("give a ZthCurve or (t_s, zth_k_per_w), not both")
        return source
    if zth_k_per_w is None:
        raise DataFormatError("time_constant_spectrum: zth_k_per_w is missing")
    return ZthCurve.from_points(source, zth_k_per_w, label="Zth data")


def _grid(curve: ZthCurve, points_per_decade: int, pre_decades: float, post_decades: float
          ) -> tuple[NDArray, NDArray, int, int]:
    """Uniform log grid with Zth on it: (t, a, first data index, last data index)."""
    t0, t1 = float(curve.t_s[0]), float(curve.t_s[-1])
    ppd = int(points_per_decade)
    dz = math.log(10) / ppd
    n_data = int(math.floor(math.log(t1 / t0) / dz + 1e-9)) + 1
    if n_data < SG_WINDOW + 2:
        raise DataFormatError(f"{curve.label or 'Zth curve'}: {t0:.3g}..{t1:.3g} s is too short "
                              f"for a spectrum (need about {SG_WINDOW + 2} grid points)")
    method = "bin" if len(curve) > 2 * n_data else "interp"
    data = curve.resample_log(ppd, t_min=t0, t_max=t1, method=method)
    a_data = np.asarray(data.zth_k_per_w, dtype=float)
    n_pre = int(round(pre_decades * ppd))
    n_post = int(round(post_decades * ppd))
    k = np.arange(-n_pre, n_data + n_post)
    t = t0 * np.exp(k * dz)
    a = np.empty(k.size)
    # √t law before the data (held flat if the curve starts below zero, e.g. when the √t
    # extrapolated Tj at the cut overshoots a given steady value: no spurious jump)
    a[:n_pre] = a_data[0] * np.sqrt(t[:n_pre] / t0) if a_data[0] > 0 else a_data[0]
    a[n_pre:n_pre + n_data] = a_data
    a[n_pre + n_data:] = a_data[-1]                                  # steady state after
    return t, a, n_pre, n_pre + n_data - 1


def log_derivative(t_s: ArrayLike, zth_k_per_w: ArrayLike) -> NDArray:
    """``dZth/d(ln t)`` on a grid uniform in ln t: the Savitzky–Golay derivative (local
    quadratic least squares over :data:`SG_WINDOW` = 5 points, i.e. the filter
    ``(−2, −1, 0, 1, 2) / (10 Δz)``), second-order one-sided differences at the two ends.

    >>> t = np.geomspace(1e-3, 1e3, 121)
    >>> d = log_derivative(t, 2.0 * np.log(t) + 0.1 * np.log(t) ** 2)   # exact for quadratics
    >>> bool(np.allclose(d, 2.0 + 0.2 * np.log(t)))
    True
    """
    t = np.asarray(t_s, dtype=float)
    a = np.asarray(zth_k_per_w, dtype=float)
    if a.size < SG_WINDOW:
        raise DataFormatError(f"log_derivative: need at least {SG_WINDOW} points")
    dz = float(np.log(t[1] / t[0]))
    d = np.gradient(a, dz, edge_order=2)
    d[2:-2] = (2 * (a[4:] - a[:-4]) + (a[3:-1] - a[1:-3])) / (10 * dz)
    return d


def time_constant_spectrum(source: ZthCurve | ArrayLike, zth_k_per_w: ArrayLike | None = None,
                           *, method: Method = "bayes", points_per_decade: int = POINTS_PER_DECADE,
                           iterations: int = BAYES_ITERATIONS, pre_decades: float = PRE_DECADES,
                           post_decades: float = POST_DECADES,
                           t_reliable_s: float | None = None,
                           lambda_rule: Literal["discrepancy", "lcurve"] = "discrepancy"
                           ) -> Spectrum:
    """Time-constant spectrum of a Zth(t) curve by deconvolution (see the module docstring).

    Parameters
    ----------
    source : a :class:`~spicethermal.identify.curves.ZthCurve`, or times (s) with ``zth_k_per_w``.
    zth_k_per_w : Zth (K/W) at those times, when ``source`` is an array of times.
    method : ``"bayes"`` (Bayesian iteration, default) or ``"nnls"`` (NNLS + Tikhonov).
    points_per_decade : grid density in t and τ.
    iterations : number of Bayesian iterations (``"bayes"``).
    pre_decades, post_decades : extension before the data (√t) and after them (steady).
    t_reliable_s : first time the data are trusted (default: the end of the masked
        electrical transient of a cooling curve, else the first sample); only reported.
    lambda_rule : how ``"nnls"`` picks λ: ``"discrepancy"`` (default) or ``"lcurve"``.

    Returns
    -------
    Spectrum

    Examples
    --------
    >>> from spicethermal.core.ladder import Foster
    >>> t = np.geomspace(1e-5, 10, 241)
    >>> s = time_constant_spectrum(t, Foster.from_tau([1.0], [1e-2]).zth(t), method="nnls")
    >>> round(s.rth_k_per_w, 3), [round(float(x), 3) for x in s.peaks_s()]
    (1.0, [0.01])
    """
    curve = _as_curve(source, zth_k_per_w)
    if method not in ("bayes", "nnls"):
        raise DataFormatError(f"method = {method!r}: 'bayes' or 'nnls'")
    if lambda_rule not in ("discrepancy", "lcurve"):
        raise DataFormatError(f"lambda_rule = {lambda_rule!r}: 'discrepancy' or 'lcurve'")
    if isinstance(points_per_decade, bool) or int(points_per_decade) != points_per_decade \
            or not 4 <= points_per_decade <= 200:
        raise DataFormatError(f"points_per_decade = {points_per_decade!r}: an integer 4..200")
    if method == "bayes" and (isinstance(iterations, bool) or int(iterations) != iterations
                              or iterations < 1):
        raise DataFormatError(f"iterations = {iterations!r}: a positive integer")
    for name, v in (("pre_decades", pre_decades), ("post_decades", post_decades)):
        if not (math.isfinite(v) and 0 <= v <= 6):
            raise DataFormatError(f"{name} = {v!r}: must be within 0..6")
    t, a, i0, i1 = _grid(curve, int(points_per_decade), pre_decades, post_decades)
    z = np.log(t)
    d = log_derivative(t, a)
    d[i1 + 3:] = 0.0                 # exact zero in the steady-state hold
    w = kernel_matrix(z, z)
    params: dict[str, Any] = {"points_per_decade": int(points_per_decade),
                              "pre_decades": float(pre_decades),
                              "post_decades": float(post_decades)}
    if method == "bayes":
        sigma = noise_sigma(d[i0:i1 + 1])
        dens = bayes(w, d, int(iterations), background=BACKGROUND_SIGMAS * sigma)
        params["background_k_per_w"] = BACKGROUND_SIGMAS * sigma
        resolution = bayes_resolution(int(points_per_decade), int(iterations))
        params["iterations"] = int(iterations)
    else:
        dens, lam, info = nnls_tikhonov(w, d, lambda_rule)
        mid = (i0 + i1) // 2
        lmat = second_difference(w.shape[1])
        wtw = w.T @ w
        psf = np.linalg.solve(wtw + lam**2 * (lmat.T @ lmat), wtw[:, mid])
        resolution = fwhm_decades(z, psf)
        params.update(info)
    # what the grid misses (Zth at its first point, mostly) goes into the first cell, so
    # that ΣR is not below the curve's final value
    dens[0] += max(float(a[-1]) - float(dens.sum()) * float(z[1] - z[0]), 0.0) / float(
        z[1] - z[0])
    if t_reliable_s is None:
        early = curve.early
        t_reliable_s = max(float(curve.t_s[0]), early.masked_s[1]) if early else float(
            curve.t_s[0])
    return Spectrum(t, dens, method, resolution, (float(t_reliable_s), float(curve.t_s[-1])),
                    params, curve.label, data_zth_k_per_w=a, data_derivative_k_per_w=d)
