"""What the bench would read at every point of a bundle: the one forward model.

:func:`predict` composes any set of effects without knowing any of them: the device effects
are terms of the network simulator (:class:`~spicethermal.engines.network.NetworkBatch`), the
measurement effects turn its true junction temperatures into readings, in the order of their
``stage`` (:meth:`~spicethermal.effects.base.MeasurementEffect.read`). Everything is batched:
``B`` parameter sets give ``(B, N)`` predictions per data set.

* cooling curves: the network's steady state at the curve's power, then its cooling at every
  reading (curves that share their times are one batch), plus the reference at each reading;
* steady readings: that steady state;
* the PWM grid: the periodic steady state of each row, read ``delay`` after an on-phase ends
  (the declared sample window by default; a measurement effect may read elsewhere through
  :attr:`~spicethermal.effects.base.Observation.after_off`): the closed form of the network
  frozen at its mean (:meth:`~spicethermal.engines.network.NetworkBatch.frozen_foster`),
  plus the data's correction (:class:`~.measurement.PwmData`) when the batch's device
  effects include those it was computed for;
* the calibration: the thermocouple temperatures (a TSP's law bends them).

Every reading went through the same calibration line, fitted to the calibration's own noisy
points: its error (an offset and a slope) is shared by every reading of every data set.
:func:`line_error` finds the offset and slope that best fit a prediction to all the data sets,
the calibration points included (whose misfit is the line's prior, exactly): the fits profile
these two numbers out of every residual.

>>> import numpy as np
>>> from spicethermal.core.ladder import Foster
>>> from spicethermal.io.bundle import Bundle, PwmTable
>>> d = BundleData.from_bundle(Bundle(ambient_c=25.0,
...                            pwm=PwmTable([1e3], [0.5], [30.0], power_w=0.1)))
>>> round(float(predict_model(d, Foster.from_tau([100.0], [10.0]))["pwm"][0]), 3)
30.0
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..effects.base import (
    CALIBRATION,
    COOLING,
    PWM,
    STEADY,
    MeasurementEffect,
    Observation,
    scalar_params,
)
from ..engines.network import NetworkBatch
from ..engines.pwm import stage_peaks
from ..model import ThermalModel
from .measurement import BundleData, CurveData

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster
    from ..effects import Effect

__all__ = ["EXACT_TOL_K", "MeasurementTerm", "line_error", "observations", "predict",
           "predict_model", "pwm_correction"]

#: The exact periodic state's accepted periodicity error (K): a five-hundredth of the best
#: bench's noise.
EXACT_TOL_K = 1e-5


@dataclass(frozen=True, eq=False)
class MeasurementTerm:
    """One measurement effect of a batch: plugin, form and ``B`` parameter sets ``(B, 1)``."""

    plugin: MeasurementEffect
    form: str
    params: Mapping[str, NDArray]


def _curve_groups(curves: Sequence[CurveData]) -> list[list[CurveData]]:
    """Curves grouped by identical reading times (each group is simulated as one batch)."""
    groups: list[list[CurveData]] = []
    for c in curves:
        for g in groups:
            if g[0].t_s.shape == c.t_s.shape and np.array_equal(g[0].t_s, c.t_s):
                g.append(c)
                break
        else:
            groups.append([c])
    return groups


def _true_cooling(data: BundleData, net: NetworkBatch) -> tuple[dict[str, NDArray],
                                                                  dict[str, NDArray]]:
    """True junction temperatures (°C, ``(B, N)``) of every cooling curve, and the steady
    junction temperature (``(B, 1)``) before each cut."""
    curves, steady = {}, {}
    for group in _curve_groups(data.cooling):
        k = len(group)
        big = net.repeat(k) if k > 1 else net
        power = np.tile([c.power_w for c in group], net.size)[:, None]
        tref = np.tile([c.tref_steady_c for c in group], net.size)[:, None]
        theta0 = big.steady(power, tref)
        rise = big.cooling(power, tref, group[0].t_s, theta0).reshape(net.size, k, -1)
        for j, c in enumerate(group):
            curves[c.name] = c.tref_c[None, :] + rise[:, j]
            steady[c.name] = c.tref_steady_c + theta0.reshape(net.size, k, -1)[:, j, :1]
    return curves, steady


def _after_off(data: BundleData, net: NetworkBatch, rows: NDArray,
               frozen: tuple[NDArray, NDArray] | None = None
               ) -> Callable[[NDArray | float], NDArray]:
    """The PWM rows' true junction temperature ``delay`` after an on-phase ends, for the
    members ``net[rows]`` (``frozen``: their frozen Foster stages, when known)."""
    p = data.pwm
    r, tau = frozen or net.frozen_foster(p.power_w, p.freq_hz, p.duty, p.tref_c)
    r, tau = r[rows], tau[rows]
    peaks = p.power_w[None, :, None] * stage_peaks(r, tau, 1.0 / p.freq_hz[None, :, None],
                                                   p.duty[None, :, None])
    base = p.tref_c[None, :]
    if p.correction_k is not None and p.corrected_for <= net.device_effects:
        base = base + p.correction_k[None, :]

    def after_off(delay: NDArray | float) -> NDArray:
        d = np.asarray(delay, dtype=float)
        d = d[..., None] if d.ndim else d
        return base + np.sum(peaks * np.exp(-d / tau), axis=-1)

    return after_off


def observations(data: BundleData,
                 after_off: Callable[[NDArray | float], NDArray] | None = None
                 ) -> dict[str, Observation]:
    """Every data set of ``data`` as the measurement effects read it."""
    out = {}
    line = data.line_temps_c
    for c in data.cooling:
        out[c.name] = Observation(COOLING, c.t_s, np.full(c.t_s.size, c.power_w), c.tref_c,
                                  line_temps_c=line)
    st = data.steady_curves
    if st:
        out[STEADY] = Observation(STEADY, np.zeros(len(st)),
                                  np.array([c.power_w for c in st]),
                                  np.array([c.tref_steady_c for c in st]), line_temps_c=line)
    if data.pwm is not None:
        p = data.pwm
        out[PWM] = Observation(PWM, p.freq_hz, p.power_w, p.tref_c, p.duty, p.window_s, line,
                               after_off)
    if data.calibration is not None:
        t = data.calibration.temp_c
        out[CALIBRATION] = Observation(CALIBRATION, t, np.zeros(t.size), t)
    return out


def predict(data: BundleData, net: NetworkBatch,
            measures: Sequence[MeasurementTerm] = (),
            pwm_engine: Callable[[NDArray | float], NDArray] | None = None,
            memo: dict | None = None) -> dict[str, NDArray]:
    """What the bench would read (°C, ``(B, N)`` per data set) for every parameter set of
    the batch ``net`` (its ladders and device effects) and ``measures``.

    Parameters
    ----------
    data : BundleData
    net : NetworkBatch
    measures : sequence of MeasurementTerm
        Each with ``B`` parameter sets (or one, broadcast).
    pwm_engine : callable, optional
        The PWM rows' junction temperature ``delay`` after an on-phase ends, from another
        engine (ngspice) instead of the network's closed form.
    memo : dict, optional
        Keeps the last network's simulation of ``data`` between calls (a fit's): when the
        next call's distinct members are the same (a fit that moves only measurement
        effects), they are not simulated again.

    Returns
    -------
    dict of str to ndarray
        Predictions by data set name.
    """
    true: dict[str, NDArray] = {}
    distinct, rows = net.unique()  # members that differ only in measurement effects share one
    curves, steady, frozen = _simulated(data, distinct, pwm_engine is None, memo)
    if data.cooling:
        true.update({k: v[rows] for k, v in curves.items()})
        if data.steady_curves:
            true[STEADY] = np.concatenate([steady[c.name][rows] for c in data.steady_curves],
                                          axis=1)
    after_off = pwm_engine or (_after_off(data, distinct, rows, frozen)
                               if data.pwm is not None else None)
    if after_off is not None:
        true[PWM] = after_off(data.pwm.window_s)
    if data.calibration is not None:
        true[CALIBRATION] = np.broadcast_to(data.calibration.temp_c, (net.size,
                                                                      data.calibration.temp_c.size))
    obs = observations(data, after_off)
    for term in sorted(measures, key=lambda m: m.plugin.stage):
        for name in true:
            true[name] = term.plugin.read(term.form, term.params, obs[name], true[name])
    return true


def _simulated(data: BundleData, net: NetworkBatch, pwm: bool, memo: dict | None
               ) -> tuple[dict[str, NDArray], dict[str, NDArray],
                          tuple[NDArray, NDArray] | None]:
    """``net``'s true cooling curves and steady states (:func:`_true_cooling`) and, when
    ``pwm`` and the bundle has a PWM grid, its frozen Foster stages at every row; from
    ``memo`` when it holds this very network's (its only entry is the last network)."""
    key = None
    if memo is not None:
        key = (net.r.tobytes(), net.c.tobytes(), net.tol_rel, net.tol_k, pwm,
               tuple((t.plugin.name, t.form, tuple((n, np.asarray(v).tobytes())
                                                   for n, v in sorted(t.params.items())))
                     for t in net.terms))
        if key in memo:
            return memo[key]
    curves, steady = _true_cooling(data, net) if data.cooling else ({}, {})
    frozen = None
    if pwm and data.pwm is not None:
        p = data.pwm
        frozen = net.frozen_foster(p.power_w, p.freq_hz, p.duty, p.tref_c)
    if memo is not None:
        memo.clear()
        memo[key] = (curves, steady, frozen)
    return curves, steady, frozen


