"""Thermal impedance curves: from a cooling curve to Zth(t), Rth and r(t) (paper §3, §5).

:class:`ZthCurve` is the one object the fitter consumes: times ``t_s`` (> 0, increasing), the
step response ``zth_k_per_w`` (heating direction, rising from 0 to Rth) and ``rth_k_per_w``.

From a cooling curve (:meth:`ZthCurve.from_cooling`):

* eq. 1, ``Rth = (Tj - Tref) / P`` from the steady state just before power is cut;
* the heating curve from the cooling curve, ``T_heating(t) = T_max - T_cooling(t)``, with the
  reference column removing drift: ``Zth(t) = [(Tj_max - Tref_steady) - (Tj(t) - Tref(t))] / P``;
* eq. 2, ``r(t) = Zth(t) / Rth``;
* the early-time correction of JESD51-14 practice: the electrical transient after the cut is
  masked and the junction temperature there (and at the cut) is extrapolated by the √t law of
  one-dimensional diffusion, ``T(t) = T0 - k √t``, fitted over a window just after the masked
  span. Masked span, window and fit are reported in :class:`EarlyTimeFix`. Without a steady
  junction temperature, ``T0`` is the junction temperature at the cut.

>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.core.synthetic import synthetic_cooling
>>> f = Foster.from_tau([1.0, 2.0], [1e-3, 1e-1])
>>> t, tj = synthetic_cooling(f, 5.0, np.geomspace(1e-5, 10, 61), ambient_c=25.0)
>>> z = ZthCurve.from_cooling(t, tj, 5.0, tj_steady_c=40.0, tref_steady_c=25.0, mask_s=None)
>>> z.rth_k_per_w, bool(np.allclose(z.zth_k_per_w, f.zth(t)))
(3.0, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..core.errors import DataFormatError
from ..io.columns import frozen
from ..io.datasets import CoolingTable, ZthTable
from .readings import cooling_tj_c

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..io.bundle import Bundle

#: Auto-detection looks for the electrical transient no later than this (s).
TRANSIENT_SEARCH_S = 1e-3
#: The masked span is this many times the time at which the transient's rise peaks.
MASK_FACTOR = 2.0
#: Default √t fit window: from the end of the masked span to this many times it (√t doubles).
FIT_WINDOW_FACTOR = 4.0
#: The √t fit needs at least this many samples (the window grows until it has them).
MIN_FIT_POINTS = 10


class NotAboveReference(DataFormatError):
    """A cooling curve whose Tj at the cut is not above its reference: no Rth. ``core`` is the
    message without the hint, for a caller that knows the better one."""

    def __init__(self, core: str, hint: str, tj_c: float, ref_c: float) -> None:
        super().__init__(f"{core} ({hint})")
        self.core, self.tj_c, self.ref_c = core, tj_c, ref_c


@dataclass(frozen=True)
class EarlyTimeFix:
    """The early-time correction applied to a cooling curve (JESD51-14 √t extrapolation).

    ``masked_s = (0, t_end)``: samples with ``t < t_end`` were replaced by the fitted
    ``T(t) = t0_c - slope_k_per_sqrt_s · √t``, which was fitted over ``fit_window_s``.
    """

    masked_s: tuple[float, float]
    masked_points: int
    fit_window_s: tuple[float, float]
    fit_points: int
    t0_c: float
    slope_k_per_sqrt_s: float
    fit_rms_k: float
    detected: bool

    def __str__(self) -> str:
        """One line: what was masked (nothing, said so), the √t fit and Tj at the cut.

        >>> fix = EarlyTimeFix((0.0, 0.0), 0, (1e-4, 8e-4), 10, 38.76, 34.2, 0.03, False)
        >>> str(fix).split("; ")[0]
        'no samples masked (no electrical transient given or detected)'
        >>> str(EarlyTimeFix((0.0, 9.6e-5), 88, (1e-4, 4e-4), 10, 38.7, 34.2, 0.03, True)
        ...     ).split("; ")[0]
        'masked 88 samples before 9.6e-05 s (detected electrical transient)'
        """
        how = "detected" if self.detected else "given"
        masked = (f"masked {self.masked_points} samples before {self.masked_s[1]:.3g} s ({how} "
                  f"electrical transient)" if self.masked_points else
                  "no samples masked (no electrical transient given or detected)")
        lo, hi = self.fit_window_s
        return (f"{masked}; sqrt(t) fit over {lo:.3g}..{hi:.3g} s "
                f"({self.fit_points} samples, rms {self.fit_rms_k:.3g} K): "
                f"T0 = {self.t0_c:.4g} degC, k = {self.slope_k_per_sqrt_s:.4g} K/sqrt(s)")


def _running_median(y: NDArray, width: int = 5) -> NDArray:
    if y.size < width:
        return y.copy()
    pad = width // 2
    yp = np.pad(y, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(yp, width)
    return np.median(windows, axis=1)


def detect_transient(t_s: ArrayLike, tj_c: ArrayLike,
                     search_s: float = TRANSIENT_SEARCH_S) -> float:
    """Time (s) until which the electrical transient corrupts a cooling curve; 0 if none.

    A cooling junction only cools. Within the first ``search_s`` (at most the first half of
    the record in log time) the curve is smoothed by a 5-sample running median; a sample
    that lies lower than a later one by more than 3 noise standard deviations (estimated
    from the median absolute sample-to-sample difference) shows the curve rising, which only
    the electrical transient does. The transient lasts at least until the highest point
    after the last such sample; the masked span is :data:`MASK_FACTOR` times that time, to
    clear the transient's tail. Spikes before it are masked with it. A transient that only
    makes the reading too hot (a curve still falling) is not detected: give its length.

    >>> t = np.geomspace(1e-6, 1, 61)
    >>> round(detect_transient(t, 30 - np.sqrt(t) - np.exp(-t / 1e-5)), 6)  # peaks at 63 us
    0.000126
    >>> detect_transient(t, 30 - np.sqrt(t))
    0.0
    """
    t = np.asarray(t_s, dtype=float)
    y = np.asarray(tj_c, dtype=float)
    pos = t > 0
    t, y = t[pos], y[pos]
    if t.size < 3:
        return 0.0
    half = math.sqrt(t[0] * t[-1])
    n = int(np.searchsorted(t, min(search_s, half), side="right"))
    if n < 3:
        return 0.0
    smooth = _running_median(y[: n + 2])[:n]
    sigma = 1.4826 * float(np.median(np.abs(np.diff(y[: n + 2])))) / math.sqrt(2)
    later_max = np.maximum.accumulate(smooth[::-1])[::-1]  # max of smooth[i:]
    rising = np.flatnonzero(smooth[:-1] < later_max[1:] - 3 * sigma)
    if rising.size == 0:
        return 0.0
    j = int(rising[-1]) + 1
    peak = j + int(np.argmax(smooth[j:]))
    return float(MASK_FACTOR * t[peak])


def sqrt_t_fit(t_s: NDArray, temp_c: NDArray, window_s: tuple[float, float]
               ) -> tuple[float, float, float, int]:
    """Least-squares ``T = T0 - k √t`` over ``window_s``: returns (T0, k, rms_k, n)."""
    lo, hi = window_s
    sel = (t_s >= lo) & (t_s <= hi)
    n = int(sel.sum())
    if n < 2:
        raise DataFormatError(f"sqrt(t) fit window {lo:.3g}..{hi:.3g} s holds {n} samples; "
                              f"need at least 2")
    s = np.sqrt(t_s[sel])
    a = np.column_stack([np.ones(n), -s])
    (t0, k), *_ = np.linalg.lstsq(a, temp_c[sel], rcond=None)
    resid = temp_c[sel] - a @ np.array([t0, k])
    return float(t0), float(k), float(np.sqrt(np.mean(resid**2))), n


def _default_window(t: NDArray, start: float) -> tuple[float, float]:
    start = max(start, float(t[0]))
    hi = start * FIT_WINDOW_FACTOR
    i0 = int(np.searchsorted(t, start))
    if int(np.searchsorted(t, hi, side="right")) - i0 < MIN_FIT_POINTS:
        hi = float(t[min(i0 + MIN_FIT_POINTS - 1, t.size - 1)])
    return start, hi


def log_grid(t_min: float, t_max: float, points_per_decade: int = 10) -> NDArray:
    """``t_min · 10^(k / points_per_decade)`` up to ``t_max`` (inclusive, to rounding).

    >>> log_grid(1e-4, 10 ** 0.5).size   # the paper: 46 points, ten per decade from 100 us
    46
    """
    if not (t_min > 0 and t_max >= t_min and points_per_decade > 0):
        raise DataFormatError(f"log grid {t_min!r}..{t_max!r} s at {points_per_decade!r} per "
                              f"decade: need 0 < t_min <= t_max and points_per_decade > 0")
    n = int(math.floor(math.log10(t_max / t_min) * points_per_decade + 1e-9)) + 1
    return t_min * 10.0 ** (np.arange(n) / points_per_decade)


@dataclass(frozen=True, eq=False)
class ZthCurve:
    """Thermal impedance Zth(t) (K/W) of a heated device, with its Rth (K/W).

    Immutable. Build it with :meth:`from_cooling`, :meth:`from_points` or
    :meth:`from_bundle`; ``t_s`` must be > 0 and strictly increasing.

    Attributes
    ----------
    t_s : ndarray (read-only)
        Times (s), positive and strictly increasing.
    zth_k_per_w : ndarray (read-only)
        Thermal impedance (K/W) at ``t_s``.
    rth_k_per_w : float
        Thermal resistance (K/W), the steady-state value of Zth.
    power_w : float or None
        The heating power (W) of the measurement, when known.
    label : str
        A name for tables and plots.
    early : EarlyTimeFix or None
        The early-time (√t) correction applied to a cooling curve, when one was.
    tj_max_c : float or None
        The junction temperature (degC) in the heated steady state.
    tref_steady_c : float or None
        The reference temperature (degC) just before the power was cut.
    meta : dict
        Free-form provenance (e.g. how the curve was resampled).
    """

    t_s: NDArray
    zth_k_per_w: NDArray
    rth_k_per_w: float
    power_w: float | None = None
    label: str = ""
    early: EarlyTimeFix | None = None
    tj_max_c: float | None = None
    tref_steady_c: float | None = None
    meta: dict[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        name = self.label or "Zth curve"
        table = ZthTable(self.t_s, zth_k_per_w=self.zth_k_per_w, file=name)
        if table.t_s[0] <= 0:
            raise DataFormatError(f"{name}: times must be > 0 (log time); got {table.t_s[0]!r}")
        rth = float(self.rth_k_per_w)
        if not (math.isfinite(rth) and rth > 0):
            raise DataFormatError(f"{name}: rth_k_per_w = {self.rth_k_per_w!r} must be > 0")
        object.__setattr__(self, "t_s", table.t_s)
        object.__setattr__(self, "zth_k_per_w", table.zth_k_per_w)
        object.__setattr__(self, "rth_k_per_w", rth)

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def from_cooling(cls, t_s: ArrayLike, tj_c: ArrayLike, power_w: float,
                     tj_steady_c: float | None = None, tref_c: ArrayLike | None = None,
                     tref_steady_c: float | None = None, *,
                     mask_s: float | str | None = "auto",
                     fit_window_s: tuple[float, float] | None = None,
                     extrapolate_to_s: float | None = None, label: str = "") -> ZthCurve:
        """Zth(t) from a cooling curve (see the module docstring for the equations).

        Parameters
        ----------
        t_s : times after power is cut, s (>= 0, increasing; samples at t = 0 are dropped).
        tj_c : junction temperature, degC.
        power_w : power before the cut, W.
        tj_steady_c : junction temperature just before the cut; ``None``: the √t-extrapolated
            ``T0`` (the curve is then corrected even with ``mask_s=None``).
        tref_c : reference temperature at each sample (removes drift).
        tref_steady_c : reference temperature just before the cut; default ``tref_c[0]``.
        mask_s : how long the electrical transient lasts: ``"auto"`` detects it
            (:func:`detect_transient`), a number gives it, ``None`` or 0 masks nothing.
        fit_window_s : √t fit window; default from the end of the masked span to
            :data:`FIT_WINDOW_FACTOR` times it (at least :data:`MIN_FIT_POINTS` samples).
        extrapolate_to_s : prepend √t-extrapolated points from this time (10 per decade) when
            the record starts later (the paper's first sample was at 100 us).

        Examples
        --------
        >>> from spicethermal.core.synthetic import mur880e_foster, synthetic_cooling
        >>> t, tj = synthetic_cooling(mur880e_foster(), 10.0, np.geomspace(1e-6, 30, 300),
        ...                           transient_s=1e-4)
        >>> z = ZthCurve.from_cooling(t, tj, 10.0, tref_steady_c=25.0)
        >>> z.early.detected, round(z.rth_k_per_w, 2)
        (True, 1.51)
        """
        name = label or "cooling curve"
        table = CoolingTable(t_s, power_w, tj_c=tj_c, tref_c=tref_c, tj_steady_c=tj_steady_c,
                             tref_steady_c=tref_steady_c, file=name)
        t, tj, p = table.t_s, table.tj_c, table.power_w
        if table.tref_c is not None:
            steady_ref = table.tref_c[0] if table.tref_steady_c is None else table.tref_steady_c
            theta = tj - (table.tref_c - steady_ref)  # junction referred to the steady reference
        elif table.tref_steady_c is not None:
            steady_ref, theta = table.tref_steady_c, tj.copy()
        else:
            raise DataFormatError(f"{name}: needs a reference: tref_steady_c or a tref_c column "
                                  f"(or the bundle's ambient_c)")
        keep = t > 0
        t, theta = t[keep], np.array(theta[keep], dtype=float)
        if t.size < 2:
            raise DataFormatError(f"{name}: needs at least 2 samples after the cut (t > 0)")

        detected = False
        if mask_s == "auto":
            t_mask = detect_transient(t, theta)
            detected = t_mask > 0
        elif mask_s is None:
            t_mask = 0.0
        else:
            if isinstance(mask_s, str) or not (math.isfinite(mask_s) and mask_s >= 0):
                raise DataFormatError(f"{name}: mask_s = {mask_s!r}: 'auto', None or a time "
                                      f">= 0 in s")
            t_mask = float(mask_s)
        if t_mask >= t[-1]:
            raise DataFormatError(f"{name}: the masked span ({t_mask:.3g} s) covers the whole "
                                  f"record")

        early = None
        need_fit = (t_mask > 0 or table.tj_steady_c is None or extrapolate_to_s is not None
                    or fit_window_s is not None)
        if need_fit:
            window = fit_window_s if fit_window_s is not None else _default_window(t, t_mask)
            t0, k, rms, n = sqrt_t_fit(t, theta, (float(window[0]), float(window[1])))
            masked = t < t_mask
            theta[masked] = t0 - k * np.sqrt(t[masked])
            early = EarlyTimeFix((0.0, t_mask), int(masked.sum()),
                                 (float(window[0]), float(window[1])), n, t0, k, rms, detected)
            if extrapolate_to_s is not None and extrapolate_to_s < t[0]:
                extra = log_grid(float(extrapolate_to_s), float(t[0]))
                extra = extra[extra < t[0] * (1 - 1e-9)]
                t = np.concatenate([extra, t])
                theta = np.concatenate([t0 - k * np.sqrt(extra), theta])
        tj_max = table.tj_steady_c if table.tj_steady_c is not None else early.t0_c
        rth = (tj_max - steady_ref) / p
        if not rth > 0:
            raise NotAboveReference(
                f"{name}: Tj at the cut ({tj_max:.4g} degC) is not above the reference "
                f"({steady_ref:.4g} degC): no Rth", "raw v_tsp_v through a calibration taken at "
                "another sense current or offset? use a k-factor calibration anchored at the "
                "reference, docs/bundle-format.md", float(tj_max), float(steady_ref))
        zth = (tj_max - theta) / p
        return cls(t, zth, rth, power_w=p, label=label, early=early, tj_max_c=float(tj_max),
                   tref_steady_c=float(steady_ref))

    @classmethod
    def from_points(cls, t_s: ArrayLike, zth_k_per_w: ArrayLike | None = None, *,
                    r: ArrayLike | None = None, rth_k_per_w: float | None = None,
                    label: str = "") -> ZthCurve:
        """Zth(t) from points, absolute (``zth_k_per_w``) or normalized (``r`` with Rth).

        Absolute points without ``rth_k_per_w`` take Rth as their last value (the curve's
        steady state). Points at t = 0 are dropped (Zth(0) = 0 by definition).

        >>> z = ZthCurve.from_points([1e-3, 1e-2, 1e-1], r=[0.18, 0.39, 0.6], rth_k_per_w=1.51)
        >>> [round(float(x), 4) for x in z.zth_k_per_w]
        [0.2718, 0.5889, 0.906]
        """
        name = label or "Zth points"
        table = ZthTable(t_s, zth_k_per_w=zth_k_per_w, r=r, rth_k_per_w=rth_k_per_w, file=name)
        if table.normalized:
            if table.rth_k_per_w is None:
                raise DataFormatError(f"{name}: normalized points r(t) need rth_k_per_w")
            zth = table.r * table.rth_k_per_w
        else:
            zth = table.zth_k_per_w
        rth = table.rth_k_per_w if table.rth_k_per_w is not None else float(zth[-1])
        keep = table.t_s > 0
        return cls(table.t_s[keep], zth[keep], rth, label=label)

    @classmethod
    def from_table(cls, table: ZthTable, label: str = "") -> ZthCurve:
        """A :class:`~spicethermal.io.bundle.ZthTable` of a bundle as a curve."""
        return cls.from_points(table.t_s, table.zth_k_per_w, r=table.r,
                               rth_k_per_w=table.rth_k_per_w, label=label or table.file or "")

    @classmethod
    def from_bundle(cls, bundle: Bundle, **options: Any) -> tuple[ZthCurve, ...]:
        """Every curve of a bundle: its cooling curves (``v_tsp_v`` converted through the
        calibration; ``options`` go to :meth:`from_cooling`), then its ``zth`` tables."""
        curves = []
        for i, c in enumerate(bundle.cooling):
            tref, tref_steady = bundle.cooling_reference_c(i)
            curves.append(cls.from_cooling(
                c.t_s, cooling_tj_c(bundle, i), c.power_w, c.tj_steady_c, tref, tref_steady,
                label=c.file or f"cooling[{i}]", **options))
        curves.extend(cls.from_table(z, label=z.file or f"zth[{i}]")
                      for i, z in enumerate(bundle.zth))
        return tuple(curves)

    # -- views -------------------------------------------------------------------------
    @property
    def r(self) -> NDArray:
        """Normalized impedance r(t) = Zth(t)/Rth (eq. 2)."""
        return frozen(self.zth_k_per_w / self.rth_k_per_w)

    def normalized(self) -> NDArray:
        """r(t) = Zth(t)/Rth at the curve's times (eq. 2 of the paper)."""
        return self.r

    def __len__(self) -> int:
        return self.t_s.size

    def at(self, t_s: ArrayLike, *, extrapolate: bool = False,
           average_decades: float = 0.0) -> NDArray:
        """Zth (K/W) at ``t_s`` by linear interpolation in log time.

        With ``average_decades`` > 0, a time with at least 3 samples within that width (in
        decades, centred on it) gets the value at its centre of a straight line fitted to
        them in log time instead: a local average for dense noisy records that stays
        unbiased when the samples are unevenly spread.

        Outside the record this raises, unless ``extrapolate``: then times before the first
        sample follow the √t law through it, ``Zth(t0) √(t/t0)`` (as the paper's early-time
        extrapolation); times after the last sample still raise.

        >>> z = ZthCurve.from_points([1e-3, 1e-2, 1e-1], [0.2, 0.4, 0.8])
        >>> [round(float(x), 6) for x in z.at([10 ** -2.5, 1e-5], extrapolate=True)]
        [0.3, 0.02]
        """
        t = np.asarray(t_s, dtype=float)
        if np.any(~np.isfinite(t)) or np.any(t <= 0):
            raise DataFormatError(f"{self.label or 'Zth curve'}: times must be > 0")
        lo, hi = self.t_s[0], self.t_s[-1]
        tol = 1e-9
        if np.any(t > hi * (1 + tol)):
            raise DataFormatError(f"{self.label or 'Zth curve'}: {float(np.max(t)):.3g} s is "
                                  f"after the record ends ({hi:.3g} s)")
        early = t < lo * (1 - tol)
        if np.any(early) and not extrapolate:
            raise DataFormatError(f"{self.label or 'Zth curve'}: {float(np.min(t)):.3g} s is "
                                  f"before the record starts ({lo:.3g} s)")
        lt = np.log(np.clip(t, lo, hi))
        z = np.interp(lt, np.log(self.t_s), self.zth_k_per_w)
        if average_decades > 0:
            z = self._local_line(np.atleast_1d(lt), np.atleast_1d(z).copy(),
                                 0.5 * average_decades * math.log(10.0)).reshape(z.shape)
        return np.where(early, self.zth_k_per_w[0] * np.sqrt(t / lo), z)

    def _local_line(self, lt: NDArray, z: NDArray, half: float) -> NDArray:
        """Replace z[j] by a straight-line fit in log time over lt[j] ± half (>= 3 samples)."""
        ls = np.log(self.t_s)
        left = np.searchsorted(ls, lt - half)
        right = np.searchsorted(ls, lt + half, side="right")
        for j in np.flatnonzero(right - left >= 3):
            x = ls[left[j]:right[j]] - lt[j]
            z[j] = np.polynomial.polynomial.polyfit(x, self.zth_k_per_w[left[j]:right[j]], 1)[0]
        return z

    def r_at(self, t_s: ArrayLike, *, extrapolate: bool = False) -> NDArray:
        """r(t) at ``t_s`` (see :meth:`at`)."""
        return self.at(t_s, extrapolate=extrapolate) / self.rth_k_per_w

    def resample_log(self, points_per_decade: int = 10, t_min: float | None = None,
                     t_max: float | None = None, method: str = "bin") -> ZthCurve:
        """The curve on a logarithmic time grid (the paper fitted 46 points, 10 per decade
        from 100 us: ``resample_log(10, 1e-4)``).

        The grid is ``t_min · 10^(k/points_per_decade)``; without ``t_min`` it starts at the
        first whole fraction of a decade (``10^(j/points_per_decade)``) at or after the first
        sample. ``method``:

        * ``"interp"`` — linear interpolation of Zth in log time;
        * ``"bin"`` (default) — for dense noisy data: in each bin of width one grid step in
          log time around a grid point, a straight line in log time is fitted to the samples
          and read at the grid point (a local average that stays unbiased when the samples
          are unevenly spread in the bin); bins with fewer than 3 samples fall back to
          interpolation.
        """
        if method not in ("interp", "bin"):
            raise DataFormatError(f"method = {method!r}: 'interp' or 'bin'")
        lo, hi = float(self.t_s[0]), float(self.t_s[-1])
        if t_min is None:
            t_min = 10.0 ** (math.ceil(math.log10(lo) * points_per_decade - 1e-9)
                             / points_per_decade)
        t_max = hi if t_max is None else float(t_max)
        if t_min < lo * (1 - 1e-9) or t_max > hi * (1 + 1e-9):
            raise DataFormatError(f"{self.label or 'Zth curve'}: resampling range "
                                  f"{t_min:.3g}..{t_max:.3g} s leaves the record "
                                  f"{lo:.3g}..{hi:.3g} s")
        grid = log_grid(float(t_min), t_max, points_per_decade)
        width = 1.0 / points_per_decade if method == "bin" else 0.0
        z = self.at(grid, average_decades=width)
        return replace(self, t_s=grid, zth_k_per_w=z, meta={**self.meta, "resampled": method})

    def to_table(self, normalized: bool = False, file: str | None = None) -> ZthTable:
        """The curve as a bundle ``zth`` table (absolute, or r(t) with its Rth)."""
        if normalized:
            return ZthTable(self.t_s, r=self.r, rth_k_per_w=self.rth_k_per_w, file=file)
        return ZthTable(self.t_s, zth_k_per_w=self.zth_k_per_w, rth_k_per_w=self.rth_k_per_w,
                        file=file)

    def __str__(self) -> str:
        text = (f"{self.label or 'Zth curve'}: {len(self)} points {self.t_s[0]:.3g}.."
                f"{self.t_s[-1]:.3g} s, Rth = {self.rth_k_per_w:.4g} K/W")
        return text + (f"; {self.early}" if self.early else "")
