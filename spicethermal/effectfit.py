"""Fitting the catalogued effects to a measurement bundle, with fast exact forward models.

The diagnosis (:mod:`spicethermal.diagnose`) and ``spicethermal fit --effect`` need, for every
candidate effect, its parameters fitted to the data sets that show it, and the model's
predictions of every data point with the effect in place. This module holds the data, the
forward models and the fitting machinery (below).

Data (:class:`BundleData`): each cooling curve (dataset ``cooling_k``, the junction reading at
every ``t_s``), the PWM grid (``pwm``: the reading at the end of the sample window) and the
calibration (``calibration``: the temperature that the least-squares *linear* calibration of
the bundle gives for each calibration voltage, against the thermocouple temperature).

Forward models (:func:`predict`), all exact for the catalogue's physics:

* linear ladder: closed forms (``Foster.cooling``, :func:`spicethermal.pwm.steady_state`);
* ``temperature-coefficient``: every form in :mod:`spicethermal.tcforward` (the junction form
  in closed form on a cooling curve and frozen at the self-consistent mean junction
  temperature under PWM, :mod:`spicethermal.tcjunction`; the local forms on the ladder's Cauer
  equivalent, exact steady state, stiff integration after the cut, frozen at every node's mean
  temperature under PWM); its fit is :mod:`spicethermal.tcfit`;
* ``phase-change`` on a cooling curve: the nodal network with the band's heat capacity at its
  node, integrated by LSODA with an exact rank-one inverse of the capacity matrix until the
  node leaves the band, then exact modal steps (< 1 mK from the model's Radau integration);
  curves that stay outside the band (:func:`spicethermal.effects.phase_change.band`) use
  the closed form.
  Under PWM the mean is exact (a heat capacity does not change it) and, when the band is
  within reach, the ripple is computed with the capacity frozen at the mean temperature
  (:func:`pc_frozen_ladder`, quasi-static), else in closed form. The band's shape is the
  catalogue's own (:meth:`~spicethermal.effects.Effect.extra_capacitance`);
* measurement effects: ``sample-window`` (the PWM reading at the end of the window),
  ``electrical-transient`` (cooling readings off by ``A·e^{−5t/masked_s}``),
  ``tsp-nonlinearity`` (readings ``T + q (T − T_cal)²``; in the calibration data set the
  linear fit absorbs the straight part, leaving ``q (u − P u)/(1 + q b_u)`` with
  ``u = (T − T_cal)²``, ``P`` the projection on straight lines and ``b_u`` the slope of ``u``).

Fits: the ladder (:func:`baseline_ladder`), the robust least squares every fit goes through
(:func:`joint_fit`, :func:`robust_lsq`, within a :func:`time_limit`) and the
``temperature-coefficient`` fit (α jointly with the ladder). The other effects' fits are
in :mod:`spicethermal.pcfit` (``phase-change``) and :mod:`spicethermal.measfit` (the
measurement effects); :mod:`spicethermal.fitters` fits any effect by name and chooses among
its forms.
"""

from __future__ import annotations

import contextvars
import math
import time
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import numpy as np

from .effects import CATALOGUE, Effect, phase_change
from .errors import DataFormatError, FitError, SimulationError
from .ladder import Cauer, Foster
from .tcforward import tc_cooling, tc_frozen
from .tcjunction import as_foster, tc_cooling_rise, tc_steady_scale

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import ArrayLike, NDArray

    from .bundle import Bundle

#: Evaluations allowed to one least-squares fit: a bound on hopeless fits only; fits stop on
#: their tolerance or on the time budget of :func:`time_limit`.
MAX_NFEV = 400
#: Relative tolerance on the cost, the step and the gradient at which a fit stops.
FIT_TOL = 1e-6
#: Tolerances of the phase-change integration (relative, and absolute in K): 0.1 mK on rises
#: of tens of kelvins, below any bench's noise.
PC_RTOL, PC_ATOL_K = 1e-7, 1e-6
#: The baseline ladder's order is searched up to this many stages ...
MAX_BASELINE_ORDER = 6
#: ... and a stage is added only when it lowers the RMS of the joint fit this many times
#: (and that of every curve).
ORDER_GAIN = 1.2
#: Numerical failures that make a trial point of a fit (or a whole candidate) fail.
NUMERICAL_ERRORS = (ArithmeticError, ValueError, np.linalg.LinAlgError)
#: Transient decay: the reading error is ``A·exp(−TRANSIENT_RATE·t/masked_s)`` (as in compare).
TRANSIENT_RATE = 5.0

