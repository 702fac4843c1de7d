"""TSP calibration (paper §4, Fig. 2): the temperature-sensitive parameter against temperature.

A diode biased at a constant small current has a forward voltage nearly linear in
temperature; its slope is the K-factor (mV/K, about -2 mV/K for silicon). :class:`Calibration`
fits ``V(T)`` by least squares, reports residuals in mV and in K, says whether a straight
line is good enough (:class:`LinearityTest`) and converts both ways.

Linearity test (stated): fit the quadratic too. The line is good enough when the quadratic
term is not significant (two-sided t test at level ``alpha`` = 5 %, n - 3 degrees of freedom)
**or** when it changes the temperature by less than ``tolerance_k`` (0.1 K) anywhere over the
calibrated range (a significant but negligible curvature). With only three points there is no
noise estimate and the curvature alone decides.

>>> cal = Calibration.fit([25, 50, 75, 100], [0.650, 0.600, 0.550, 0.500])
>>> round(cal.k_factor_mv_per_k, 9)
-2.0
>>> round(float(cal.temperature(0.575)), 9)
62.5
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..io.datasets import KFactorLaw, check_coefficients, check_monotonic

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class LinearityTest:
    """Is a straight line good enough for this calibration? (see the module docstring)."""

    quadratic_coefficient_v_per_k2: float
    t_statistic: float
    p_value: float
    curvature_k: float
    noise_k: float
    alpha: float
    tolerance_k: float
    linear_ok: bool

    def __str__(self) -> str:
        verdict = "linear is good enough" if self.linear_ok else "use the quadratic"
        return (f"quadratic term t = {self.t_statistic:.3g} (p = {self.p_value:.3g}), its largest "
                f"effect {self.curvature_k:.3g} K vs noise {self.noise_k:.3g} K: {verdict}")


def _as_points(temp_c: ArrayLike, v_tsp_v: ArrayLike) -> tuple[NDArray, NDArray]:
    try:
        t = np.asarray(temp_c, dtype=float).ravel()
        v = np.asarray(v_tsp_v, dtype=float).ravel()
    except (TypeError, ValueError):
        raise DataFormatError("calibration: temp_c and v_tsp_v must be numbers") from None
    if t.size != v.size:
        raise DataFormatError(f"calibration: {t.size} temperatures but {v.size} voltages")
    for name, arr in (("temp_c", t), ("v_tsp_v", v)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise DataFormatError(f"calibration, point {bad[0] + 1}, column {name}: "
                                  f"{arr[bad[0]]} is not a finite number")
    if np.any(t < -273.15):
        i = int(np.flatnonzero(t < -273.15)[0])
        raise DataFormatError(f"calibration, point {i + 1}, column temp_c: below absolute zero")
    return t, v


def _polyfit(t: NDArray, v: NDArray, degree: int, center: float, scale: float):
    """Least squares in x = (T - center)/scale; returns coefficients and their covariance."""
    x = (t - center) / scale
    a = np.vander(x, degree + 1, increasing=True)
    coef, _, rank, _ = np.linalg.lstsq(a, v, rcond=None)
    if rank < degree + 1:
        raise DataFormatError(f"calibration: the temperatures do not determine a degree "
                              f"{degree} fit (need {degree + 1} distinct temperatures)")
    resid = v - a @ coef
    dof = t.size - degree - 1
    s2 = float(resid @ resid) / dof if dof > 0 else math.nan
    cov = s2 * np.linalg.inv(a.T @ a)
    return coef, cov, dof


def _to_plain(coef_x: NDArray, center: float, scale: float) -> tuple[float, ...]:
    """Coefficients in x = (T - c)/s -> coefficients in T (ascending)."""
    p = np.polynomial.Polynomial(coef_x)
    q = p(np.polynomial.Polynomial([-center / scale, 1.0 / scale]))
    out = list(q.coef) + [0.0] * (len(coef_x) - len(q.coef))
    return tuple(float(c) for c in out)


@dataclass(frozen=True)
class Calibration:
    """A fitted TSP calibration ``V(T) = Σ coefficients[k] · T^k`` (T in degC, V in volts).

    Build it with :meth:`fit`. Immutable.

    Attributes
    ----------
    temp_c, v_tsp_v : tuple of float
        The calibration points: temperatures (degC) and TSP voltages (V).
    degree : int
        Degree of the polynomial.
    coefficients : tuple of float
        ``V(T)`` coefficients, ascending powers of T (V per degC^k).
    given : bool
        Whether the coefficients were given (a polynomial calibration) rather than fitted.
    """

    temp_c: tuple[float, ...]
    v_tsp_v: tuple[float, ...]
    degree: int
    coefficients: tuple[float, ...]
    given: bool = False

    @classmethod
    def fit(cls, temp_c: ArrayLike, v_tsp_v: ArrayLike, degree: int | str = 1) -> Calibration:
        """Least-squares fit of the calibration points.

        Parameters
        ----------
        temp_c : temperatures of the points, degC.
        v_tsp_v : TSP voltages measured at those temperatures, V.
        degree : 1 (linear), 2 (quadratic) or ``"auto"`` (linear unless the
            :attr:`linearity` test says a straight line is not good enough).

        Examples
        --------
        >>> cal = Calibration.fit([20, 40, 60, 80], [0.6, 0.56, 0.52, 0.48])
        >>> cal.degree, round(cal.k_factor_mv_per_k, 9), round(cal.rms_mv, 9)
        (1, -2.0, 0.0)
        """
        t, v = _as_points(temp_c, v_tsp_v)
        if degree == "auto":
            line = cls.fit(t, v, 1)
            if np.unique(t).size < 3 or line.linearity.linear_ok:
                return line
            degree = 2
        if degree not in (1, 2) or isinstance(degree, bool):
            raise DataFormatError(f"calibration: degree = {degree!r}, must be 1, 2 or 'auto'")
        if np.unique(t).size < degree + 1:
            raise DataFormatError(f"calibration: a degree {degree} fit needs at least "
                                  f"{degree + 1} distinct temperatures, got {np.unique(t).size}")
        center, scale = float(t.mean()), float(np.ptp(t)) or 1.0
        coef, _, _ = _polyfit(t, v, degree, center, scale)
        plain = _to_plain(coef, center, scale)
        cal = cls(tuple(map(float, t)), tuple(map(float, v)), int(degree), plain)
        if degree == 2:
            lo, hi = min(t), max(t)
            vertex = -plain[1] / (2 * plain[2]) if plain[2] != 0 else math.inf
            if lo < vertex < hi:
                raise DataFormatError(f"calibration: the quadratic turns at {vertex:.4g} degC, "
                                      f"inside the calibrated range; the TSP is not monotonic")
            if abs(plain[1] + 2 * plain[2] * center) * scale <= 1e-12 * np.abs(v).max():
                raise DataFormatError("calibration: zero slope, the TSP does not depend on T")
        elif abs(plain[1]) * scale <= 1e-12 * np.abs(v).max():
            raise DataFormatError("calibration: zero slope, the TSP does not depend on T")
        return cal

    @classmethod
    def from_coefficients(cls, coefficients: Sequence[float], temp_c: ArrayLike,
                          v_tsp_v: ArrayLike) -> Calibration:
        """A polynomial fitted elsewhere (a T3Ster ``.tco`` header, a PyRth polynomial), kept
        with the points it was fitted to so that its residuals show.

        Parameters
        ----------
        coefficients : ``V(T) = Σ coefficients[k] · T^k`` (V, T in degC), ascending, 2 or 3 of
            them (a line or a quadratic).
        temp_c, v_tsp_v : the calibration points.

        Examples
        --------
        >>> cal = Calibration.from_coefficients([0.65, -0.002], [25, 75], [0.6, 0.5])
        >>> cal.kind, cal.residuals_mv.round(9).tolist()
        ('polynomial', [0.0, 0.0])
        """
        coef = check_coefficients(coefficients)
        t, v = _as_points(temp_c, v_tsp_v)
        if t.size < 2:
            raise DataFormatError("calibration: a polynomial needs its points (at least 2)")
        cal = cls(tuple(map(float, t)), tuple(map(float, v)), len(coef) - 1, coef, True)
        check_monotonic(coef, cal.t_range_c)
        return cal

    @property
    def kind(self) -> str:
        """``"table"`` (fitted here to the points) or ``"polynomial"`` (given)."""
        return "polynomial" if self.given else "table"

    # -- the fit ------------------------------------------------------------------------
    @property
    def points(self) -> int:
        return len(self.temp_c)

    @property
    def t_range_c(self) -> tuple[float, float]:
        """Calibrated temperature range, degC."""
        return min(self.temp_c), max(self.temp_c)

    def voltage(self, temp_c: ArrayLike) -> NDArray:
        """TSP voltage (V) at temperature ``temp_c`` (degC)."""
        return np.polynomial.polynomial.polyval(np.asarray(temp_c, dtype=float),
                                                self.coefficients)

    def slope_v_per_k(self, temp_c: ArrayLike) -> NDArray:
        """dV/dT in V/K at ``temp_c``."""
        t = np.asarray(temp_c, dtype=float)
        c = self.coefficients
        return c[1] + (2 * c[2] * t if self.degree == 2 else 0.0 * t)

    def k_factor_at(self, temp_c: float) -> float:
        """K-factor dV/dT in mV/K at ``temp_c`` (the same everywhere for a line)."""
        return float(self.slope_v_per_k(temp_c)) * 1e3

    @property
    def k_factor_mv_per_k(self) -> float:
        """K-factor in mV/K; for the quadratic, at the middle of the calibrated range."""
        return self.k_factor_at(sum(self.t_range_c) / 2)

    @property
    def residuals_mv(self) -> NDArray:
        """Measured minus fitted voltage at each point, mV."""
        t, v = np.asarray(self.temp_c), np.asarray(self.v_tsp_v)
        return (v - self.voltage(t)) * 1e3

    @property
    def residuals_k(self) -> NDArray:
        """The residuals as temperature errors, K: the voltage residual over the local slope,
        i.e. how far the fit would put the temperature of the measured voltage from the true
        one (positive when the fit reads too hot)."""
        t = np.asarray(self.temp_c)
        return self.residuals_mv * 1e-3 / self.slope_v_per_k(t)

    @property
    def rms_mv(self) -> float:
        """Root mean square of the residuals, mV."""
        return float(np.sqrt(np.mean(self.residuals_mv ** 2)))

    @property
    def rms_k(self) -> float:
        """Root mean square of the residuals, K."""
        return float(np.sqrt(np.mean(self.residuals_k ** 2)))

    @property
    def linearity(self) -> LinearityTest:
        """The stated test of whether a straight line is good enough (module docstring)."""
        return self.linearity_test()

    def linearity_test(self, alpha: float = 0.05, tolerance_k: float = 0.1) -> LinearityTest:
        """Test the quadratic term against noise and against ``tolerance_k``; see the module
        docstring. Needs at least 3 distinct temperatures."""
        t, v = np.asarray(self.temp_c), np.asarray(self.v_tsp_v)
        if np.unique(t).size < 3:
            raise DataFormatError("calibration: the linearity test needs at least 3 distinct "
                                  "temperatures")
        center, scale = float(t.mean()), float(np.ptp(t))
        coef, cov, dof = _polyfit(t, v, 2, center, scale)
        a2 = float(coef[2])
        line = np.polynomial.polynomial.polyfit((t - center) / scale, v, 1)
        x = (np.linspace(t.min(), t.max(), 201) - center) / scale
        quad = np.polynomial.polynomial.polyval(x, coef)
        lin = np.polynomial.polynomial.polyval(x, line)
        slope = abs(float(line[1]) / scale)
        curvature_k = float(np.max(np.abs(quad - lin))) / slope
        if dof > 0:
            se = math.sqrt(max(cov[2, 2], 0.0))
            resid = v - np.polynomial.polynomial.polyval((t - center) / scale, coef)
            noise_k = math.sqrt(float(resid @ resid) / dof) / slope
            if se == 0:
                tstat = math.inf if a2 != 0 else 0.0
                p = 0.0 if a2 != 0 else 1.0
            else:
                from scipy.special import stdtr

                tstat = a2 / se
                p = float(2 * stdtr(dof, -abs(tstat)))  # Student's two-sided tail
            significant = p < alpha
        else:
            tstat, p, noise_k = math.nan, math.nan, math.nan
            significant = True
        ok = (not significant) or curvature_k < tolerance_k
        return LinearityTest(a2 / scale**2, float(tstat), float(p), curvature_k, noise_k,
                             alpha, tolerance_k, bool(ok))

    # -- conversion ---------------------------------------------------------------------
    def temperature(self, v_tsp_v: ArrayLike, *, margin_k: float | None = None) -> NDArray:
        """Junction temperature (degC) from TSP voltage (V): the inverse of :meth:`voltage`.

        A line extrapolates freely unless ``margin_k`` is given. For the quadratic the root on
        the calibrated branch is taken, and a voltage whose temperature lies more than
        ``margin_k`` (default 25 K) outside the calibrated range, or beyond the parabola's
        turning point, raises :class:`DataFormatError`.

        >>> cal = Calibration.fit([0, 50, 100], [0.70, 0.60, 0.51], degree=2)
        >>> [round(float(x), 9) for x in cal.temperature(cal.voltage([10.0, 90.0]))]
        [10.0, 90.0]
        """
        v = np.asarray(v_tsp_v, dtype=float)
        if not np.all(np.isfinite(v)):
            raise DataFormatError("v_tsp_v: not a finite number")
        c = self.coefficients
        lo, hi = self.t_range_c
        if self.degree == 1:
            t = (v - c[0]) / c[1]
        else:
            if margin_k is None:
                margin_k = 25.0
            a, b = c[2], c[1]
            disc = b * b - 4 * a * (c[0] - v)
            mid = (lo + hi) / 2
            sign = 1.0 if (b + 2 * a * mid) > 0 else -1.0  # the branch: sign of the slope
            beyond = disc < 0
            root = np.sqrt(np.where(beyond, 0.0, disc))
            # the root with slope b + 2aT = sign * sqrt(disc); stable form
            t = 2 * (v - c[0]) / (b + sign * root)
            if np.any(beyond):
                bad = float(np.ravel(v)[np.flatnonzero(np.ravel(beyond))[0]])
                raise DataFormatError(f"v_tsp_v = {bad!r} V lies beyond the turning point of "
                                      f"the quadratic calibration")
        if margin_k is not None:
            out = (t < lo - margin_k) | (t > hi + margin_k)
            if np.any(out):
                k = np.flatnonzero(np.ravel(out))[0]
                raise DataFormatError(
                    f"v_tsp_v = {float(np.ravel(v)[k])!r} V means "
                    f"{float(np.ravel(t)[k]):.4g} degC, more than {margin_k:g} K outside the "
                    f"calibrated range {lo:g}..{hi:g} degC")
        return t

    def __str__(self) -> str:
        kind = "linear" if self.degree == 1 else "quadratic"
        kind += " (given)" if self.given else ""
        return (f"{kind} TSP calibration over {self.t_range_c[0]:g}..{self.t_range_c[1]:g} degC "
                f"({self.points} points): K = {self.k_factor_mv_per_k:.4g} mV/K, "
                f"rms {self.rms_mv:.3g} mV = {self.rms_k:.3g} K")


class KFactor(KFactorLaw):
    """The converter of a K-factor calibration (:class:`~spicethermal.io.datasets.KFactorLaw`,
    whose numbers and checks it has): ``V(T) = v_ref_v + K (T - t_ref_c)`` both ways.

    >>> k = KFactor.from_mv_per_k(-2.0, v_ref_v=0.6, t_ref_c=25.0)
    >>> round(float(k.temperature(0.55)), 9), round(float(k.voltage(50.0)), 9)
    (50.0, 0.55)
    """

    @property
    def degree(self) -> int:
        return 1

    def voltage(self, temp_c: ArrayLike) -> NDArray:
        """TSP voltage (V) at ``temp_c`` (degC)."""
        return self.v_ref_v + self.k_v_per_k * (np.asarray(temp_c, dtype=float) - self.t_ref_c)

    def slope_v_per_k(self, temp_c: ArrayLike) -> NDArray:
        """dV/dT in V/K (the same everywhere)."""
        return np.full_like(np.asarray(temp_c, dtype=float), self.k_v_per_k)

    def temperature(self, v_tsp_v: ArrayLike, *, margin_k: float | None = None) -> NDArray:
        """Junction temperature (degC) from TSP voltage (V); ``margin_k`` is accepted for the
        converter interface and ignored (a K-factor has no calibrated range)."""
        v = np.asarray(v_tsp_v, dtype=float)
        if not np.all(np.isfinite(v)):
            raise DataFormatError("v_tsp_v: not a finite number")
        return self.t_ref_c + (v - self.v_ref_v) / self.k_v_per_k


#: Anything that converts TSP voltage to junction temperature (:class:`Calibration`,
#: :class:`KFactor`): ``temperature(v)``, ``voltage(T)``, ``k_factor_mv_per_k``.
Converter = Calibration | KFactor


def anchored(calibration: Converter, v_tsp_v: float, temp_c: float) -> KFactor:
    """The K-factor of ``calibration`` re-anchored so that ``v_tsp_v`` reads ``temp_c``: what a
    transient recorded with another sense current or amplifier offset than the calibration
    needs (for a quadratic, the slope where the table puts ``v_tsp_v``).

    Parameters
    ----------
    calibration : a fitted or given polynomial, or a K-factor.
    v_tsp_v : a voltage of the transient at a known temperature (the end of a cooling record).
    temp_c : that temperature, degC.

    Returns
    -------
    KFactor

    >>> cal = Calibration.fit([25, 75], [0.60, 0.50])
    >>> k = anchored(cal, 0.65, 25.0)
    >>> round(k.k_factor_mv_per_k, 9), round(float(k.temperature(0.60)), 9)
    (-2.0, 50.0)
    """
    at = float(np.mean(calibration.temperature(v_tsp_v)))
    slope = float(calibration.slope_v_per_k(at))
    return KFactor(slope, float(v_tsp_v), float(temp_c), "calibration")

