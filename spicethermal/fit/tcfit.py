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
   weighed by their noise, as in the diagnosis). With other effects in the model, the first
   two are judged on the cooling curves, which every form is fitted to: the other data sets
   are read through those effects, fitted without the coefficient. On top of a sample window
   so fitted, the junction form took two curves of a diode from χ² 13 500 to 190 while the
   window, held, misread the PWM grid with it, so the whole bundle's error rose and the local
   forms (χ² 30 on the curves, at the truth's α) were never tried (seed 5's draw 000 of the
   random validation set). The local forms refine a temperature
   coefficient that the junction form already shows to first order; otherwise the data cannot
   tell the forms apart (and the stiff integrations would cost every bundle seconds). Each is
   fitted with the junction form's ladder held (one or two parameters), then jointly with the
   ladder within :data:`JOINT_BUDGET_S` of work: ``local`` (α; within
   :data:`JOINT_ITERATIONS` iterations' worth when that is more, for the other forms start from
   its ladder), ``power-law`` (exponent and capacity slope), and the best inner or outer
   subset of layers (α; the subset is chosen among all of them within
   :data:`SUBSET_BUDGET_S`, each with the linear ladder brought back to ``T0`` for its α,
   :func:`_best_subset`, and refitted with the ladder within :data:`SUBSET_JOINT_BUDGET_S`).
   When the candidate's budget runs out, the forms fitted so far stand.
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
from scipy.optimize import minimize_scalar

from ..core.errors import FitError, SimulationError
from ..core.ladder import Cauer, Foster
from ..effects import Effect
from .budget import spent
from .effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    TimeLimitError,
    bounded,
    joint_fit,
    predict,
    sse,
    subset,
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
#: Work (s, :mod:`.budget`) allowed to each local form's joint refit with the ladder ...
JOINT_BUDGET_S = 1.0
#: ... or this many iterations' worth, when that is more (three cooling curves of a diode
#: heated by 60 K need about five; one iteration is a Jacobian over every stage, a second of
#: work there, and a refit cut within its first iteration never moves the ladder).
JOINT_ITERATIONS = 5
#: Work (s, :mod:`.budget`) allowed to the search of the layer subset (ladder held).
SUBSET_BUDGET_S = 2.0
#: ... and to the joint refit of the best subset's α with the ladder (from the screening's
#: ladder at ``T0``, it needs a few more iterations than the other forms).
SUBSET_JOINT_BUDGET_S = 3.0
#: Subsets refined by a scalar search over α after the linearised screening, and the
#: evaluations of each search (:func:`_best_subset`).
SUBSET_REFINED = 2
SUBSET_EVALS = 10
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

    # 2. the local forms, when the junction form shows an effect at all: on every data set, or
    # with effects found before held, on the curves it was fitted to (those effects, fitted
    # without it, may misread the other data sets with it)
    def errors(sets: BundleData) -> tuple[int, float, float]:  # points, linear, junction
        return (max(sum(sets.measured(d).size for d in sets.datasets), 2), sse(sets, f, base),
                sse(sets, lad_j, effs_j))

    n_g, lin_g, j_g = errors(subset(data, names) if base else data)
    if _bic(n_g, lin_g, 0) - _bic(n_g, j_g, 1) < GATE_BIC or lin_g < GATE_SSE_RATIO * j_g:
        return out
    n, err_lin, err_j = errors(data) if base else (n_g, lin_g, j_g)
    if data.scales and err_j <= n + GATE_NOISE_SIGMAS * math.sqrt(2.0 * n):  # at the noise
        return out
    alpha_l = float(np.clip(effs_j[-1].params["alpha_per_k"] * local_ratio(lad_j), -0.015,
                            0.015))
    return out + _local_fits(data, names, f, lad_j, base, t0, alpha_l, exclude, facts, err_lin)


