"""Diagnosis: where a linear ladder fails, which catalogued effect is missing, and by how much
the error falls when it is added.

:func:`diagnose` compares a model with every data set of a bundle (each cooling curve, the
PWM grid, the calibration), localises the misfit (time decade, frequency, duty, temperature
band), fits every candidate effect of the catalogue (:mod:`spicethermal.fit.effectfit`) and ranks
them. The result (:class:`Diagnosis`) prints as a short report and serialises to the
``spicethermal-diagnosis/2`` document (docs/diagnosis-json.md).

Criterion (stated)
------------------
Residuals ``r = measured − model`` in kelvin. Each data set ``d`` gets a noise estimate
``σ_d`` that no model choice can bias: the scatter of consecutive baseline residuals (smooth
misfits cancel in the differences; the largest 10 % are trimmed, see
:func:`noise_estimates`), at least :data:`NOISE_FLOOR_K`. A model's criterion is
``BIC = Σ_d RSS_d / σ_d² + k ln N`` with ``k`` the number of effect parameters fitted and
``N`` the number of points. An effect is *found* when the best candidate (lowest BIC)

1. lowers the BIC by at least :data:`MIN_BIC_DROP` (strong evidence on Kass & Raftery's scale),
2. lowers the pooled (or the noise-weighted) RMS by at least :data:`MIN_IMPROVEMENT` ×, and
3. explains at least :data:`MIN_EXPLAINED` of the misfit beyond the noise
   (:func:`~spicethermal.analysis.verdict.explained_fraction`).

Clean data fail (1) and (2): an effect fitted to noise gains little. An effect outside the
catalogue fails (2) or (3): the verdict is then null and the reason says where the misfit is.
When the baseline already fits every data set within :data:`EXPLAINED_RATIO` × its noise,
nothing is missing.

The pooled RMS (``rms_k``; ``improvement = baseline rms / candidate rms``) weighs every point
equally, as ``spicethermal compare`` does, with the calibration points added.

A table of measured vs simulated PWM readings (the paper's Table 2, :func:`diagnose_table`)
goes through the same rule with the simulated column as the baseline; its noise is the
scatter of one measured reading beyond an offset per frequency (see :class:`TableAnalysis`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.progress import bar
from ..effects import CATALOGUE, DEVICE, Effect
from ..fit.backfit import refit_effects
from ..fit.budget import TimeLimitError, mark, reached
from ..fit.effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    baseline_ladder,
    needs,
    time_limit,
    transient_spans,
)
from ..fit.fitters import choose_form, fit_effect_forms, fit_with_effects
from ..fit.tcforward import own_cache
from ..model import ThermalModel
from ..report.diagnosis import write_report
from .compare import Comparison
from .consistency import amplitude_only, device_effect_contradicted, transient_hidden
from .diagnosis import DIAGNOSIS_FORMAT, Candidate, Diagnosis, Step
from .evidence import evidence
from .residuals import comparison_of, localise, noise_estimates
from .table2 import TableAnalysis, analyse_table, diagnose_table
from .verdict import (
    MAX_LEFT_CHI2,
    MIN_BIC_DROP,
    MIN_EXPLAINED,
    MIN_IMPROVEMENT,
    MIN_TOTAL_EXPLAINED,
    at_noise,
    can_be_decisive,
    chi2,
    criterion,
    decisive,
    explained_fraction,
    far_left,
    passes,
    runs_z,
    structured,
    verdict_reason,
)
from .verdict import improvement as improvement_of

if TYPE_CHECKING:  # pragma: no cover
    from ..core.ladder import Foster
    from ..io.bundle import Bundle

__all__ = ["DIAGNOSIS_FORMAT", "MIN_EXPLAINED", "MIN_IMPROVEMENT", "Candidate", "Diagnosis",
           "Step", "TableAnalysis", "analyse_table", "candidates", "comparison_of", "diagnose",
           "diagnose_table", "evidence", "explained_fraction", "fit_with_effects", "localise",
           "noise_estimates", "runs_z", "structured", "write_report"]

#: Effects whose only signature is in some data sets (those whose name starts so) and their
#: least number of parameters: they are not fitted when those data sets leave no room for a
#: decisive improvement (:func:`~spicethermal.analysis.verdict.can_be_decisive`).
SIGNATURE = {"phase-change": ("cooling", 4), "electrical-transient": ("cooling", 2),
             "sample-window": ("pwm", 1)}
#: ... of which these act on the cooling curves beyond their electrical transient.
AFTER_TRANSIENT = ("phase-change",)
#: Costly fits (an integration per evaluation) come last and are skipped when a cheaper
#: candidate already brings every data set to its noise without structure (:func:`not_needed`).
FITTED_LAST = ("phase-change",)
#: Effects whose first form is cheap and whose others cost: they come after the cheap effects,
#: and when a cheaper candidate already brings every data set to its noise they get a glance
#: (:data:`GLANCE_S` of work, the cheap form) and their full fit only when the glance beats
#: that candidate's criterion by :data:`MIN_BIC_DROP` (a TSP bow at the noise can still be
#: decisively worse than a temperature coefficient).
GLANCED = ("temperature-coefficient",)
#: Work (s) of a glance.
GLANCE_S = 1.0
#: Effects added at most, one per step.
MAX_STEPS = 3
#: Time budget (s of work, see :func:`~spicethermal.fit.effectfit.time_limit`) of one
#: candidate's fit at the first step; a fit past it keeps its
#: best point so far (a fit that cannot start fails).
CANDIDATE_BUDGET_S = 8.0
#: ... and at later steps (their forward models carry the effects added so far; a second
#: effect is often the one that needs an integration).
LATER_BUDGET_S = 8.0
#: Work (s, see :mod:`~spicethermal.fit.budget`) allowed to the joint refit of every effect found
#: and the ladder after each later step (:func:`refit_step`).
REFIT_BUDGET_S = 8.0
#: Work (s, see :mod:`~spicethermal.fit.budget`) allowed to all the steps of one diagnosis together
#: (the candidates' own budgets stop at it too): no bundle keeps the diagnosis busy for longer,
#: whatever its fits do.
DIAGNOSIS_BUDGET_S = 50.0
#: ... and to the joint refit of a later candidate that is not decisive on top of the effects
#: found so far (:func:`rescue`).
RESCUE_BUDGET_S = 8.0


def candidates(data: BundleData, ladder: Foster, effects: Sequence[Effect],
                names: Sequence[str], before: Comparison, noise: Mapping[str, float],
                say: Callable[[str], None], skipped: dict[str, str],
                budget_s: float = 6.0, quiet: bool = True, step: int = 1) -> list[Candidate]:
    """Every effect of ``names`` fitted on top of ``ladder`` and ``effects`` (each form; the
    default form unless another is decisively better, :func:`choose_form`), each within
    ``budget_s`` of work; failures go to ``skipped``."""
    present = {e.name for e in effects}
    amplitude = None  # the power-per-curve alternative of the device effects, fitted once
    # the model so far refitted jointly (what a rescue must beat), fitted once when asked
    refitted: list[float] = []

    def held_bic() -> float:
        if not refitted:
            joint = joint_refit(data, ladder, effects, RESCUE_BUDGET_S, before, noise)
            refitted.append(criterion(joint[2] if joint else before, noise, 0))
        return refitted[0]

    cands: list[Candidate] = []
    bic_before = criterion(before, noise, 0)
    order = sorted(names, key=lambda n: 2 if n in FITTED_LAST else n in GLANCED)
    for name in bar(order, desc=f"diagnose step {step}: fitting effects", quiet=quiet):
        if name in present:
            skipped.setdefault(name, "already in the model")
            continue
        why = not_needed(name, cands, bic_before, noise) \
            if name in FITTED_LAST or name in GLANCED else ""
        if why and name in FITTED_LAST:
            skipped[name] = f"not needed: {why}"
            continue
        # the criterion a glance must beat: the best candidate so far
        bar_bic = min(c.bic for c in cands) - MIN_BIC_DROP if why else None
        why = needs(name, data)
        if why:
            skipped[name] = why
            continue
        if name in SIGNATURE:
            sets = [d for d in before.datasets if d.startswith(SIGNATURE[name][0])]
            seen = before
            if name in AFTER_TRANSIENT and "electrical-transient" not in present:
                spans = transient_spans(data)
                seen = Comparison(tuple(p for p in before.points if p.dataset not in spans
                                        or p.at["t_s"] >= spans[p.dataset]), before.engine)
            if not can_be_decisive(seen, noise, sets, SIGNATURE[name][1]):
                skipped[name] = (f"cannot be decisive: {', '.join(sets)} (where it acts) are "
                                 f"within their noise")
                continue
        say(f"fitting {name}")
        t0 = time.perf_counter()
        try:
            scored = scored_forms(data, ladder, name, effects, noise,
                                  budget_s if bar_bic is None else GLANCE_S)
            if bar_bic is not None:
                if min(x[2] for x in scored) > bar_bic:
                    skipped[name] = f"not needed: {why} (its first form is no better)"
                    continue
                scored = scored_forms(data, ladder, name, effects, noise, budget_s)
            best = scored[choose_form([x[2] for x in scored])]
        except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS) as exc:
            skipped[name] = f"fit failed: {exc}"
            continue
        fit, cmp, bic = best
        model_effects: tuple[Effect, ...] = ()
        if effects and not passes(bic_before - bic, improvement_of(before, cmp, noise),
                                  explained_fraction(before, cmp, noise)):
            fit, cmp, bic, model_effects = rescue(data, fit, effects, before, cmp, bic, noise,
                                                  held_bic)
        contradicted = ""
        if fit.effect.kind == DEVICE and len(data.cooling) > 1:
            try:
                if amplitude is None:
                    amplitude = amplitude_only(data, ladder)
                contradicted = device_effect_contradicted(data, ladder, fit.effect,
                                                          fit.n_params, [x[1] for x in scored],
                                                          amplitude)
            except (FitError, SimulationError, *NUMERICAL_ERRORS):  # nothing contradicts
                contradicted = ""
        if fit.effect.name == "electrical-transient" and not fit.facts.get("no_gain"):
            # the first readings stand out of the model it extends or of its own ladder (a
            # transient proportional to the power passes for a fast stage of the first)
            why = transient_hidden(before, fit.effect, noise) and transient_hidden(
                comparison_of(data, fit.ladder, effects), fit.effect, noise)
            if why:
                skipped[name] = f"not seen: {why}"
                continue
        improvement = before.rms_k / cmp.rms_k if cmp.rms_k > 0 else math.inf
        cands.append(Candidate(fit.effect, fit.ladder, cmp, fit.n_params, bic, improvement,
                               evidence(fit, data, before, cmp, noise),
                               explained_fraction(before, cmp, noise),
                               time.perf_counter() - t0, contradicted, fit.facts,
                               improvement_of(before, cmp, noise), model_effects))
    cands.sort(key=lambda c: c.bic)
    return cands


def scored_forms(data: BundleData, ladder: Foster, name: str, effects: Sequence[Effect],
                 noise: Mapping[str, float], budget_s: float
                 ) -> list[tuple[EffectFit, Comparison, float]]:
    """Every form of ``name`` fitted on top of ``ladder`` and ``effects`` within ``budget_s``
    of work, each with its comparison and criterion."""
    with time_limit(budget_s):
        fits = fit_effect_forms(data, ladder, name, effects)
    scored = []
    for fit in fits:
        cmp = comparison_of(data, fit.ladder, [*effects, fit.effect])
        scored.append((fit, cmp, criterion(cmp, noise, fit.n_params)))
    return scored


def not_needed(name: str, cands: Sequence[Candidate], bic_before: float,
               noise: Mapping[str, float]) -> str:
    """Why the costly fit of ``name`` is not needed ("" when it is): a decisive candidate
    fitted before it (not contradicted) already brings every data set to its noise, or the
    data sets where ``name`` acts (:data:`SIGNATURE`)."""
    held = [c for c in cands if not c.contradicted and decisive(c, bic_before)]
    done = next((c for c in held if at_noise(c.comparison, noise)), None)
    if done is not None:
        return f"{done.effect.name} brings every data set to its noise"
    where = SIGNATURE[name][0] if name in SIGNATURE else ""
    done = next((c for c in held if where and quiet_where(c.comparison, noise, where)), None)
    if done is not None:
        return f"{done.effect.name} brings the {where} data sets (where it acts) to their noise"
    return ""


def quiet_where(comparison: Comparison, noise: Mapping[str, float], prefix: str) -> bool:
    """Whether the data sets of ``comparison`` whose name starts with ``prefix`` (there is one
    at least) are at their noise (:func:`~spicethermal.analysis.verdict.at_noise`)."""
    sub = Comparison(tuple(p for p in comparison.points if p.dataset.startswith(prefix)),
                     comparison.engine)
    return bool(sub.points) and at_noise(sub, noise)


def unexplained(final: Comparison, noise: Mapping[str, float], n_steps: int) -> bool:
    """Whether the effects leave a misfit too large to call them the diagnosis (the caller
    asks only when the residual is structured): a data set whose structured residual is
    above 3× its noise (:func:`far_left`); after two, a noise-weighted ``χ²/N`` above
    :data:`MAX_LEFT_CHI2`; after three, any (a structured residual that three catalogued
    effects leave is physics they only approximate together: a convection that switches
    passes for a temperature coefficient, a sample window and a latent heat)."""
    if n_steps >= MAX_STEPS:
        return True
    if n_steps > 1 and chi2(final, noise) / max(len(final.points), 1) > MAX_LEFT_CHI2:
        return True
    return bool(far_left(final, noise))


def joint_refit(data: BundleData, ladder: Foster, effects: Sequence[Effect], budget_s: float,
                than: Comparison, noise: Mapping[str, float]
                ) -> tuple[Foster, list[Effect], Comparison] | None:
    """Every effect of ``effects`` and ``ladder`` refitted jointly
    (:func:`~spicethermal.fit.backfit.refit_effects`, within ``budget_s`` of work) with
    its comparison; ``None`` when it fails or does not lower the noise-weighted squared error
    of ``than``."""
    try:
        with time_limit(budget_s):
            lad, refitted = refit_effects(data, ladder, effects)
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
    joint = joint_refit(data, tried.ladder, [*effects, tried.effect], RESCUE_BUDGET_S, cmp,
                        noise)
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
    return replace(chosen, effect=refitted[-1], ladder=ladder, comparison=cmp,
                   bic=criterion(cmp, noise, chosen.n_params),
                   improvement=before.rms_k / cmp.rms_k if cmp.rms_k > 0 else math.inf,
                   explained=explained_fraction(before, cmp, noise),
                   evidence=evidence(fit, data, before, cmp, noise),
                   noise_gain=improvement_of(before, cmp, noise)), refitted


@own_cache()  # its fits' work, so where they stop, owes nothing to earlier runs
def diagnose(bundle: Bundle, model: ThermalModel | None = None,
             effects: Sequence[str] | None = None,
             progress: Callable[[str], None] | None = None, quiet: bool = True) -> Diagnosis:
    """Compare, localise, fit every candidate effect, add the decisive one, and again.

    Each step fits every catalogued effect the model lacks (each of its forms) on top of the
    model so far and adds the best when it is decisively better (:data:`MIN_BIC_DROP`,
    :data:`MIN_IMPROVEMENT`, :data:`MIN_EXPLAINED`); the steps stop when the residual is at
    the noise, nothing is decisive, two different effects are decisive at a later step and
    the data cannot tell them apart (their criteria within :data:`MIN_BIC_DROP`: what they gain
    alike comes from refitting the model, not from either effect), or after
    :data:`MAX_STEPS`.

    Parameters
    ----------
    bundle : the measurements (``spicethermal-bundle/1``).
    model : the baseline model; default the linear ladder of the bundle's lowest-power cooling
        curve refitted to all its cooling curves
        (:func:`~spicethermal.fit.effectfit.baseline_ladder`).
        Its effects stay in every candidate; the candidates are the catalogued effects it lacks.
    effects : candidate names (default: every catalogued effect).
    progress : called with a short text before each step.
    quiet : no progress bar on stderr (one bar per step over the candidate fits, shown only
        when stderr is a terminal; :mod:`spicethermal.core.progress`).

    Returns
    -------
    Diagnosis

    Examples
    --------
    >>> from spicethermal.analysis.scenarios import scenario_bundle
    >>> d = diagnose(scenario_bundle("sample-window", seed=0))
    >>> d.verdict_effect, d.effects, d.best.improvement > 3
    ('sample-window', ['sample-window'], True)
    """
    t_start = time.perf_counter()
    say = progress or (lambda _text: None)
    data = BundleData.from_bundle(bundle)
    if not data.datasets:
        raise DataFormatError(f"{data.source}: nothing to diagnose (no cooling, pwm or "
                              f"calibration data)")
    if model is not None and model.reference != bundle.reference:
        raise DataFormatError(f"{data.source}: measured against the {bundle.reference} but the "
                              f"model's reference is {model.reference}")
    say("baseline ladder")
    if model is None:
        try:
            ladder = baseline_ladder(data)
        except (SimulationError, *NUMERICAL_ERRORS) as exc:
            raise FitError(f"{data.source}: no linear ladder fits the cooling curves: "
                           f"{exc}") from None
        model = ThermalModel(ladder, (), bundle.reference,
                             {"tool": "spicethermal diagnose", "baseline": "linear ladder"})
    else:
        ladder = model.ladder if model.ladder.topology == "foster" else model.ladder.to_foster()
    base = comparison_of(data, ladder, model.effects)
    noise = noise_estimates(base)
    data = replace(data, scales=noise)  # the fits weigh each data set by its noise
    bic0 = criterion(base, noise, 0)
    names = list(effects) if effects is not None else list(CATALOGUE)
    skipped: dict[str, str] = {e.name: "already in the model" for e in model.effects
                               if e.name in names}
    steps: list[Step] = []
    first: list[Candidate] = []
    cur_ladder, cur_effects, cur, cur_bic = ladder, list(model.effects), base, bic0
    k_total = 0
    contradicted = ""
    # one budget for every step: a step that finds its time spent stops the diagnosis
    end = mark(DIAGNOSIS_BUDGET_S)
    with time_limit(DIAGNOSIS_BUDGET_S):
        while len(steps) < MAX_STEPS and not at_noise(cur, noise) and \
                not reached(end):
            # the first step's candidates and skips are the report's; later ones are its steps'
            try:
                cands = candidates(data, cur_ladder, cur_effects, names, cur, noise, say,
                                   skipped if not steps else {},
                                   CANDIDATE_BUDGET_S if not steps else LATER_BUDGET_S,
                                   quiet, len(steps) + 1)
            except TimeLimitError:  # the budget ran out within the step: it is not taken
                break
            if not steps:
                first = cands
            winners = [c for c in cands if decisive(c, cur_bic)]  # best BIC first
            if not winners:
                break
            chosen = winners[0]
            if steps and len(winners) > 1 and winners[1].bic - chosen.bic < MIN_BIC_DROP:
                break  # two effects gain alike on top of the model: the gain is neither's
            contradicted = chosen.contradicted
            if contradicted:
                break
            k_total += chosen.n_params
            model_effects = list(chosen.model_effects) or [*cur_effects, chosen.effect]
            if steps and not chosen.model_effects:
                # the effects found before held their one-at-a-time fits: refit all
                chosen, model_effects = refit_step(data, chosen, model_effects, cur, noise)
            steps.append(Step(chosen, tuple(cands), tuple(model_effects)))
            cur_ladder, cur_effects, cur = chosen.ladder, model_effects, chosen.comparison
            cur_bic = criterion(cur, noise, k_total)
    where = tuple(localise(base, noise))

    def partial_after(k: int) -> bool:  # the first k effects leave physics they do not explain
        c = steps[k - 1].chosen.comparison
        return bool(structured(c, noise)) and (
            explained_fraction(base, c, noise) < MIN_TOTAL_EXPLAINED or unexplained(c, noise, k))

    partial = bool(steps) and partial_after(len(steps))
    # a later effect that only mops up the misfit of an approximate first one leaves the
    # fewer effects that hold on their own
    kept = next((k for k in range(len(steps) - 1, 0, -1) if not partial_after(k)), 0)
    if partial and kept and not contradicted:
        steps = steps[:kept]
        cur, partial = steps[-1].chosen.comparison, False
    total = explained_fraction(base, cur, noise)
    if contradicted:
        located = localise(cur, noise) or localise(cur)
        done = "".join(f"{st.chosen.effect.name} explains part of the misfit; then "
                       for st in steps)
        reason = (f"{done}no catalogued effect explains the misfit: {contradicted}; not in the "
                  f"catalogue: the error sits in {'; and in '.join(located[:2])}")
        if partial:  # what was found is no diagnosis either (see below)
            steps = []
    elif partial:
        # the effects found explain part of the misfit and leave a structured residual: the
        # physics at work is not in the catalogue (a remounted contact, a heater that sags
        # or a convection that switches can each pass for a temperature coefficient, and
        # several effects together for more of it)
        tried = ", ".join(s.chosen.effect.name for s in steps)
        located = localise(cur, noise) or localise(cur)
        why = (f"would explain only {100 * total:.0f} % of it (needs "
               f"{100 * MIN_TOTAL_EXPLAINED:.0f} % when a structured residual remains)"
               if total < MIN_TOTAL_EXPLAINED else
               f"would explain {100 * total:.0f} % of it but leave a structured residual above "
               f"{math.sqrt(MAX_LEFT_CHI2):g}× the noise" if far_left(cur, noise) else
               f"together would still leave a structured residual of "
               f"{math.sqrt(chi2(cur, noise) / len(cur.points)):.3g}× the noise (after "
               f"{len(steps)} effects, none is allowed)" if len(steps) >= MAX_STEPS else
               f"together would still leave {math.sqrt(chi2(cur, noise) / len(cur.points)):.3g}× "
               f"the noise (more than {math.sqrt(MAX_LEFT_CHI2):g}× after several effects)")
        reason = (f"no catalogued effect explains the misfit: {tried} {why} and leave "
                  f"{'; and '.join(located[:2])}; not in the catalogue")
        steps = []
    else:
        reason = verdict_reason(base, cur, noise, first, steps, skipped)
    effect = steps[0].chosen.effect.name if steps else None
    return Diagnosis(base, model, noise, bic0, tuple(first), effect, reason, where, skipped,
                     time.perf_counter() - t_start, data.source, {}, tuple(steps))
