"""The joint refits of a step's effects with the ladder: the rescue of a later candidate that
its held fit hides, the refit of every effect found after a later step, and the converged fit
of a device effect's general form before the cooling dynamics refuse it.
:mod:`~spicethermal.analysis.candidates` calls them."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.ladder import Foster
from ..effects import MEASUREMENT, Effect, spec
from ..fit.backfit import HELD_LADDER_S, refit_effects
from ..fit.effectfit import NUMERICAL_ERRORS, BundleData, EffectFit, time_limit
from .compare import Comparison
from .diagnosis import Candidate
from .evidence import evidence
from .residuals import comparison_of
from .verdict import DIRECT, MIN_BIC_DROP, chi2, criterion, explained_fraction
from .verdict import improvement as improvement_of

__all__ = ["GENERAL_FORM", "REFIT_BUDGET_S", "RESCUE_BUDGET_S", "Scored", "converged",
           "joint_refit", "refit_step", "rescue"]

#: Work (s, see :mod:`~spicethermal.fit.budget`) allowed to the joint refit of every effect found
#: and the ladder after each later step (:func:`refit_step`).
REFIT_BUDGET_S = 8.0

#: ... and to the joint refit of a later candidate that is not decisive on top of the effects
#: found so far (:func:`rescue`).
RESCUE_BUDGET_S = 8.0

#: The most general form of a device effect, refitted until it converges before the cooling
#: dynamics refuse the effect (:func:`converged`): the power law of each layer's temperature,
#: with a heat capacity that rises with it, holds the local linear coefficient to first order.
GENERAL_FORM = {"temperature-coefficient": "power-law"}

#: One effect's fit with its comparison and criterion (:func:`scored_forms`).
Scored = tuple[EffectFit, Comparison, float]


def converged(data: BundleData, name: str, scored: list[Scored], noise: Mapping[str, float]
              ) -> list[Scored] | None:
    """``scored`` with the most general form of device effect ``name`` (:data:`GENERAL_FORM`)
    refitted jointly with its ladder within :data:`RESCUE_BUDGET_S` of work, or ``None`` when
    the effect has no such form among them or the refit lowers nothing. Before the cooling
    dynamics refuse an effect's physics (a linear alternative fits them decisively better than
    every form *as fitted*), its general form gets a fit that converges: within the
    candidate's budget a form integrated per evaluation gets a second of joint refit, less
    than one iteration of the ladder's Jacobian (seed 303's draw 032 of the random validation
    set: a MOSFET whose layers' conductivity follows T^-2.1, the power law fitted at
    n = 2.19 with χ² 612 on 134 points, its ladder unmoved, so a power per curve fitted the
    cooling curves better; refitted for 8 s of work, n = 2.08 and χ² 28)."""
    form = GENERAL_FORM.get(name)
    k = next((k for k, x in enumerate(scored) if x[0].effect.form == form), None)
    if k is None:
        return None
    fit = scored[k][0].facts.get("tried", scored[k][0])
    joint = joint_refit(data, fit.ladder, [fit.effect], RESCUE_BUDGET_S, scored[k][1], noise)
    if joint is None:
        return None
    ladder, refitted, cmp = joint
    facts = {key: v for key, v in fit.facts.items() if key not in ("no_gain", "tried")}
    again = EffectFit(refitted[-1], ladder, fit.n_params, facts)
    return [*scored[:k], (again, cmp, criterion(cmp, noise, fit.n_params)), *scored[k + 1:]]


def joint_refit(data: BundleData, ladder: Foster, effects: Sequence[Effect], budget_s: float,
                than: Comparison, noise: Mapping[str, float], held_first: bool = False
                ) -> tuple[Foster, list[Effect], Comparison] | None:
    """Every effect of ``effects`` and ``ladder`` refitted jointly
    (:func:`~spicethermal.fit.backfit.refit_effects`, within ``budget_s`` of work) with
    its comparison; ``None`` when it fails or does not lower the noise-weighted squared error
    of ``than``."""
    try:
        with time_limit(budget_s + (HELD_LADDER_S if held_first else 0.0)):
            lad, refitted = refit_effects(data, ladder, effects, held_first)
        cmp = comparison_of(data, lad, refitted)
    except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS):
        return None
    return (lad, refitted, cmp) if chi2(cmp, noise) < chi2(than, noise) else None


def rescue(data: BundleData, fit: EffectFit, effects: Sequence[Effect], before: Comparison,
           cmp: Comparison, bic: float, noise: Mapping[str, float],
           held_bic: Callable[[], float]
           ) -> tuple[EffectFit, Comparison, float, tuple[Effect, ...]]:
    """A later step's candidate that is not decisive on top of the effects found so far (their
    parameters held), refitted jointly with them (:func:`~spicethermal.fit.backfit.refit_effects`,
    within :data:`RESCUE_BUDGET_S`) when its own fit shows it somewhere: some data set's
    noise-weighted squared error falls by :data:`MIN_BIC_DROP` (a TSP bow that fits the
    calibration, which an effect found before had mimicked in the curves). The joint refit
    counts only when its criterion is lower by :data:`MIN_BIC_DROP` than ``held_bic()``, the
    criterion of the effects found so far refitted jointly without it: what the refit alone
    gains is no sign of the candidate. Returns the fit, its comparison, its criterion and the
    model's refitted effects (empty: unchanged)."""
    tried = fit.facts.get("tried", fit)
    tried_cmp = cmp if tried is fit else comparison_of(data, tried.ladder, [*effects,
                                                                            tried.effect])
    was = before.by_dataset()
    if not any(chi2(was[n], {n: noise[n]}) - chi2(sub, {n: noise[n]}) >= MIN_BIC_DROP
               for n, sub in tried_cmp.by_dataset().items() if n in was):
        return fit, cmp, bic, ()
    # a measurement effect leaves the thermal path alone: the effects first, the ladder held
    joint = joint_refit(data, tried.ladder, [*effects, tried.effect], RESCUE_BUDGET_S, cmp,
                        noise, spec(tried.effect.name).kind == MEASUREMENT)
    if joint is None:
        return fit, cmp, bic, ()
    ladder, refitted, new = joint
    new_bic = criterion(new, noise, fit.n_params)
    if held_bic() - new_bic < MIN_BIC_DROP:
        return fit, cmp, bic, ()
    facts = {k: v for k, v in fit.facts.items() if k not in ("no_gain", "tried")}
    return (EffectFit(refitted[-1], ladder, fit.n_params, facts), new, new_bic,
            tuple(refitted))