def _local_fits(data: BundleData, names: list[str], linear: Foster, lad_j: Foster,
                base: list[Effect], t0: float, alpha_l: float, exclude, facts: dict,
                err_lin: float) -> list[EffectFit]:
    """The local forms in turn: ``local`` (from the junction α scaled by
    :func:`local_ratio`), ``power-law`` (from the local fit, ``n = α (T0 + 273.15)``, no
    capacity slope), and, when a residual beyond the noise remains, the best subset; when the
    candidate's budget runs out, the forms fitted so far."""
    def local(x: NDArray, **layers: float) -> list[Effect]:
        return [*base, _effect("local", t0, alpha_per_k=float(x[0]) * 1e-3, **layers)]

    def power(x: NDArray) -> list[Effect]:
        return [*base, _effect("power-law", t0, exponent=float(x[0]),
                               c_slope_per_k=float(x[1]) * 1e-3)]

    out: list[EffectFit] = []
    try:
        fit = _fit_local(data, names, linear, lad_j, [alpha_l * 1e3], [-15.0], [15.0], local,
                         exclude, err_lin, iterations=JOINT_ITERATIONS)
        if fit is None:
            return out
        out.append(EffectFit(fit[1][-1], fit[0], 1, facts))
        a_fit = fit[1][-1].params["alpha_per_k"]
        n0 = float(np.clip(a_fit * (t0 + 273.15), -3.9, 5.9))
        fit = _fit_local(data, names, linear, out[0].ladder, [n0, 0.0], [-4.0, -5.0],
                         [6.0, 10.0], power, exclude, err_lin)
        if fit is not None:
            out.append(EffectFit(fit[1][-1], fit[0], 2, facts))
        n_points = sum(data.measured(d).size for d in names)
        if sse(data, out[0].ladder, [*base, out[0].effect]) < SUBSET_CHI2 * n_points:
            return out  # every layer at the noise already: no subset to look for
        found = _best_subset(data, linear, base, t0, a_fit, exclude)
        if found:
            layers, a_sub, lad_sub = found

            def build(x: NDArray, layers: dict = layers) -> list[Effect]:
                return local(x, **layers)

            fit = _fit_local(data, names, linear, lad_sub, [a_sub * 1e3], [-15.0], [15.0],
                             build, exclude, err_lin, SUBSET_JOINT_BUDGET_S)
            if fit is not None:
                out.append(EffectFit(fit[1][-1], fit[0], 2, facts))
    except TimeLimitError:  # the candidate's budget ran out: the forms fitted so far stand
        pass
    return out


def _best_subset(data: BundleData, linear: Foster, base: list[Effect], t0: float,
                 alpha: float, exclude) -> tuple[dict[str, float], float, Cauer] | None:
    """The inner or outer subset of layers whose α fits the cooling curves best, with its α
    and its ladder at ``T0``, within :data:`SUBSET_BUDGET_S` (``None`` when none was fitted).

    The linear ladder fits the curves at their own temperatures, so a layer whose resistance
    follows α is ``R(T0) (1 + α ΔT)`` in it, with ``ΔT`` its mean steady temperature above
    ``T0`` over the curves (:func:`layer_rise`): each trial α comes with its layers'
    resistances divided by that factor, the ladder at ``T0`` it implies (a held linear ladder
    pulls α towards zero: a strong α on the inner layers of an actuator is otherwise found at
    a tenth of its value, and on the wrong layers).

    1. Screening, linearised: one integration per layer with α = ``alpha`` on that layer alone
       gives each layer's effect on the weighted residuals; every subset's α and squared
       error then follow in closed form (least squares along the sum of its layers' effects).
    2. The :data:`SUBSET_REFINED` best subsets: a bounded scalar search over α (with its
       ladder at ``T0``); the lowest squared error wins.
    """
    c = as_cauer(linear)
    r, cap, n = np.asarray(c.r), np.asarray(c.c), c.order
    rise = layer_rise(data, c, t0)
    sub = subset(data, [cv.name for cv in data.cooling])
    h = alpha if abs(alpha) >= 1e-4 else 1e-3

    def at_t0(s: dict, a: float) -> Cauer:
        layer = np.arange(n)
        inside = (layer >= s.get("first_layer", 0)) & (layer <= s.get("last_layer", n))
        return Cauer(np.where(inside, r / np.maximum(1 + a * rise, 0.05), r), cap)

    keep = {cv.name: cv.t_s >= (exclude or {}).get(cv.name, 0.0) for cv in sub.cooling}

    def residuals(s: dict, a: float) -> NDArray:
        pred = predict(sub, at_t0(s, a), [*base, _effect("local", t0, alpha_per_k=a, **s)])
        return sub.weighted(pred, keep, keep)

    subsets = [{"first_layer": float(n - k)} for k in range(1, n)] + \
               [{"last_layer": float(k - 1)} for k in range(1, n)]
    best: tuple[float, dict, float, Cauer] | None = None

    def search() -> None:
        nonlocal best
        r0 = residuals({}, 0.0)
        each = [(residuals({"first_layer": float(i), "last_layer": float(i)}, h) - r0) / h
                for i in range(n)]
        screened = []
        for s in subsets:
            j = np.sum(each[int(s.get("first_layer", 0)):int(s.get("last_layer", n - 1)) + 1],
                       axis=0)
            a = float(np.clip(-(j @ r0) / (j @ j), -0.015, 0.015)) if j @ j > 0 else 0.0
            screened.append((float(np.sum((r0 + a * j) ** 2)), s))
        for _, s in sorted(screened, key=lambda x: x[0])[:SUBSET_REFINED]:
            def cost(x: float, s: dict = s) -> float:
                try:
                    return float(np.sum(residuals(s, x * 1e-3) ** 2))
                except (FitError, SimulationError, *NUMERICAL_ERRORS):
                    return math.inf
            with np.errstate(invalid="ignore", over="ignore"):  # a failed trial α: inf
                res = minimize_scalar(cost, bounds=(-15.0, 15.0), method="bounded",
                                      options={"xatol": 0.2, "maxiter": SUBSET_EVALS})
            if np.isfinite(res.fun) and (best is None or res.fun < best[0]):
                a = float(res.x) * 1e-3
                best = (float(res.fun), s, a, at_t0(s, a))

    try:
        bounded(search, SUBSET_BUDGET_S, None)
    except (FitError, SimulationError, *NUMERICAL_ERRORS):  # the screening failed
        pass
    return None if best is None else best[1:]