_DEADLINE: contextvars.ContextVar[float] = contextvars.ContextVar("deadline", default=math.inf)


class TimeLimitError(SimulationError):
    """The time budget of :func:`time_limit` ran out."""


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """A time budget for the fits and integrations run inside the block: past it,
    :func:`check_time` raises :class:`TimeLimitError` (fits then return their best point so far,
    integrations fail). Nested budgets keep the earlier deadline. The clock is the process's
    CPU time (:func:`time.process_time`): a numerical hang is caught the same way on a busy
    machine as on an idle one, and the verdict does not depend on the machine's load.

    >>> with time_limit(0.0):
    ...     check_time()
    Traceback (most recent call last):
    ...
    spicethermal.effectfit.TimeLimitError: time budget exhausted
    """
    deadline = min(_DEADLINE.get(), time.process_time() + seconds)
    token = _DEADLINE.set(deadline)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


@contextmanager
def unlimited() -> Iterator[None]:
    """Lift every :func:`time_limit` inside the block (for the checks that must complete,
    such as comparing a fit with the model it extends)."""
    token = _DEADLINE.set(math.inf)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def bounded(fn: Callable[[], Any], seconds: float, default: Any) -> Any:
    """``fn()`` within ``seconds`` of CPU time, else ``default`` (the enclosing
    :func:`time_limit` still raises when it runs out).

    >>> bounded(lambda: 1 + 1, 1.0, None), bounded(check_time, 0.0, "late")
    (2, 'late')
    """
    outer = _DEADLINE.get()
    try:
        with time_limit(seconds):
            return fn()
    except TimeLimitError:
        if time.process_time() > outer:
            raise
        return default


#: The CPU clock is read at most this often (s of wall time) by :func:`check_time`: between
#: reads the CPU time is bounded by the last reading plus the wall time since (one thread), and
#: the inner loops of the integrations call it tens of thousands of times per fit.
CLOCK_EVERY_S = 2e-3
_CLOCK = [-math.inf, 0.0]  # wall time and CPU time of the last reading


def check_time() -> None:
    """Raise :class:`TimeLimitError` when the current :func:`time_limit` has run out."""
    deadline = _DEADLINE.get()
    if deadline == math.inf:
        return
    wall = time.perf_counter()
    if _CLOCK[1] + (wall - _CLOCK[0]) <= deadline and wall - _CLOCK[0] < CLOCK_EVERY_S:
        return
    _CLOCK[0], _CLOCK[1] = wall, time.process_time()
    if _CLOCK[1] > deadline:
        raise TimeLimitError("time budget exhausted")


# --------------------------------------------------------------------------------------------
# data
# --------------------------------------------------------------------------------------------
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

    >>> from spicethermal.bundle import Bundle, PwmTable
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


# --------------------------------------------------------------------------------------------
# forward models
# --------------------------------------------------------------------------------------------
def _band_reached(effect: Effect, t_lo_c: float, t_hi_c: float) -> bool:
    low, high = phase_change.band(effect)
    return effect.params["latent_j"] > 0 and t_hi_c > low and t_lo_c < high


