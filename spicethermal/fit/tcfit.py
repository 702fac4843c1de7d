"""Fit of the ``temperature-coefficient`` forms to a bundle (the forward models are in
:mod:`spicethermal.fit.tcforward`).

:func:`fit_temperature_coefficient` returns one :class:`~spicethermal.fit.effectfit.EffectFit`
per form tried; :func:`~spicethermal.fit.fitters.fit_effect` keeps the default form
(``junction``) unless another lowers the BIC by more than
:data:`~spicethermal.fit.effectfit.FORM_BIC_MARGIN`. Every fit is bounded and scaled (α in 1/mK,
the capacity slope in 1/mK, the exponent as it is) and starts from two points, the guess
(:func:`guess`) and the linear solution with the effect switched off, so that it never ends
worse than the linear model it extends.

1. ``junction``: α jointly with the ladder at ``T0`` (the reference temperature) from every
   cooling curve (closed-form forward model, cheap).
2. The local forms cost a stiff integration per cooling curve and evaluation; they are tried
   only when the junction form is decisively better than the linear ladder
   (:data:`GATE_BIC`), removes a substantial part of its squared error
   (:data:`GATE_SSE_RATIO`) and does not already reach the noise (when the data sets are
   weighed by their noise, as in the diagnosis): the local forms refine a temperature
   coefficient that the junction form already shows to first order; otherwise the data cannot
   tell the forms apart (and the stiff integrations would cost every bundle seconds). Each is
   fitted with the junction form's ladder held (one or two parameters), then jointly with the
   ladder within
   :data:`JOINT_BUDGET_S` of CPU time: ``local`` (α), ``power-law`` (exponent and capacity
   slope), and the best inner or outer subset of layers (α; the subset is chosen among all of
   them with the ladder held, within :data:`SUBSET_BUDGET_S`).
3. The signature against an error of the heating power (a heater whose power sags as it
   warms, recorded at its nominal value: each cooling curve scaled, its shape unchanged) is
   not tested here: the diagnosis's consistency rule (:mod:`spicethermal.analysis.consistency`)
   tests it for every device effect.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..core.errors import FitError, SimulationError
from ..core.ladder import Foster
from ..effects import Effect
from .effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    TimeLimitError,
    bounded,
    joint_fit,
    sse,
    transient_spans,
    tsp_true,
)
from .tcforward import as_cauer
from .tcjunction import as_foster, tc_steady_scale

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

NAME = "temperature-coefficient"
#: The local forms are fitted only when the junction form lowers the BIC of the linear ladder
#: by more than this (otherwise the data cannot tell the forms apart).
GATE_BIC = 10.0
#: ... and only when it divides the linear ladder's squared error by at least this (an RMS
#: ratio of 1.14, the diagnosis's own bar for an improvement).
GATE_SSE_RATIO = 1.3
#: ... and only while the junction form's weighted χ² is more than this many standard
#: deviations (√(2N)) above the number of points N (not yet at the noise).
GATE_NOISE_SIGMAS = 3.0
#: CPU time (s) allowed to each local form's joint refit with the ladder.
JOINT_BUDGET_S = 1.0
#: CPU time (s) allowed to the search of the layer subset (ladder held).
SUBSET_BUDGET_S = 2.0
#: Evaluations allowed to a fit with the ladder held.
HELD_NFEV = 20
#: The subsets of layers are searched only when the local form over every layer leaves a
#: weighted χ² above this many times the number of points (a residual beyond the noise).
SUBSET_CHI2 = 1.5


def _bic(n: int, err: float, k: int) -> float:
    return n * math.log(max(err, 1e-300) / n) + k * math.log(n)


def guess(data: BundleData, ladder: Foster, base: Sequence[Effect]) -> tuple[float, list, list]:
    """α of the junction form from the apparent Rth of each curve, ``1/Rth(P) = 1/Rth0 − α P``
    (0 from a single power), with the powers and apparent Rths (K/W).

    Parameters
    ----------
    data : BundleData
        The bundle's data sets.
    ladder : Foster
        The linear ladder.
    base : sequence of Effect
        The other effects (a TSP nonlinearity is undone on the steady readings).

    Returns
    -------
    tuple
        ``(alpha_per_k, powers_w, rth_k_per_w)``.
    """
    tsp = next((e for e in base if e.name == "tsp-nonlinearity"), None)
    powers, rths = [], []
    for c in data.cooling:
        top = c.tj_steady_c if c.tj_steady_c is not None else float(c.tj_c[0])
        powers.append(c.power_w)
        rths.append((float(tsp_true(top, tsp)) - c.tref_steady_c) / c.power_w)
    alpha0 = 0.0
    if np.unique(powers).size >= 2:
        slope, _ = np.polyfit(np.array(powers), 1 / np.array(rths), 1)
        alpha0 = float(np.clip(-slope, -0.015, 0.015))
    return alpha0, powers, rths


def local_ratio(ladder: Foster) -> float:
    """``θj / Σ Rᵢ θ̄ᵢ / Rth``: how much hotter the junction runs than the R-weighted mean layer
    temperature in the linear steady state (the factor from a junction α to a local one).

    Parameters
    ----------
    ladder : Foster
        The ladder.

    Returns
    -------
    float
        ≥ 1.

    >>> round(local_ratio(Foster.from_tau([1.0], [1.0])), 6)
    2.0
    """
    r = np.asarray(as_cauer(ladder).r)
    theta = np.append(np.cumsum(r[::-1])[::-1], 0.0)
    mean = 0.5 * (theta[:-1] + theta[1:])
    return float(theta[0] / (r @ mean / r.sum()))


def _effect(form: str, t0: float, **params: float) -> Effect:
    return Effect.create(NAME, form, t0_c=t0, **params)


def fit_temperature_coefficient(data: BundleData, ladder: Foster,
                                effects: Sequence[Effect] = ()) -> list[EffectFit]:
    """Every form of ``temperature-coefficient`` fitted on top of ``ladder`` and ``effects``
    (module docstring).

    Parameters
    ----------
    data : BundleData
        The bundle's data sets (cooling curves needed).
    ladder : Foster
        The linear ladder.
    effects : sequence of Effect
        The effects already in the model.

    Returns
    -------
    list of EffectFit
        The junction form first, then the local forms that were tried.
    """
    if not data.cooling:
        raise FitError("temperature-coefficient needs cooling curves")
    f = as_foster(ladder)
    t0 = data.reference_c
    names = [c.name for c in data.cooling]
    base = [e for e in effects if e.name != NAME]
    alpha0, powers, rths = guess(data, f, base)
    exclude = None if any(e.name == "electrical-transient" for e in base) \
        else transient_spans(data)
    facts = {"powers_w": powers, "rth_k_per_w": rths}

    # 1. junction: two starts, the guess (its ladder rescaled to T0) and the linear solution
    s_mean = float(np.mean([tc_steady_scale(f.rth, alpha0, t0, c.tref_steady_c, c.power_w)
                            for c in data.cooling])) if alpha0 else 1.0
    start = Foster.from_tau(np.asarray(f.r) / s_mean, np.asarray(f.tau) / s_mean)

    def junction(x: NDArray) -> list[Effect]:
        return [*base, _effect("junction", t0, alpha_per_k=float(x[0]) * 1e-3)]

    fits = [joint_fit(data, names, lad0, True, [a0 * 1e3], [-15.0], [15.0], junction,
                      exclude=exclude)
            for lad0, a0 in ([(start, alpha0)] if alpha0 else []) + [(f, 0.0)]]
    lad_j, effs_j, _ = min(fits, key=lambda r: r[2].cost)
    out = [EffectFit(effs_j[-1], lad_j, 1, facts)]

    # 2. the local forms, when the junction form shows an effect at all
    n = max(sum(data.measured(d).size for d in data.datasets), 2)
    err_lin, err_j = sse(data, f, base), sse(data, lad_j, effs_j)
    if _bic(n, err_lin, 0) - _bic(n, err_j, 1) < GATE_BIC or err_lin < GATE_SSE_RATIO * err_j:
        return out
    if data.scales and err_j <= n + GATE_NOISE_SIGMAS * math.sqrt(2.0 * n):  # at the noise
        return out
    alpha_l = float(np.clip(effs_j[-1].params["alpha_per_k"] * local_ratio(lad_j), -0.015,
                            0.015))
    try:
        out += _local_fits(data, names, f, lad_j, base, t0, alpha_l, exclude, facts, err_lin)
    except TimeLimitError:  # the candidate's budget ran out: keep the forms fitted so far
        pass
    return out


def _local_fits(data: BundleData, names: list[str], linear: Foster, lad_j: Foster,
                base: list[Effect], t0: float, alpha_l: float, exclude, facts: dict,
                err_lin: float) -> list[EffectFit]:
    """The local forms in turn: ``local`` (from the junction α scaled by
    :func:`local_ratio`), ``power-law`` (from the local fit, ``n = α (T0 + 273.15)``, no
    capacity slope), and, when a residual beyond the noise remains, the best subset."""
    def local(x: NDArray, **subset: float) -> list[Effect]:
        return [*base, _effect("local", t0, alpha_per_k=float(x[0]) * 1e-3, **subset)]

    def power(x: NDArray) -> list[Effect]:
        return [*base, _effect("power-law", t0, exponent=float(x[0]),
                               c_slope_per_k=float(x[1]) * 1e-3)]

    out = []
    fit = _fit_local(data, names, linear, lad_j, [alpha_l * 1e3], [-15.0], [15.0], local,
                     exclude, err_lin)
    if fit is None:
        return out
    out.append(EffectFit(fit[1][-1], fit[0], 1, facts))
    a_fit = fit[1][-1].params["alpha_per_k"]
    n0 = float(np.clip(a_fit * (t0 + 273.15), -3.9, 5.9))
    fit = _fit_local(data, names, linear, out[0].ladder, [n0, 0.0], [-4.0, -5.0], [6.0, 10.0],
                     power, exclude, err_lin)
    if fit is not None:
        out.append(EffectFit(fit[1][-1], fit[0], 2, facts))
    n_points = sum(data.measured(d).size for d in names)
    if sse(data, out[0].ladder, [*base, out[0].effect]) < SUBSET_CHI2 * n_points:
        return out  # every layer at the noise already: no subset to look for
    subset = _best_subset(data, out[0].ladder, base, t0, a_fit)
    if subset:
        def build(x: NDArray, subset: dict = subset) -> list[Effect]:
            return local(x, **subset)

        fit = _fit_local(data, names, linear, out[0].ladder, [a_fit * 1e3], [-15.0], [15.0],
                         build, exclude, err_lin)
        if fit is not None:
            out.append(EffectFit(fit[1][-1], fit[0], 2, facts))
    return out


def _best_subset(data: BundleData, lad_j: Foster, base: list[Effect], t0: float,
                 alpha_l: float) -> dict[str, float]:
    """The inner or outer subset of layers whose α (ladder held) fits best, within
    :data:`SUBSET_BUDGET_S` (empty when none was fitted)."""
    n = as_cauer(lad_j).order
    subsets = [{"first_layer": float(n - k)} for k in range(1, n)] + \
              [{"last_layer": float(k - 1)} for k in range(1, n)]
    names = [c.name for c in data.cooling]
    best: tuple[float, dict] | None = None

    def search() -> None:
        nonlocal best
        for subset in subsets:
            def build(x: NDArray, subset: dict = subset) -> list[Effect]:
                return [*base, _effect("local", t0, alpha_per_k=float(x[0]) * 1e-3, **subset)]

            try:
                res = joint_fit(data, names, lad_j, False, [alpha_l * 1e3], [-15.0], [15.0],
                                build, max_nfev=HELD_NFEV // 2, tol=1e-4)[2]
            except (FitError, SimulationError, *NUMERICAL_ERRORS):
                continue
            if best is None or res.cost < best[0]:
                best = (res.cost, subset)

    bounded(search, SUBSET_BUDGET_S, None)
    return {} if best is None else best[1]


def _fit_local(data: BundleData, names: list[str], linear: Foster, lad0: Foster,
               x0: list[float], lo: list[float], hi: list[float], build, exclude,
               err_lin: float) -> tuple[Foster, list[Effect]] | None:
    """A local form: its parameters with ``lad0`` held from ``x0`` (and, when that ends worse
    than the linear ladder, from the effect switched off on ``linear``), then jointly with the
    ladder within :data:`JOINT_BUDGET_S`; ``None`` when every start fails."""
    held = []
    for lad, x in ((lad0, x0), (linear, [0.0] * len(x0))):
        try:
            held.append(joint_fit(data, names, lad, False, x, lo, hi, build,
                                  max_nfev=HELD_NFEV, tol=1e-5, exclude=exclude))
        except (FitError, SimulationError, *NUMERICAL_ERRORS):
            continue
        if 2 * held[-1][2].cost < err_lin:
            break
    if not held:
        return None
    lad, effs, res = min(held, key=lambda r: r[2].cost)

    def joint() -> tuple:
        return joint_fit(data, names, lad, True, list(res.x), lo, hi, build, tol=1e-5,
                         exclude=exclude)

    try:
        got = bounded(joint, JOINT_BUDGET_S, None)
    except FitError:
        got = None
    if got is not None and got[2].cost < res.cost:
        return got[0], got[1]
    return lad, effs