def layer_rise(data: BundleData, ladder: Cauer, t0: float) -> NDArray:
    """Each layer's mean temperature above ``t0`` (K) in the linear steady state, averaged over
    the cooling curves (the reference's own temperature included).

    >>> from spicethermal.core.ladder import Cauer
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> d = BundleData.from_bundle(Bundle(ambient_c=25.0, cooling=(CoolingTable(
    ...     t_s=[1e-3, 1e-2], tj_c=[40.0, 30.0], power_w=1.0, tj_steady_c=45.0,
    ...     tref_steady_c=25.0),)))
    >>> layer_rise(d, Cauer([10.0, 10.0], [1.0, 1.0]), 25.0).tolist()
    [15.0, 5.0]
    """
    r = np.asarray(ladder.r)
    node = np.append(np.cumsum(r[::-1])[::-1], 0.0)
    return np.mean([cv.tref_steady_c - t0 + cv.power_w * 0.5 * (node[:-1] + node[1:])
                    for cv in data.cooling], axis=0)


def _fit_local(data: BundleData, names: list[str], linear: Foster, lad0: Foster,
               x0: list[float], lo: list[float], hi: list[float], build, exclude,
               err_lin: float, joint_s: float | None = None, iterations: int = 0
               ) -> tuple[Foster, list[Effect]] | None:
    """A local form: its parameters with ``lad0`` held from ``x0`` (and, when that ends worse
    than the linear ladder, from the effect switched off on ``linear``), then jointly with the
    ladder within ``joint_s`` (default :data:`JOINT_BUDGET_S`) of work, or ``iterations``
    iterations' worth when that is more;
    ``None`` when every start fails."""
    held = []
    w0, evaluations = spent(), 0
    for lad, x in ((lad0, x0), (linear, [0.0] * len(x0))):
        try:
            held.append(joint_fit(data, names, lad, False, x, lo, hi, build,
                                  max_nfev=HELD_NFEV, tol=1e-5, exclude=exclude))
        except (FitError, SimulationError, *NUMERICAL_ERRORS):
            continue
        res = held[-1][2]
        evaluations += res.nfev + (getattr(res, "njev", 0) or 0) * len(x)
        if 2 * res.cost < err_lin:
            break
    if not held:
        return None
    lad, effs, res = min(held, key=lambda r: r[2].cost)
    # an iteration: a Jacobian over the stages' R and τ and the form's parameters, each
    # column an evaluation (what the held fits cost one, on average)
    k = 2 * as_foster(lad).order + len(res.x) + 1
    joint_s = max(JOINT_BUDGET_S if joint_s is None else joint_s,
                  iterations * k * (spent() - w0) * 1e-9 / max(evaluations, 1))

    def joint() -> tuple:
        return joint_fit(data, names, lad, True, list(res.x), lo, hi, build, tol=1e-5,
                         exclude=exclude)

    try:
        got = bounded(joint, joint_s, None)
    except FitError:
        got = None
    if got is not None and got[2].cost < res.cost:
        return got[0], got[1]
    return lad, effs