def pc_cooling_rise(ladder: Foster | Cauer, effect: Effect, tref_c: float, power_w: float,
                    t_s: ArrayLike, tc: Effect | None = None) -> NDArray:
    """Junction rise (K) after ``power_w`` is cut, with the ``phase-change`` heat capacity
    (and, if given, the ``temperature-coefficient`` effect ``tc`` as well).

    The nodal network (the one :class:`~spicethermal.model.ThermalModel` and the SPICE export
    use) with the band's capacity at its node, ``M(θ) dθ/dt = −G θ / s(Tj)``, integrated by
    LSODA with an exact rank-one inverse of ``M`` (agrees with the model's Radau integration
    to < 1 mK, 10× faster); without ``tc`` the network is linear again once the node has left
    the band, and exact modal steps finish the curve; closed form when the curve stays more
    outside the band (:func:`~spicethermal.effects.phase_change.band`; and there is no ``tc``).
    """
    from scipy.integrate import solve_ivp

    from .model import Network

    if tc is not None and tc.form != "junction":
        raise SimulationError(f"phase-change together with temperature-coefficient form "
                              f"{tc.form} has no fast forward model")
    f = as_foster(ladder)
    t = np.asarray(t_s, dtype=float)
    alpha = 0.0 if tc is None else tc.params["alpha_per_k"]
    t0 = 0.0 if tc is None else tc.params["t0_c"]
    s_ss = tc_steady_scale(f.rth, alpha, t0, tref_c, power_w) if tc is not None else 1.0
    rise0 = power_w * f.rth * s_ss
    if not _band_reached(effect, tref_c, tref_c + rise0):
        if tc is not None:
            return tc_cooling_rise(ladder, alpha, t0, tref_c, power_w, t)
        return power_w * f.cooling(t)
    net = Network.of(ladder)
    g = net.conductance()
    cinv = np.linalg.inv(net.capacitance())
    p = effect.params
    node = int(p["node"])
    ce = cinv[:, node]
    b = np.zeros(net.n)
    b[0] = power_w
    theta0 = np.linalg.solve(g, b) * s_ss

    def scale(theta: NDArray) -> float:
        return max(0.05, 1.0 + alpha * (tref_c + float(theta[0]) - t0))

    capacity = CATALOGUE[effect.name].extra_capacitance

    def minv(theta: NDArray, y: NDArray) -> NDArray:
        cx = capacity(effect, node, tref_c + float(theta[node]))
        cy = cinv @ y
        return cy - cx * ce * cy[node] / (1 + cx * ce[node])

    def rhs(_t: float, theta: NDArray) -> NDArray:
        check_time()
        return minv(theta, -g @ theta / scale(theta))

    def jac(_t: float, theta: NDArray) -> NDArray:  # the resistance's own slope left out
        return np.column_stack([minv(theta, -g[:, k] / scale(theta)) for k in range(net.n)])

    t_end = float(t.max()) if t.size else 0.0
    if t_end <= 0:
        return np.full(t.shape, float(theta0[0]))
    order = np.argsort(t)
    below = phase_change.band(effect)[0]

    def left_band(_t: float, theta: NDArray) -> float:
        return tref_c + theta[node] - below

    left_band.terminal = True  # type: ignore[attr-defined]
    left_band.direction = -1  # type: ignore[attr-defined]
    with warnings.catch_warnings():  # a failed integration is reported by sol.success
        warnings.simplefilter("ignore")
        sol = solve_ivp(rhs, (0.0, t_end), theta0, method="LSODA", jac=jac, t_eval=t[order],
                        rtol=PC_RTOL, atol=PC_ATOL_K, first_step=min(f.tau) / 1000,
                        events=left_band if tc is None else None)
    if not sol.success:
        raise SimulationError(f"phase-change cooling integration failed: {sol.message}")
    out = np.empty(t.shape)
    got = np.asarray(sol.y[0]) if len(sol.t) else np.zeros(0)
    out[order[:got.size]] = got
    if got.size < t.size:  # below the band the network is linear again: exact modal steps
        from scipy.linalg import eigh

        t_exit, theta_exit = float(sol.t_events[0][0]), sol.y_events[0][0]
        lam, v = eigh(g, net.capacitance())
        z0 = np.linalg.solve(v, theta_exit)
        rest = t[order[got.size:]] - t_exit
        out[order[got.size:]] = (z0 * np.exp(-lam * rest[:, None])) @ v[0, :]
    return out


