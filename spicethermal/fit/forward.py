"""What the bench would read at every point of a bundle's data sets with the effects in place:
the forward models every effect fit evaluates (:func:`predict`).

Forward models (:func:`predict`), all exact for the catalogue's physics:

* linear ladder: closed forms (``Foster.cooling``, :func:`spicethermal.engines.pwm.steady_state`);
* ``temperature-coefficient``: every form in :mod:`spicethermal.fit.tcforward` (the junction form
  in closed form on a cooling curve and frozen at the self-consistent mean junction
  temperature under PWM, :mod:`spicethermal.fit.tcjunction`; the local forms on the ladder's Cauer
  equivalent, exact steady state, stiff integration after the cut, frozen at every node's mean
  temperature under PWM); its fit is :mod:`spicethermal.fit.tcfit`;
* ``phase-change`` (:mod:`spicethermal.fit.pcforward`) on a cooling curve: the nodal network
  with the band's heat capacity at its node, integrated by LSODA with an exact rank-one
  inverse of the capacity matrix until the node leaves the band, then exact modal steps
  (< 1 mK from the model's Radau integration);
  curves that stay outside the band (:func:`spicethermal.effects.phase_change.band`) use
  the closed form.
  Under PWM the mean is exact (a heat capacity does not change it) and, when the band is
  within reach, the ripple is computed with the capacity frozen at the band's secant over
  the node's swing (:func:`pc_frozen_ladder`, quasi-static), else in closed form. The band's
  shape is the catalogue's own (:meth:`~spicethermal.effects.Effect.extra_capacitance`);
* measurement effects: ``sample-window`` (the PWM reading at the end of the window),
  ``electrical-transient`` (cooling readings off by ``A·e^{−5t/masked_s}``),
  ``tsp-nonlinearity`` (readings ``T + q (T − T_cal)²``; in the calibration data set the
  linear fit absorbs the straight part, leaving ``q (u − P u)/(1 + q b_u)`` with
  ``u = (T − T_cal)²``, ``P`` the projection on straight lines and ``b_u`` the slope of ``u``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.ladder import Cauer, Foster
from ..effects import Effect
from ..engines.pwm import check_drive, stage_peaks, steady_state
from .budget import FROZEN_ROW_S, TC_STEP_S, check_time
from .measurement import (
    BundleData,
    CurveData,
    PwmData,
    calibrated_reading,
    calibration_reading,
    transient_offset,
)
from .pcforward import band_reached, pc_cooling_rise, pc_frozen_ladder
from .tcforward import tc_cooling, tc_frozen
from .tcjunction import as_foster

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["cooling_true_c", "effects_map", "held_share", "integrated", "predict", "pwm_true_c",
           "window_average_k"]


def effects_map(effects: Sequence[Effect]) -> dict[str, Effect]:
    """``effects`` by name."""
    return {e.name: e for e in effects}


def _tc_step() -> None:
    """The budget's check at every right-hand side of an integrated temperature coefficient."""
    check_time(TC_STEP_S)


def cooling_true_c(curve: CurveData, ladder: Foster | Cauer, effects: Sequence[Effect],
                   share: NDArray | None = None) -> NDArray:
    """True junction temperature (°C) along a cooling curve under the device effects (with
    ``share``, the integrated ones' share at each reading, :func:`held_share`, in their
    place)."""
    if share is not None:
        closed = [e for e in effects if not integrated(e)]
        return cooling_true_c(curve, ladder, closed) + share
    fx = effects_map(effects)
    tc, pc = fx.get("temperature-coefficient"), fx.get("phase-change")
    tref = curve.tref_steady_c
    if pc is not None:
        rise = pc_cooling_rise(ladder, pc, tref, curve.power_w, curve.t_s, tc)
    elif tc is not None:
        rise = tc_cooling(ladder, tc, tref, curve.power_w, curve.t_s, _tc_step)
    else:
        rise = curve.power_w * ladder.cooling(curve.t_s)
    return curve.tref_c + rise


def pwm_true_c(data: PwmData, ladder: Foster | Cauer, effects: Sequence[Effect]) -> NDArray:
    """True junction temperature (°C) at the end of the sample window of every PWM row."""
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
            if integrated(tc):
                check_time(FROZEN_ROW_S)
            lad = tc_frozen(ladder, tc, tref, p * d)
        if pc is not None and band_reached(pc, tref, tref + p * as_foster(lad).rth):
            check_time(FROZEN_ROW_S)
            lad = pc_frozen_ladder(lad, pc, tref, p, f, d)
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
    >>> round(window_average_k(lad, 1.0, 1e6, 0.5, 1e-3), 3) == round(5 * (1 - 1 / np.e), 3)
    True
    """
    check_drive(freq_hz, duty, power_w, window_s)
    f = as_foster(ladder)
    r, tau = np.asarray(f.r), np.asarray(f.tau)
    peaks = power_w * stage_peaks(r, tau, 1.0 / freq_hz, duty)
    return float(np.sum(peaks * tau / window_s * -np.expm1(-window_s / tau)))


def integrated(effect: Effect) -> bool:
    """Whether the cooling curves of device effect ``effect`` are integrated (a phase change,
    the local forms of a temperature coefficient) rather than closed forms.

    >>> [integrated(Effect.create("temperature-coefficient", f)) for f in ("local", "junction")]
    [True, False]
    """
    return effect.name == "phase-change" or (effect.name == "temperature-coefficient"
                                             and effect.form != "junction")


def held_share(data: BundleData, ladder: Foster | Cauer,
               held: Sequence[Effect]) -> dict[str, NDArray]:
    """What the integrated device effects ``held`` add to each cooling curve's true
    temperature (K) on ``ladder``, just before the cut (first element) and at every reading:
    the cooling curves of a ladder near ``ladder`` are then its closed form plus this share
    (:func:`joint_fit`'s ``linearise``)."""
    out = {}
    for c in data.cooling:
        at = replace(c, t_s=np.append(0.0, c.t_s), tref_c=np.append(c.tref_steady_c, c.tref_c))
        out[c.name] = cooling_true_c(at, ladder, held) - cooling_true_c(at, ladder, [])
    return out


def predict(data: BundleData, ladder: Foster | Cauer,
            effects: Sequence[Effect] = (),
            share: Mapping[str, NDArray] | None = None) -> dict[str, NDArray]:
    """What the bench would read (°C) at every point of every data set, by data set name
    (with ``share``, :func:`held_share`, in place of the integrated device effects in the
    cooling curves).

    >>> from spicethermal.io.bundle import Bundle, PwmTable
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
        true = cooling_true_c(c, ladder, effects, None if share is None else share[c.name][1:])
        out[c.name] = calibrated_reading(true, tsp, line) + transient_offset(c.t_s, tr,
                                                                              c.power_w)
    if data.pwm is not None:
        out["pwm"] = calibrated_reading(pwm_true_c(data.pwm, ladder, effects), tsp, line)
    if data.calibration is not None:
        out["calibration"] = calibration_reading(data.calibration.temp_c, tsp)
    return out
