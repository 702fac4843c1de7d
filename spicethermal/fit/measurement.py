"""The measurement model: a bundle's data sets as the fits see them, and how the bench reads
a true temperature.

Data (:class:`BundleData`): each cooling curve (dataset ``cooling_k``, the junction reading at
every ``t_s``), the PWM grid (``pwm``: the reading at the end of the sample window) and the
calibration (``calibration``: the temperature that the least-squares *linear* calibration of
the bundle gives for each calibration voltage, against the thermocouple temperature).

Readings: a TSP that is not linear (:func:`tsp_reading`, its inverse :func:`tsp_true`), read
through the bench's linear calibration (:func:`calibrated_reading`,
:func:`calibration_reading`), and the electrical transient after the cut
(:func:`transient_offset`). compare, fit and diagnose all read through these.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import DataFormatError
from ..effects import Effect

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from ..io.bundle import Bundle

#: Transient decay: the reading error is ``A·exp(−TRANSIENT_RATE·t/masked_s)`` (as in compare).
TRANSIENT_RATE = 5.0

@dataclass(frozen=True, eq=False)
class CurveData:
    """One cooling curve: readings ``tj_c`` at ``t_s`` (t > 0 only), the reference at every
    point, the power before the cut and the steady reading just before it (or None)."""

    name: str
    t_s: NDArray
    tj_c: NDArray
    tref_c: NDArray
    power_w: float
    tref_steady_c: float
    tj_steady_c: float | None
    has_tref_column: bool


@dataclass(frozen=True, eq=False)
class PwmData:
    """The PWM grid: one reading per row, and the bundle's declared sample window."""

    freq_hz: NDArray
    duty: NDArray
    power_w: NDArray
    tref_c: NDArray
    tj_c: NDArray
    window_s: float


@dataclass(frozen=True, eq=False)
class CalData:
    """Calibration points: thermocouple ``temp_c`` and the temperature ``read_c`` that the
    least-squares straight line gives for the measured voltage."""

    temp_c: NDArray
    read_c: NDArray

    def curvature_basis(self, t_cal_c: float) -> tuple[NDArray, float]:
        """``(u − P u, b_u)`` for ``u = (T − t_cal)²`` (see the module docstring)."""
        t = self.temp_c
        a = np.column_stack([np.ones_like(t), t])
        u = (t - t_cal_c) ** 2
        coef, *_ = np.linalg.lstsq(a, u, rcond=None)
        return u - a @ coef, float(coef[1])