def pc_frozen_ladder(ladder: Foster | Cauer, effect: Effect, tref_c: float,
                     mean_power_w: float) -> Foster:
    """The junction's Foster equivalent of the network with the band's heat capacity frozen
    at the node's mean temperature under ``mean_power_w``.

    A heat capacity does not change a periodic state's mean (the enthalpy returns each
    period), only its ripple; this is what the PWM prediction uses when the ripple reaches
    the band (a quasi-static approximation, unlike the cooling curves).
    """
    from scipy.linalg import eigh

    from .model import Network

    net = Network.of(ladder)
    g, cm = net.conductance(), net.capacitance()
    b = np.zeros(net.n)
    b[0] = mean_power_w
    node = int(effect.params["node"])
    cm[node, node] += effect.extra_capacitance(node, tref_c + float(np.linalg.solve(g, b)[node]))
    lam, v = eigh(g, cm)
    return Foster.from_tau(v[0, :] ** 2 / lam, 1 / lam)


def effects_map(effects: Sequence[Effect]) -> dict[str, Effect]:
    """``effects`` by name."""
    return {e.name: e for e in effects}




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


def cooling_true_c(curve: CurveData, ladder: Foster | Cauer,
                   effects: Sequence[Effect]) -> NDArray:
    """True junction temperature (°C) along a cooling curve under the device effects."""
    fx = effects_map(effects)
    tc, pc = fx.get("temperature-coefficient"), fx.get("phase-change")
    tref = curve.tref_steady_c
    if pc is not None:
        rise = pc_cooling_rise(ladder, pc, tref, curve.power_w, curve.t_s, tc)
    elif tc is not None:
        rise = tc_cooling(ladder, tc, tref, curve.power_w, curve.t_s, check_time)
    else:
        rise = curve.power_w * ladder.cooling(curve.t_s)
    return curve.tref_c + rise


def pwm_true_c(data: PwmData, ladder: Foster | Cauer, effects: Sequence[Effect]) -> NDArray:
    """True junction temperature (°C) at the end of the sample window of every PWM row."""
    from .pwm import steady_state

    fx = effects_map(effects)
    tc, pc, sw = (fx.get(n) for n in ("temperature-coefficient", "phase-change",
                                      "sample-window"))
    window = float(sw.params["window_s"]) if sw is not None else data.window_s
    average = sw is not None and sw.form == "average" and window > 0
    out = np.empty(data.freq_hz.size)
    for i, (f, d, p, tref) in enumerate(zip(data.freq_hz, data.duty, data.power_w, data.tref_c,
                                            strict=True)):
        lad: Foster | Cauer = ladder
        if tc is not None:
            lad = tc_frozen(ladder, tc, tref, p * d)
        if pc is not None and _band_reached(pc, tref, tref + p * as_foster(lad).rth):
            lad = pc_frozen_ladder(lad, pc, tref, p * d)
        if average:
            out[i] = tref + window_average_k(lad, p, f, d, window)
        else:
            out[i] = tref + steady_state(lad, p, f, d, window).reading_k
    return out


def window_average_k(ladder: Foster | Cauer, power_w: float, freq_hz: float, duty: float,
                     window_s: float) -> float:
    """Mean junction rise (K) over a power-off window of ``window_s`` that starts when an
    on-phase of the periodic steady state ends: each Foster stage starts at its peak ``pᵢ``
    and decays, so the mean is ``Σ pᵢ τᵢ/w (1 − e^{−w/τᵢ})``.

    >>> lad = Foster.from_tau([10.0], [1e-3])
    >>> round(window_average_k(lad, 1.0, 1e6, 0.5, 1e-3), 3) == round(5 * (1 - math.exp(-1)), 3)
    True
    """
    from .pwm import steady_state

    f = as_foster(ladder)
    total = 0.0
    for r, tau in zip(f.r, f.tau, strict=True):
        peak = steady_state(Foster.from_tau([r], [tau]), power_w, freq_hz, duty).peak_k
        total += peak * tau / window_s * -math.expm1(-window_s / tau)
    return total