def predict_model(data: BundleData, ladder: Foster | Cauer,
                  effects: Sequence[Effect] = ()) -> dict[str, NDArray]:
    """:func:`predict` for one model: ``ladder`` and configured ``effects``; ``(N,)`` per
    data set.

    Parameters
    ----------
    data : BundleData
    ladder : Foster or Cauer
    effects : sequence of Effect

    Returns
    -------
    dict of str to ndarray
    """
    net = NetworkBatch.of(ladder, effects)
    measures = [MeasurementTerm(e.plugin, e.form, scalar_params(e))  # type: ignore[arg-type]
                for e in effects if isinstance(e.plugin, MeasurementEffect)]
    return {k: np.asarray(v[0]) for k, v in predict(data, net, measures).items()}


def pwm_correction(data: BundleData, ladder: Foster | Cauer,
                   effects: Sequence[Effect]) -> NDArray | None:
    """What the closed form misses of each PWM reading of the model ``ladder`` with
    ``effects``: the junction's exact periodic state read after the declared window
    (:meth:`~spicethermal.model.ThermalModel.pwm_reading`, shooting) minus the closed form of
    the network frozen at its mean, the quasi-static state that is first order in the
    ripple. Where a device effect changes across the ripple (a strong temperature
    coefficient, a band crossed at a few hertz) they differ by many times a bench's noise.

    Parameters
    ----------
    data : BundleData
    ladder : Foster or Cauer
    effects : sequence of Effect

    Returns
    -------
    ndarray or None
        One correction (K) per row; None without a PWM grid or a device effect (the closed
        form is then exact).

    Raises
    ------
    SimulationError
        When the shooting finds no periodic state.
    """
    model = ThermalModel(ladder, tuple(effects))
    if data.pwm is None or model.is_linear:
        return None
    p = data.pwm
    closed = _after_off(data.with_pwm_correction(None), model.batch(),
                        np.zeros(1, dtype=int))(p.window_s)[0]
    exact = np.array([t + model.pwm_reading(w, f, d, p.window_s, t, EXACT_TOL_K) for w, f, d, t
                      in zip(p.power_w, p.freq_hz, p.duty, p.tref_c, strict=True)])
    return exact - closed