def refit_step(data: BundleData, chosen: Candidate, effects: list[Effect],
               before: Comparison, noise: Mapping[str, float]) -> tuple[Candidate, list[Effect]]:
    """``chosen`` (the last of ``effects``) after the joint refit of every effect and the ladder
    (:func:`~spicethermal.fit.backfit.refit_effects`, within :data:`REFIT_BUDGET_S`), with its
    figures against ``before``; unchanged when the refit does not lower the noise-weighted
    squared error."""
    joint = joint_refit(data, chosen.ladder, effects, REFIT_BUDGET_S, chosen.comparison, noise)
    if joint is None:
        return chosen, effects
    ladder, refitted, cmp = joint
    fit = EffectFit(refitted[-1], ladder, chosen.n_params, chosen.facts)
    within = DIRECT.get(chosen.effect.name, ())
    return replace(chosen, effect=refitted[-1], ladder=ladder, comparison=cmp,
                   bic=criterion(cmp, noise, chosen.n_params),
                   improvement=before.rms_k / cmp.rms_k if cmp.rms_k > 0 else math.inf,
                   explained=explained_fraction(before, cmp, noise, within),
                   evidence=evidence(fit, data, before, cmp, noise),
                   noise_gain=improvement_of(before, cmp, noise, within)), refitted