def predict(data: BundleData, ladder: Foster | Cauer,
            effects: Sequence[Effect] = ()) -> dict[str, NDArray]:
    """What the bench would read (°C) at every point of every data set, by data set name.

    >>> from spicethermal.bundle import Bundle, PwmTable
    >>> d = BundleData.from_bundle(Bundle(ambient_c=25.0,
    ...                            pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1)))
    >>> round(float(predict(d, Foster.from_tau([100.0], [10.0]))["pwm"][0]), 3)
    30.0
    """
    fx = effects_map(effects)
    tsp, tr = fx.get("tsp-nonlinearity"), fx.get("electrical-transient")
    out: dict[str, NDArray] = {}
    line = data.line_temps_c
    for c in data.cooling:
        out[c.name] = calibrated_reading(cooling_true_c(c, ladder, effects), tsp, line) + \
            transient_offset(c.t_s, tr, c.power_w)
    if data.pwm is not None:
        out["pwm"] = calibrated_reading(pwm_true_c(data.pwm, ladder, effects), tsp, line)
    if data.calibration is not None:
        out["calibration"] = calibration_reading(data.calibration.temp_c, tsp)
    return out


# --------------------------------------------------------------------------------------------
# the ladder
# --------------------------------------------------------------------------------------------
def reference_ladder(data: BundleData, order: int | str = "auto",
                     correct: Callable[[CurveData], tuple[NDArray, float | None]] | None = None,
                     mask_s: float | str | None = "auto") -> Foster:
    """A linear ladder fitted (:func:`~spicethermal.fit.fit_foster`, ΣR = Rth held) to the
    Zth of the reference (lowest-power) cooling curve, as ``spicethermal fit`` does, optionally
    corrected first by ``correct(curve) -> (tj_c, tj_steady_c)`` (an inverse measurement
    model). The electrical transient is masked and extrapolated by √t (``mask_s``, see
    :meth:`~spicethermal.curves.ZthCurve.from_cooling`)."""
    from .curves import ZthCurve
    from .fit import fit_foster

    c = data.reference_curve
    tj, steady = (c.tj_c, c.tj_steady_c) if correct is None else correct(c)
    curve = ZthCurve.from_cooling(c.t_s, tj, c.power_w, steady,
                                  c.tref_c if c.has_tref_column else None, c.tref_steady_c,
                                  mask_s=mask_s, label=c.name)
    return fit_foster(curve.t_s, curve.zth_k_per_w, order=order,
                      rth_k_per_w=curve.rth_k_per_w).foster


def transient_spans(data: BundleData) -> dict[str, float]:
    """Per cooling curve, the span (s) the electrical transient corrupts, as detected by
    :func:`~spicethermal.curves.detect_transient` (0 when none is seen)."""
    from .curves import detect_transient

    return {c.name: detect_transient(c.t_s, c.tj_c) for c in data.cooling}


def baseline_ladder(data: BundleData, order: int | str = "auto") -> Foster:
    """The linear ladder the diagnosis starts from: :func:`reference_ladder` (order chosen by
    BIC on the lowest-power curve), then refitted jointly to every cooling curve's readings
    outside their detected transients, so that the effects are compared with the best linear
    model of all the curves rather than of one. With ``order="auto"`` one and two more stages
    are tried too, and the joint fit with the lowest BIC is kept (one sparse, noisy curve
    can hide a stage that all of them show).

    >>> from spicethermal.scenarios import scenario_bundle
    >>> lad = baseline_ladder(BundleData.from_bundle(scenario_bundle("clean", seed=0)))
    >>> lad.order, round(lad.rth)
    (4, 146)
    """
    ladder = reference_ladder(data, order)
    if len(data.cooling) < 2:
        return ladder
    names = [c.name for c in data.cooling]
    spans = transient_spans(data)
    orders = [ladder.order]
    if order == "auto":
        orders += [m for m in (ladder.order + 1, ladder.order + 2) if m <= MAX_BASELINE_ORDER]
    best = None
    for m in orders:
        try:
            start = ladder if m == ladder.order else reference_ladder(data, m)
            lad, _, res = joint_fit(data, names, start, True, [], [], [], lambda x: [],
                                    exclude=spans)
        except (FitError, DataFormatError, SimulationError, *NUMERICAL_ERRORS):
            continue
        n = max(res.fun.size, 2)
        bic = n * math.log(max(2 * res.cost, 1e-300) / n) + 2 * m * math.log(n)
        pred = predict(subset(data, names), lad)
        per_curve = [float(np.sum(((pred[c.name] - c.tj_c)[c.t_s >= spans.get(c.name, 0.0)])
                                  ** 2)) for c in data.cooling]
        # more stages only for a ladder that is plainly too short: every curve fits better
        # and the RMS falls ORDER_GAIN× (a slow extra stage that one curve's drift asks for
        # would otherwise hide what the diagnosis must see)
        if best is None or (bic < best[0] and res.cost < best[2] / ORDER_GAIN ** 2
                            and all(a <= b for a, b in zip(per_curve, best[3], strict=True))):
            best = (bic, lad, res.cost, per_curve)
    if best is None:
        raise FitError(f"{data.source}: no linear ladder fits the cooling curves")
    return best[1]


