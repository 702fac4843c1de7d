"""Fitting the measurement effects: ``sample-window``, ``electrical-transient`` and
``tsp-nonlinearity`` (their forward models are the measurement model of
:mod:`spicethermal.fit.effectfit`).

Each fit returns one :class:`~spicethermal.fit.effectfit.EffectFit` per form it tried; the choice
among forms and the nested-model guarantee are :mod:`spicethermal.fit.fitters`'. The ladder is
held for ``sample-window`` (cooling curves are not affected) and refitted jointly for the
other two (the readings the ladder was fitted from carry the artefact).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import FitError
from ..effects import CATALOGUE, Effect
from .effectfit import (
    BundleData,
    EffectFit,
    effects_map,
    joint_fit,
    others,
    predict,
    subset,
    transient_spans,
)

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..core.ladder import Cauer, Foster

__all__ = ["fit_electrical_transient", "fit_sample_window", "fit_tsp_nonlinearity"]

#: Evaluations allowed to each start of the transient's fit on the early points (ladder held;
#: 2-3 parameters): the starts are many, a start that has not converged by then is a poor one.
HELD_NFEV = 60
#: The longest span (s) an electrical transient may mask: the sense current and the device's
#: capacitances settle within microseconds to about a millisecond after the cut (JESD51-14
#: masks 10–100 µs for discrete packages). A "transient" fitted over tens of milliseconds is a
#: thermal misfit of the first layers (a temperature coefficient of the die or the solder).
LONGEST_TRANSIENT_S = 3e-3
#: A calibration with at least this many points beyond its line (2) and the form's parameters
#: fixes the TSP's nonlinearity by itself (a residual scatter can then be told from a bow).
CAL_SPARE = 3
#: Bounds of the TSP's curvature: its quadratic and its cubic term each bend the reading by at
#: most this fraction of the span of temperatures the fit may reach (the readings ± 50 K). At
#: 0.2 a diode's cubic of −1.9e-5 K/K³ over 25-80 °C was held at −8e-6 and left its
#: calibration at 10× the noise (seed 41's draw 021 of the random validation set).
BOW = 1.0


def fit_sample_window(data: BundleData, ladder: Foster | Cauer,
                      effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """``window_s`` from the PWM readings, ladder held (cooling curves are not affected), for
    each form (reading at the end of the window, averaged over it); three starts each."""
    if data.pwm is None:
        raise FitError("sample-window needs a PWM data set")
    base = others(effects, "sample-window")
    hi_us = 1e6 * min(1.0, 20.0 / float(np.min(data.pwm.freq_hz)))
    out = []
    for form in CATALOGUE["sample-window"].forms:
        def build(x: NDArray, form: str = form) -> list[Effect]:
            return [*base, Effect.create("sample-window", form, window_s=float(x[0]) * 1e-6)]

        best = None
        for s in (10.0, 100.0, 1000.0):
            if s < hi_us:
                r = joint_fit(data, ["pwm"], ladder, False, [s], [0.0], [hi_us], build)
                if best is None or r[2].cost < best[2].cost:
                    best = r
        lad, effs, _ = best
        out.append(EffectFit(effs[-1], lad, 1, {"declared_s": data.pwm.window_s}))
    return out


def fit_electrical_transient(data: BundleData, ladder: Foster | Cauer,
                             effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """Each form of the transient: its parameters first on the early points of every cooling
    curve with the ladder held (a multi-start), then jointly with the ladder from every point
    of every cooling curve (the early ones included) and, for the power form (and the fixed
    one when every curve was cut from one power), from every data set. The artefact is in
    the cooling readings only: the steady readings and the PWM grid see the true ladder, and
    they are what tells a transient proportional to the power cut off from a fast stage of
    the ladder, which shapes every curve alike (a fixed error over curves of several powers,
    or a ringing, cannot pass for one)."""
    if not data.cooling:
        raise FitError("electrical-transient needs cooling curves")
    names = [c.name for c in data.cooling]
    base = others(effects, "electrical-transient")
    first = min(float(c.t_s[0]) for c in data.cooling)
    pred = predict(subset(data, names), ladder, base)
    amp0 = float(np.mean([data.measured(n)[0] - pred[n][0] for n in names]))
    per_w0 = float(np.mean([(data.measured(c.name)[0] - pred[c.name][0]) / c.power_w
                            for c in data.cooling]))
    spans = [s for s in transient_spans(data).values() if s > 0]
    span0 = max(float(np.median(spans)) if spans else 1e-4, 10 * first)
    lspan = math.log10(span0)
    lo_s = math.log10(first) - 1
    hi_s = max(math.log10(LONGEST_TRANSIENT_S), lo_s + 1)
    forms = {  # form: (starts, lower, upper, parameters from x)
        "fixed": ([[amp0, lspan]], [-1e3, lo_s], [1e3, hi_s],
                  lambda x: {"amplitude_k": x[0], "masked_s": 10 ** x[1]}),
        "power": ([[per_w0, lspan]], [-1e4, lo_s], [1e4, hi_s],
                  lambda x: {"k_per_w": x[0], "masked_s": 10 ** x[1]}),
        "ringing": ([[amp0, ls, lf] for ls in (lspan, lspan + 0.5)
                     for lf in (-0.3, 0.3, 0.9, 1.5)],
                    [-1e3, lo_s, -1.0], [1e3, hi_s, 1.5],
                    lambda x: {"amplitude_k": x[0], "masked_s": 10 ** x[1],
                               "ring_hz": 10 ** (x[2] - x[1])}),
    }
    early = {n: 10 * span0 for n in names}
    n_early = sum(int(np.sum(c.t_s < early[c.name])) for c in data.cooling)
    # the held fits see the early points only: the curves cut there (the forward models of
    # the device effects then integrate only that far)
    head = replace(data, cooling=tuple(
        replace(c, t_s=c.t_s[k], tj_c=c.tj_c[k], tref_c=c.tref_c[k])
        for c in data.cooling for k in [c.t_s < early[c.name]] if np.any(k)))
    if not head.cooling:
        raise FitError("electrical-transient: no reading within the early span")
    early_names = [c.name for c in head.cooling]
    held = {}
    for form, (starts, lo, hi, params) in forms.items():
        def build(x: NDArray, form: str = form, params=params) -> list[Effect]:
            return [*base, Effect.create("electrical-transient", form,
                                         **{k: float(v) for k, v in params(x).items()})]

        res = min((joint_fit(head, early_names, ladder, False, np.clip(x0, lo, hi), lo, hi,
                             build, max_nfev=HELD_NFEV)[2] for x0 in starts),
                  key=lambda r: r.cost)
        held[form] = (2 * res.cost + len(lo) * math.log(max(n_early, 2)), res.x, build)
    # the ladder is refitted with the default form, with the best other form when the early
    # points prefer it decisively, and then (last, the first to lose its budget) with the
    # power form when the curves' powers differ: the held ladder has taken that as a fast
    # stage of its own, and may show it to the early points as a ringing; only the refitted
    # ladder tells them apart
    one_power = len({c.power_w for c in data.cooling}) == 1
    refine = ["fixed"]
    best = min(held, key=lambda k: held[k][0])
    if best != "fixed" and held[best][0] < held["fixed"][0] - 10:
        refine.append(best)
    if "power" not in refine and not one_power:
        refine.append("power")
    out = []
    for form in refine:
        _, x0, build = held[form]
        lo, hi = forms[form][1], forms[form][2]
        # a form that can pass for a fast stage (the power form; with one power, the fixed
        # one too) is refitted on every data set. The linear ladder may have taken it as a
        # fast stage of its own, and then the held fit's error has any sign and span (seed
        # 5's draw 011: +0.0047 K/W over 15 µs for a truth of -0.0038 K/W over 260 µs): on
        # the linear ladder alone its refit also starts from no error at spans a decade
        # either side (on top of other effects their ladder was refitted with them, and each
        # start costs their forward models)
        fast = form == "power" or (form == "fixed" and one_power)
        starts = [list(x0)] + [[0.0, s, *x0[2:]] for s in (x0[1] - 1, x0[1] + 1)
                               if not base and fast and lo[1] <= s <= hi[1]]
        on = list(data.datasets) if fast else names
        lad, effs, _ = min((joint_fit(data, on, ladder, True, x, lo, hi, build,
                                      linearise=True) for x in starts),
                           key=lambda r: r[2].cost)
        out.append(EffectFit(effs[-1], lad, len(lo), {}))
    return out


def fit_tsp_nonlinearity(data: BundleData, ladder: Foster | Cauer,
                         effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """``q`` and ``t_cal_c`` (and, in the cubic form, ``c``) of the TSP, and the ladder.

    The nonlinearity belongs to the sensor, and the calibration measures it directly: when the
    calibration has enough points (:data:`CAL_SPARE` beyond its line and the form's
    parameters), the form's parameters are fitted to the calibration alone and the ladder is
    then refitted to the readings of the curves through them, so that another effect's
    signature in the curves (a temperature coefficient, a phase change) cannot bend the
    sensor's curvature. With a sparse calibration (or none) they are fitted jointly with the
    ladder to every data set: the calibration residuals fix the curvature, the readings of the
    curves and the PWM grid ``t_cal_c``. The cubic form starts from the quadratic fit."""
    names = list(data.datasets)
    if not names:
        raise FitError("tsp-nonlinearity needs data")
    base = others(effects, "tsp-nonlinearity")
    tcal0 = data.reference_c
    q0 = 0.0
    n_cal = 0
    if data.calibration is not None:
        basis, _ = data.calibration.curvature_basis(tcal0)
        resid = data.calibration.read_c - data.calibration.temp_c
        q0 = float(basis @ resid / max(float(basis @ basis), 1e-300))
        n_cal = int(data.calibration.temp_c.size)
    temps = np.concatenate([data.measured(n) for n in names])
    lo_t, hi_t = float(np.min(temps)) - 50, float(np.max(temps)) + 50
    qmax = 1e4 * BOW / max(hi_t - lo_t, 1.0)
    cmax = 1e6 * BOW / max(hi_t - lo_t, 1.0) ** 2
    exclude = transient_spans(data) if "electrical-transient" not in effects_map(base) \
        else None
    fit_ladder = bool(data.cooling)

    def build(x: NDArray) -> list[Effect]:
        cubic = {"cub_k_per_k3": float(x[2]) * 1e-6} if len(x) > 2 else {}
        return [*base, Effect.create("tsp-nonlinearity", "cubic" if cubic else "quadratic",
                                     quad_k_per_k2=float(x[0]) * 1e-4, t_cal_c=float(x[1]),
                                     **cubic)]

    def fit(x0: list[float], lo: list[float], hi: list[float],
            lad: Foster | Cauer) -> tuple[Foster | Cauer, list[Effect]]:
        if n_cal < 2 + len(x0) + CAL_SPARE:
            new_lad, effs, _ = joint_fit(data, names, lad, fit_ladder, x0, lo, hi, build,
                                         exclude=exclude, linearise=True)
            return new_lad, effs
        # the calibration fixes the bow: the coefficients of T² (q − 3 c T_cal) and T³ (c)
        _, effs, _ = joint_fit(data, ["calibration"], lad, False, x0, lo, hi, build)
        rest = [n for n in names if n != "calibration"]
        if not rest:
            return lad, effs
        p = effs[-1].params
        cub = p["cub_k_per_k3"] * 1e6 if len(x0) > 2 else 0.0
        a2 = p["quad_k_per_k2"] * 1e4 - 3e-2 * cub * p["t_cal_c"]

        def on_bow(x: NDArray) -> list[Effect]:  # the curves place T_cal on that bow
            return build(np.array([a2 + 3e-2 * cub * x[0], x[0], cub][:len(x0)]))

        new_lad, effs, _ = joint_fit(data, rest, lad, fit_ladder, [p["t_cal_c"]], [lo_t],
                                     [hi_t], on_bow, exclude=exclude, linearise=True)
        return new_lad, effs

    x0 = [float(np.clip(q0 * 1e4, -0.99 * qmax, 0.99 * qmax)), tcal0]
    lad, effs = fit(x0, [-qmax, lo_t], [qmax, hi_t], ladder)
    out = [EffectFit(effs[-1], lad, 2, {})]
    q = effs[-1].params
    x1 = [q["quad_k_per_k2"] * 1e4, q["t_cal_c"], 0.0]
    lad3, effs3 = fit(x1, [-qmax, lo_t, -cmax], [qmax, hi_t, cmax], lad)
    out.append(EffectFit(effs3[-1], lad3, 3, {}))
    return out