def line_error(pred: NDArray, measured: NDArray, weight: NDArray,
               centre_c: float) -> NDArray:
    """The readings ``pred`` ``(B, N)`` (every data set side by side, the calibration's
    included) corrected for the error of the calibration line they all went through: the
    offset ``a`` and slope ``b`` that minimise ``Σ w² (pred + a + b (pred − centre) −
    measured)²`` for each row (weighted least squares, closed form).

    Parameters
    ----------
    pred, measured, weight : ndarray
        ``(B, N)``, ``(N,)``, ``(N,)``: predictions, readings and ``1/noise``.
    centre_c : float
        Where the slope pivots (the calibration points' mean).

    Returns
    -------
    ndarray
        ``(B, N)``; rows with a non-finite prediction as they were.

    >>> pred = np.array([[20.0, 40.0, 60.0]])
    >>> line_error(pred, np.array([20.1, 40.2, 60.3]), np.ones(3), 40.0).round(6).tolist()
    [[20.1, 40.2, 60.3]]
    """
    r = (pred - measured[None, :]) * weight[None, :]
    u = np.broadcast_to(weight[None, :], pred.shape)
    v = (pred - centre_c) * weight[None, :]
    with np.errstate(all="ignore"):
        a11, a12, a22 = np.sum(u * u, axis=1), np.sum(u * v, axis=1), np.sum(v * v, axis=1)
        b1, b2 = -np.sum(u * r, axis=1), -np.sum(v * r, axis=1)
        det = a11 * a22 - a12 * a12
        off = (a22 * b1 - a12 * b2) / det
        slope = (a11 * b2 - a12 * b1) / det
    ok = np.isfinite(off) & np.isfinite(slope)
    off, slope = np.where(ok, off, 0.0), np.where(ok, slope, 0.0)
    return pred + off[:, None] + slope[:, None] * (pred - centre_c)