# --------------------------------------------------------------------------------------------
# fits
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class EffectFit:
    """One fitted effect: the effect, the ladder that goes with it, how many effect
    parameters were fitted, and facts for the evidence sentence."""

    effect: Effect
    ladder: Foster
    n_params: int
    facts: Mapping[str, Any] = field(default_factory=dict)


def subset(data: BundleData, names: Sequence[str]) -> BundleData:
    """The data sets ``names`` of ``data`` only."""
    return BundleData(tuple(c for c in data.cooling if c.name in names),
                      data.pwm if "pwm" in names else None,
                      data.calibration if "calibration" in names else None,
                      data.ambient_c, data.source, data.scales, data.line_temps_c)




def robust_lsq(fun: Callable[[NDArray], NDArray], x0: Sequence[float], lo: Sequence[float],
               hi: Sequence[float], **kw: Any) -> Any:
    """:func:`scipy.optimize.least_squares` made robust: a trial point whose forward model
    fails numerically (overflow, no convergence, a :class:`~spicethermal.errors.SimulationError`)
    gets a large residual; past the :func:`time_limit` the best point so far is returned (its
    ``status`` is ``-9``). Raises :class:`~spicethermal.errors.FitError` when the start fails."""
    from scipy.optimize import least_squares

    lo_a, hi_a = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    x0 = np.asarray(x0, dtype=float)
    pad = 1e-9 * np.maximum(1.0, np.abs(x0))
    x0 = np.clip(x0, lo_a + pad, hi_a - pad)
    best = SimpleNamespace(x=x0, cost=math.inf, fun=None, status=-9, nfev=0)

    def evaluate(x: NDArray) -> NDArray:
        check_time()
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            return np.asarray(fun(x), dtype=float)

    try:
        r0 = evaluate(x0)
    except (SimulationError, DataFormatError, *NUMERICAL_ERRORS) as exc:
        raise FitError(f"the forward model fails at the start point: {exc}") from None
    if not np.all(np.isfinite(r0)):
        raise FitError("the forward model is not finite at the start point")
    size = r0.size

    def safe(x: NDArray) -> NDArray:
        try:
            r = evaluate(x)
        except TimeLimitError:
            raise
        except (SimulationError, DataFormatError, *NUMERICAL_ERRORS):
            return np.full(size, 1e6)
        if not np.all(np.abs(r) < 1e6):
            return np.full(size, 1e6)
        cost = 0.5 * float(r @ r)
        best.nfev += 1
        if cost < best.cost:
            best.x, best.cost, best.fun = np.array(x), cost, r
        return r

    kw.setdefault("max_nfev", MAX_NFEV)
    kw.setdefault("x_scale", "jac")
    for key in ("ftol", "xtol", "gtol"):
        kw.setdefault(key, FIT_TOL)
    try:
        return least_squares(safe, x0, bounds=(lo_a, hi_a), **kw)
    except TimeLimitError:
        if best.fun is None:
            raise
        return best