@dataclass(frozen=True, eq=False)
class BundleData:
    """The arrays of a bundle that the diagnosis compares against, by data set name.

    >>> from spicethermal.io.bundle import Bundle, PwmTable
    >>> d = BundleData.from_bundle(Bundle(ambient_c=25.0,
    ...                            pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1)))
    >>> d.datasets
    ('pwm',)
    """

    cooling: tuple[CurveData, ...] = ()
    pwm: PwmData | None = None
    calibration: CalData | None = None
    ambient_c: float = 25.0
    source: str = "bundle"
    #: Noise scale (K) of each data set: the fits weigh its residuals by 1/scale (1 K when
    #: absent); the diagnosis sets them to its noise estimates.
    scales: Mapping[str, float] = field(default_factory=dict)
    #: Temperatures of the bundle's calibration points when the cooling curves are in volts:
    #: their readings went through the least-squares line fitted to those points (here, in
    #: :meth:`from_bundle`). None: readings in °C from the bench, modelled as through the
    #: tangent at ``t_cal_c`` (which also covers a line of another gain and offset).
    line_temps_c: NDArray | None = None

    def scale(self, name: str) -> float:
        """Noise scale (K) of data set ``name`` (1 when not set)."""
        return float(self.scales.get(name, 1.0))

    @classmethod
    def from_bundle(cls, bundle: Bundle) -> BundleData:
        ambient = bundle.ambient_c if bundle.ambient_c is not None else 25.0
        # curves in volts go through the *linear* calibration, as the calibration data set
        # does: a curvature of the TSP then shows once, as tsp-nonlinearity, never twice
        line = bundle.calibration
        if line is not None and hasattr(line, "fit"):  # a K-factor is linear already
            line = line.fit(1)
        curves = []
        for i, c in enumerate(bundle.cooling):
            tj = np.asarray(c.tj_c if c.tj_c is not None else line.temperature(c.v_tsp_v),
                            dtype=float)
            rows, steady = bundle.cooling_reference_c(i)
            if steady is None:
                steady = float(rows[0]) if rows is not None else ambient
            tref = (np.asarray(rows, dtype=float) if rows is not None
                    else np.full(tj.size, float(steady)))
            keep = c.t_s > 0
            curves.append(CurveData(f"cooling_{i + 1}", np.asarray(c.t_s)[keep], tj[keep],
                                    tref[keep], float(c.power_w), float(steady),
                                    c.tj_steady_c, rows is not None))
        pwm = None
        if bundle.pwm is not None:
            p = bundle.pwm
            tref = (np.asarray(p.tref_c, dtype=float) if p.tref_c is not None
                    else np.full(p.freq_hz.size, ambient))
            pwm = PwmData(np.asarray(p.freq_hz, float), np.asarray(p.duty, float),
                          np.asarray(p.powers_w, float), tref, np.asarray(p.tj_c, float),
                          float(p.sample_window_s))
        cal = None
        points = getattr(bundle.calibration, "temp_c", None)  # a K-factor has no points
        if line is not None and points is not None and np.unique(points).size >= 3:
            cal = CalData(np.asarray(bundle.calibration.temp_c, float),
                          np.asarray(line.temperature(bundle.calibration.v_tsp_v), float))
        in_volts = bool(bundle.cooling) and all(c.tj_c is None for c in bundle.cooling)
        return cls(tuple(curves), pwm, cal, float(ambient), bundle.source or "bundle",
                   line_temps_c=np.asarray(points, float) if in_volts and points is not None
                   else None)

    @property
    def datasets(self) -> tuple[str, ...]:
        """Names of the data sets, in report order."""
        names = [c.name for c in self.cooling]
        if self.pwm is not None:
            names.append("pwm")
        if self.calibration is not None:
            names.append("calibration")
        return tuple(names)

    def curve(self, name: str) -> CurveData:
        return next(c for c in self.cooling if c.name == name)

    def measured(self, name: str) -> NDArray:
        """Measured values (°C) of data set ``name``."""
        if name == "pwm":
            return self.pwm.tj_c
        if name == "calibration":
            return self.calibration.read_c
        return self.curve(name).tj_c

    def weighted(self, pred: Mapping[str, NDArray], names: Iterable[str],
                 keep: Mapping[str, NDArray] | None = None) -> NDArray:
        """The residuals of the predictions ``pred`` against the readings of data sets
        ``names``, each over its noise scale (:meth:`scale`), concatenated; ``keep[name]``
        (a mask or an index) picks the points of a data set, every point when absent. A
        diverged prediction gives ``inf`` or ``nan``, never a warning.

        >>> d = BundleData(calibration=CalData(np.array([20.0, 60.0, 100.0]),
        ...                                    np.array([20.1, 59.8, 100.3])),
        ...                scales={"calibration": 0.1})
        >>> d.weighted({"calibration": np.array([20.0, 60.0, 100.0])}, ["calibration"],
        ...            {"calibration": np.array([False, True, True])}).round(6).tolist()
        [2.0, -3.0]
        """
        keep = keep or {}
        with np.errstate(over="ignore", invalid="ignore"):
            return np.concatenate([((pred[n] - self.measured(n)) / self.scale(n))
                                   [keep.get(n, slice(None))] for n in names])

    def coordinates(self, name: str) -> list[dict[str, float]]:
        """``at`` of every point of data set ``name``."""
        if name == "pwm":
            return [{"freq_hz": float(f), "duty": float(d)}
                    for f, d in zip(self.pwm.freq_hz, self.pwm.duty, strict=True)]
        if name == "calibration":
            return [{"temp_c": float(t)} for t in self.calibration.temp_c]
        return [{"t_s": float(t)} for t in self.curve(name).t_s]

    @property
    def reference_curve(self) -> CurveData:
        """The lowest-power cooling curve: the one a linear ladder is fitted from (the
        least heated, as the paper measured)."""
        if not self.cooling:
            raise DataFormatError(f"{self.source}: no cooling curve to fit a ladder from")
        return min(self.cooling, key=lambda c: c.power_w)

    @property
    def reference_c(self) -> float:
        """The reference temperature the temperature coefficient is centred on."""
        return self.cooling[0].tref_steady_c if self.cooling else self.ambient_c



