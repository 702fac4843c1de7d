"""Every threshold of the diagnosis, with its reason, and the statistics it is applied to.

The diagnosis compares models by one criterion, ``BIC = χ² + k ln N`` (χ² weighted by each
data set's noise, ``k`` parameters fitted, ``N`` points), and names an effect by one rule
(:func:`decisive`): its model lowers the criterion by :data:`DECISIVE_BIC` and removes at
least :data:`MIN_EXPLAINED` of the misfit beyond the noise. Nothing here refers to a case.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

__all__ = ["AT_NOISE_Z", "CLOSED_FORM_COST", "DECISIVE_BIC", "LOCAL_WINDOW", "MAX_EFFECTS",
           "MIN_APPROXIMATE", "MIN_EXPLAINED", "NOISE_EFFICIENCY", "NOISE_FLOOR_K", "NOISE_KEPT",
           "POLY_MAX_DEGREE", "POLY_P", "REFINE_ROUNDS", "RUNS_MIN", "RUNS_Z", "SCREEN_ROUNDS",
           "at_noise", "beyond_noise", "correlated_gain", "decisive", "excess", "explained",
           "runs_z", "shows"]

# -- noise ------------------------------------------------------------------------------------
#: No bench reads better than this (K): a floor on every noise estimate.
NOISE_FLOOR_K = 0.005
#: A cooling curve's noise is its residuals' scatter about a local quadratic in log t over
#: this many readings: wide enough for a stable scatter, narrow enough that a smooth misfit
#: (what a missing effect leaves) is a quadratic over it.
LOCAL_WINDOW = 7
#: A curve's noise is the scatter of this fraction of those local residuals, the smallest:
#: the largest tenth (a transient's or a kink's few readings) are no noise.
NOISE_KEPT = 0.9
#: The calibration's law is a polynomial whose degree is raised while a higher degree lowers
#: the residual at this significance (F-test; one chance in a hundred of taking noise for a
#: bow, each test) ...
POLY_P = 0.01
#: ... up to this degree (a TSP is smooth in T).
POLY_MAX_DEGREE = 3

# -- naming -------------------------------------------------------------------------------------
#: A model is decisively better than another when its BIC is lower by this much: "very strong"
#: evidence on Kass & Raftery's scale (a Bayes factor above 150). The same margin says two
#: candidates cannot be told apart.
DECISIVE_BIC = 10.0
#: An effect must also remove this fraction of the misfit beyond the noise of the model it is
#: added to: on a badly misspecified model any flexible term lowers χ² by tens, and that is
#: no evidence of its physics. 0.4 lets each of two effects of similar size pass in turn.
MIN_EXPLAINED = 0.4
#: Effects that leave a structured residual are named as *approximate* only when together they
#: remove this fraction of the baseline's misfit beyond the noise: the closest catalogued
#: effect is then still the user's best next step; below it the physics is elsewhere.
MIN_APPROXIMATE = 0.9
#: A data set is at its noise when its χ² is within this many standard deviations of its
#: number of points: χ² of n points of white noise is n ± √(2n) with the noise known, and
#: the noise is itself estimated from about as many residuals (an estimate of efficiency
#: :data:`NOISE_EFFICIENCY`), which widens the band to ±√(2n (1 + 1/efficiency)) ...
AT_NOISE_Z = 3.0
#: The efficiency of :func:`~.noise.trimmed_scale` keeping :data:`NOISE_KEPT` against the
#: plain standard deviation (Gaussian noise).
NOISE_EFFICIENCY = 0.8
#: ... and its residual has no runs structure: a runs test on the signs below this z (three
#: standard deviations too few runs) ...
RUNS_Z = -3.0
#: ... which needs this many residuals.
RUNS_MIN = 8
#: Effects named at most (forward selection stops there).
MAX_EFFECTS = 3

# -- work (counted, never timed) ----------------------------------------------------------------
#: Levenberg–Marquardt rounds of a candidate's first fit (its own parameters, the rest held).
SCREEN_ROUNDS = 15
#: Rounds of a candidate's joint refit with the ladder and every other effect.
REFINE_ROUNDS = 30
#: The simulator's cost (:func:`spicethermal.engines.meter.metered`: network solves and
#: :data:`~spicethermal.engines.meter.STEP_SOLVES` for each batched step) one diagnosis may
#: spend. A unit takes 3 to 4 µs of CPU on a quiet 2-core machine of the bench's kind (the
#: steady states' Newton steps and long ladders counted as they cost,
#: :data:`~spicethermal.engines.meter.SOLVE_NODES`): 12,000,000 is about 40 s, which keeps every
#: bundle, the overrun below and a loaded machine's slower units included, under a minute; the
#: median bundle takes a small part of it. Once it is spent, a ladder stops growing (a longer
#: ladder's fit stops where it is), the candidates and forms not yet fitted are not (a later
#: step screens the measurement effects left on its model held, one simulation of the device
#: each, and refits the best jointly once), and a step that did not fit every form of every
#: candidate is taken only when its best is at the noise; any other bounded fit that has started
#: finishes (a diagnosis may overrun the budget by one form's fits, one round of a longer
#: ladder's, one step's refit and settling, or that joint refit).
WORK_BUDGET = 12_000_000
#: An effect whose relative cost (``Traits.cost``) is at most this is evaluated in closed form,
#: a few thousandths of the budget a fit. Each step fits those first, then the simulated ones
#: (after the first step, each group in the first step's ranking): a budget that the simulated
#: fits spend then leaves none of the closed-form effects unfitted, where in the ranking's
#: order alone a cheap second effect queued behind a costly one was never tried.
CLOSED_FORM_COST = 1.0


def correlated_gain(before: NDArray, after: NDArray) -> float:
    """The fall of χ² from residual ``before`` to ``after`` (in noises, data order) weighed
    under the correlation of the misfit ``after`` leaves: generalised least squares with
    first-order autoregressive errors (Cochrane–Orcutt). Both are prewhitened by ``after``'s
    lag-one autocorrelation ρ in [0, 0.99] (``e_i = r_i − ρ r_(i−1)``, ``e_0 = √(1 − ρ²)
    r_0``) and the fall divided by the variance of ``after``'s innovations, at least 1: a
    smooth misfit left is one error repeated, a white one the plain fall."""
    a, b = np.asarray(after, dtype=float), np.asarray(before, dtype=float)
    norm = float(a @ a)
    rho = min(max(float(a[1:] @ a[:-1]) / norm, 0.0), 0.99) if norm > 0 and a.size > 1 else 0.0
    ea, eb = ([math.sqrt(1.0 - rho * rho) * r[0], *(r[1:] - rho * r[:-1])] for r in (a, b))
    return float(np.dot(eb, eb) - np.dot(ea, ea)) / max(float(np.dot(ea, ea)) / a.size, 1.0)


def runs_z(residuals: NDArray) -> float:
    """Wald–Wolfowitz runs test on the signs of ``residuals`` in data order: the z of the
    number of runs (very negative: too few runs, a structured residual).

    Parameters
    ----------
    residuals : ndarray

    Returns
    -------
    float
        0 for fewer than :data:`RUNS_MIN` residuals or one sign only.

    >>> runs_z(np.array([1.0] * 10 + [-1.0] * 10)) < -3
    True
    """
    r = np.asarray(residuals, dtype=float)
    r = r[r != 0]
    pos = int(np.sum(r > 0))
    neg = r.size - pos
    if r.size < RUNS_MIN or pos == 0 or neg == 0:
        return 0.0
    runs = 1 + int(np.sum(np.diff(np.sign(r)) != 0))
    n = r.size
    mu = 2.0 * pos * neg / n + 1
    var = (mu - 1) * (mu - 2) / (n - 1)
    return float((runs - mu) / math.sqrt(var)) if var > 0 else 0.0


def beyond_noise(chi2: float, n: int, residuals: NDArray) -> bool:
    """Whether one data set's residual is beyond its noise: χ² above the band of
    :data:`AT_NOISE_Z` or a runs structure (:data:`RUNS_Z`).

    Parameters
    ----------
    chi2 : float
    n : int
    residuals : ndarray

    Returns
    -------
    bool
    """
    spread = math.sqrt(2 * n * (1 + 1 / NOISE_EFFICIENCY))
    return chi2 > n + AT_NOISE_Z * spread or runs_z(residuals) < RUNS_Z


def at_noise(chi2: Mapping[str, float], residuals: Mapping[str, NDArray]) -> bool:
    """Whether every data set is at its noise (:func:`beyond_noise`)."""
    return not any(beyond_noise(chi2[n], residuals[n].size, residuals[n]) for n in chi2)


def excess(chi2: Mapping[str, float], sizes: Mapping[str, int]) -> float:
    """The misfit beyond the noise: ``Σ max(χ²_d − n_d, 0)``."""
    return float(sum(max(chi2[n] - sizes[n], 0.0) for n in chi2))


def explained(before: Mapping[str, float], after: Mapping[str, float],
              sizes: Mapping[str, int]) -> float:
    """The fraction of ``before``'s misfit beyond the noise that ``after`` removes (1 when
    nothing was beyond it and nothing got worse).

    >>> explained({"a": 30.0}, {"a": 12.0}, {"a": 10})
    0.9
    """
    e = excess(before, sizes)
    gain = sum(before.values()) - sum(after.values())
    if e <= 0:
        return 1.0 if gain >= 0 else 0.0
    return float(min(1.0, gain / e))


def decisive(bic_before: float, bic_after: float, fraction: float) -> bool:
    """The naming rule: the criterion falls by :data:`DECISIVE_BIC` and the effect removes
    :data:`MIN_EXPLAINED` of the misfit beyond the noise.

    >>> decisive(200.0, 150.0, 0.6), decisive(200.0, 195.0, 0.9)
    (True, False)
    """
    return bic_before - bic_after >= DECISIVE_BIC and fraction >= MIN_EXPLAINED


def shows(before: Mapping[str, float], after: Mapping[str, float], sets: Sequence[str]) -> bool:
    """Whether the data sets ``sets`` that an effect needs (its ``traits.needs``: those that
    tell it from the other effects) show it themselves: the model with it (``after``) lowers
    their χ² by :data:`DECISIVE_BIC`, a likelihood ratio above e⁵ on those data alone. The
    rest of the bundle cannot tell the effect from the others, so it is no evidence of its
    physics (a TSP's curvature that its calibration does not show is a device's misfit
    taken for the sensor's). Nothing is needed: shown.

    >>> shows({"calibration": 40.0}, {"calibration": 12.0}, ["calibration"])
    True
    >>> shows({"calibration": 15.2, "pwm": 27.0}, {"calibration": 15.6, "pwm": 15.0},
    ...       ["calibration"])
    False
    """
    if not sets:
        return True
    return sum(before[n] - after[n] for n in sets) >= DECISIVE_BIC