def joint_fit(data: BundleData, names: Sequence[str], ladder: Foster | Cauer,
              fit_ladder: bool, x0: Sequence[float], lo: Sequence[float], hi: Sequence[float],
              build: Callable[[NDArray], list[Effect]], *,
              exclude: Mapping[str, float] | None = None,
              keep_before: Mapping[str, float] | None = None,
              max_nfev: int | None = None,
              diff_step: float | None = None,
              tol: float = FIT_TOL) -> tuple[Foster, list[Effect], Any]:
    """Least squares of the readings of data sets ``names`` over the effect parameters
    ``x`` (``build(x)`` gives the effects) and, if ``fit_ladder``, the ladder's
    ``log R`` and ``log τ`` (same order). Cooling points before ``exclude[name]`` s are left
    out, and so are those at or after ``keep_before[name]`` s. When the ladder is fitted,
    each curve's steady reading just before the cut is a data
    point too (it pins Rth). ``diff_step`` is the relative finite-difference step (larger than
    the default for forward models solved by an adaptive integrator). Returns the ladder, the
    effects and scipy's result."""
    f = as_foster(ladder)
    m = f.order if fit_ladder else 0
    sub = subset(data, names)
    keep = {n: ((sub.curve(n).t_s >= (exclude or {}).get(n, 0.0))
                & (sub.curve(n).t_s < (keep_before or {}).get(n, math.inf)))
            if n.startswith("cooling") else slice(None) for n in names}
    meas = {n: data.measured(n)[keep[n]] for n in names}

    def split(x: NDArray) -> tuple[Foster, NDArray]:
        if not m:
            return f, x
        return Foster.from_tau(np.exp(x[:m]), np.exp(x[m:2 * m])), x[2 * m:]

    steady = [c for c in sub.cooling if c.tj_steady_c is not None] if m else []

    def fun(x: NDArray) -> NDArray:
        lad, xe = split(x)
        effects = build(xe)
        pred = predict(sub, lad, effects)
        parts = [(pred[n][keep[n]] - meas[n]) / data.scale(n) for n in names]
        tsp = effects_map(effects).get("tsp-nonlinearity")
        for c in steady:  # the reading just before the cut pins the ladder's Rth
            top = replace(c, t_s=np.zeros(1), tref_c=np.full(1, c.tref_steady_c))
            parts.append((calibrated_reading(cooling_true_c(top, lad, effects), tsp,
                                             data.line_temps_c) - c.tj_steady_c)
                         / data.scale(c.name))
        return np.concatenate(parts)

    start = np.concatenate([np.log(f.r), np.log(f.tau)]) if m else np.zeros(0)
    big = np.full(2 * m, np.inf)
    res = robust_lsq(fun, np.concatenate([start, np.asarray(x0, float)]),
               np.concatenate([-big, np.asarray(lo, float)]),
               np.concatenate([big, np.asarray(hi, float)]),
               **({"max_nfev": max_nfev} if max_nfev else {}), diff_step=diff_step,
               ftol=tol, xtol=tol, gtol=tol)
    lad, xe = split(res.x)
    return lad, build(xe), res


def others(effects: Sequence[Effect], name: str) -> list[Effect]:
    """``effects`` without effect ``name``."""
    return [e for e in effects if e.name != name]




def needs(name: str, data: BundleData) -> str:
    """Why effect ``name`` cannot be fitted to ``data`` ("" when it can)."""
    if name == "sample-window" and data.pwm is None:
        return "no PWM data set"
    if name in ("temperature-coefficient", "phase-change", "electrical-transient") \
            and not data.cooling:
        return "no cooling curve"
    return ""


def switched_off(name: str, form: str, data: BundleData) -> Effect:
    """Effect ``name`` at its neutral parameters (no latent heat, no α, no error; the declared
    sample window): what a nested model reduces to.

    >>> switched_off("temperature-coefficient", "junction", BundleData()).params["alpha_per_k"]
    0.0
    """
    if name == "sample-window":
        return Effect.create(name, form, window_s=data.pwm.window_s if data.pwm else 0.0)
    return Effect.create(name, form)


def sse(data: BundleData, ladder: Foster | Cauer, effects: Sequence[Effect]) -> float:
    """Sum of squared residuals over every point of every data set, each data set's divided
    by its noise scale squared (K² when no scale is set)."""
    pred = predict(data, ladder, effects)
    with np.errstate(over="ignore", invalid="ignore"):  # a wild trial point: inf, not a warning
        return float(sum(np.sum((pred[n] - data.measured(n)) ** 2) / data.scale(n) ** 2
                         for n in data.datasets))