def tsp_reading(temp_c: ArrayLike, effect: Effect | None) -> NDArray:
    """What a linear-calibrated TSP reads at true temperature ``temp_c``:
    ``T + q (T − T_cal)² + c (T − T_cal)³`` (``c`` in the cubic form only).

    >>> e = Effect.create("tsp-nonlinearity", "cubic", quad_k_per_k2=1e-3, cub_k_per_k3=1e-5)
    >>> round(float(tsp_reading(35.0, e)), 9)
    35.11
    """
    t = np.asarray(temp_c, dtype=float)
    if effect is None:
        return t
    p = effect.params
    d = t - p["t_cal_c"]
    out = t + p["quad_k_per_k2"] * d ** 2
    if effect.form == "cubic":
        out = out + p["cub_k_per_k3"] * d ** 3
    return out


def tsp_true(read_c: ArrayLike, effect: Effect | None) -> NDArray:
    """Inverse of :func:`tsp_reading` (the root on the calibrated branch; Newton steps from the
    quadratic root for the cubic form)."""
    r = np.asarray(read_c, dtype=float)
    if effect is None:
        return r
    q, tc = effect.params["quad_k_per_k2"], effect.params["t_cal_c"]
    t = r
    if q != 0:
        disc = np.clip(1 + 4 * q * (r - tc), 0.0, None)
        t = tc + 2 * (r - tc) / (1 + np.sqrt(disc))
    c = effect.params["cub_k_per_k3"] if effect.form == "cubic" else 0.0
    if c != 0:
        for _ in range(30):
            d = t - tc
            slope = np.maximum(1 + 2 * q * d + 3 * c * d * d, 0.05)
            step = (t + q * d * d + c * d ** 3 - r) / slope
            t = t - step
            if np.all(np.abs(step) < 1e-12 * (1 + np.abs(t))):
                break
    return t


def transient_offset(t_s: ArrayLike, effect: Effect | None, power_w: float = 0.0) -> NDArray:
    """Reading error (K) of the electrical transient at ``t_s`` after cutting ``power_w``.

    >>> e = Effect.create("electrical-transient", "power", k_per_w=-10.0, masked_s=1e-4)
    >>> round(float(transient_offset(0.0, e, 0.3)), 9)
    -3.0
    """
    t = np.asarray(t_s, dtype=float)
    if effect is None or effect.params["masked_s"] <= 0:
        return np.zeros(t.shape)
    p = effect.params
    amp = p["k_per_w"] * power_w if effect.form == "power" else p["amplitude_k"]
    out = amp * np.exp(-TRANSIENT_RATE * t / p["masked_s"])
    if effect.form == "ringing":
        out = out * np.cos(2 * math.pi * p["ring_hz"] * t)
    return out


def calibrated_reading(temp_c: ArrayLike, effect: Effect | None,
                       line_temps_c: NDArray | None) -> NDArray:
    """What the bench reads at true temperature ``temp_c`` through its linear calibration:
    fitted by least squares to the calibration points at ``line_temps_c`` (the line absorbs
    the straight part of the TSP's nonlinearity, so a curvature cannot pose as a gain), or,
    without calibration points, the tangent at ``t_cal_c`` (:func:`tsp_reading`).

    >>> e = Effect.create("tsp-nonlinearity", quad_k_per_k2=1e-3, t_cal_c=20.0)
    >>> round(float(calibrated_reading(50.0, e, np.array([20.0, 40.0, 60.0, 80.0]))), 4)
    49.5283
    """
    r = tsp_reading(temp_c, effect)
    if effect is None or line_temps_c is None:
        return r
    slope, offset = np.polyfit(line_temps_c, tsp_reading(line_temps_c, effect), 1)
    return (r - offset) / slope


def calibration_reading(temp_c: NDArray, effect: Effect | None) -> NDArray:
    """What the least-squares linear calibration of the points at ``temp_c`` reads there when
    the TSP reads :func:`tsp_reading` through its true tangent: the calibration regresses the
    TSP (here that reading) on ``T`` and inverts the line, which absorbs the straight part of
    the nonlinearity and leaves the bow (``q (u − P u)/(1 + q b_u)`` for the quadratic form).

    >>> t = np.array([20.0, 40.0, 60.0, 80.0])
    >>> e = Effect.create("tsp-nonlinearity", quad_k_per_k2=1e-3, t_cal_c=20.0)
    >>> [round(float(x - y), 4) for x, y in zip(calibration_reading(t, e), t)]
    [0.3774, -0.3774, -0.3774, 0.3774]
    """
    if effect is None:
        return temp_c.copy()
    return calibrated_reading(temp_c, effect, temp_c)
