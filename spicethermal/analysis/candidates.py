"""One step of the diagnosis: every candidate effect fitted on top of the model so far, and
what a later step does beyond that (the rescue of a candidate that its held fit hides, the
joint refit of every effect found, the swap of a first effect that took up the second one's
signature). :func:`~spicethermal.analysis.diagnose.diagnose` runs the steps."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.progress import bar
from ..effects import DEVICE, MEASUREMENT, Effect, spec
from ..fit.backfit import HELD_LADDER_S, refit_effects
from ..fit.budget import TimeLimitError, check_time
from ..fit.effectfit import (
    MAX_BASELINE_ORDER,
    NUMERICAL_ERRORS,
    BundleData,
    EffectFit,
    baseline_ladder,
    needs,
    time_limit,
    transient_spans,
)
from ..fit.fitters import choose_form, fit_effect_forms
from .compare import Comparison
from .consistency import alternatives, device_effect_contradicted, transient_hidden
from .diagnosis import Candidate, Step
from .evidence import evidence
from .residuals import comparison_of
from .verdict import (
    MIN_BIC_DROP,
    MIN_TOTAL_EXPLAINED,
    at_noise,
    can_be_decisive,
    chi2,
    criterion,
    decisive,
    explained_fraction,
    partial_fit,
    passes,
)
from .verdict import improvement as improvement_of

if TYPE_CHECKING:  # pragma: no cover
    from ..core.ladder import Foster

__all__ = ["FITTED_FIRST", "LONGER_LADDER", "REFIT_BUDGET_S", "RESCUE_BUDGET_S", "SWAPPABLE",
           "Scored", "candidates", "joint_refit", "longer_ladder", "not_needed", "quiet_where",
           "refit_step", "rescue", "scored_forms", "swap_dead_end", "swap_first"]

#: Effects whose only signature is in some data sets (those whose name starts so) and their
#: least number of parameters: they are not fitted when those data sets leave no room for a
#: decisive improvement (:func:`~spicethermal.analysis.verdict.can_be_decisive`). An
#: electrical transient acts on the cooling curves' first readings, and through the ladder,
#: which its fit refits on every data set, on the PWM grid: a ladder that absorbed the
#: artefact in a fast stage brings the cooling curves to their noise and leaves the PWM
#: readings, which the artefact spares, far from theirs (seed 53's draw 035 of the random
#: validation set: a transient of −0.95 K beside a latent heat, the PWM readings at 7× their
#: noise after the band).
SIGNATURE = {"phase-change": (("cooling",), 4),
             "electrical-transient": (("cooling", "pwm"), 2),
             "sample-window": (("pwm",), 1)}

#: Effects that a data set of their own measures directly (a TSP's calibration: the sensor
#: alone, no thermal model in it): their gain counts there too
#: (:func:`~spicethermal.analysis.verdict.improvement`).
DIRECT = {"tsp-nonlinearity": ("calibration",)}

#: ... of which these act on the cooling curves beyond their electrical transient.
AFTER_TRANSIENT = ("phase-change",)

#: Cheap fits (the model's readings changed in closed form) come first: a step whose budget runs
#: out within a costly fit has tried them (seed 41's draw 015: a latent heat first, then at the
#: second step a transient's fit and rescue on top of the band spent 30 s of work, and the TSP
#: bow, a fit of one second, found the diagnosis's budget spent).
FITTED_FIRST = ("sample-window", "tsp-nonlinearity")

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

#: Effects whose fit gets this factor of a candidate's budget: a latent-heat band is screened
#: at every node of two ladders and each of its evaluations integrates the cooling curves, so
#: three dense curves leave its joint refit with the ladder no time in the common budget
#: (seed 53's draw 031 of the random validation set: a plateau at the actuator's node 2,
#: explained 73 % at 8 s of work, 99 % at 12 s). A temperature coefficient's forms come one
#: after the other (junction, local, power law, then a subset of layers), each integrated on
#: three dense curves, so the subset came last and got none (seed 53's draw 023: an actuator's
#: inner layers at α = 5.4e-3/K, whose subset fit reaches the noise, α = 5.6e-3/K, at 11 s).
BUDGET_FACTOR = {"phase-change": 1.5, "temperature-coefficient": 1.5}

#: Work (s, see :mod:`~spicethermal.fit.budget`) allowed to the joint refit of every effect found
#: and the ladder after each later step (:func:`refit_step`).
REFIT_BUDGET_S = 8.0

#: ... and to the joint refit of a later candidate that is not decisive on top of the effects
#: found so far (:func:`rescue`).
RESCUE_BUDGET_S = 8.0

#: Device effects that can pass for one another at the first step (each changes how the
#: heat flows through the device): when the first step took one and the second step found
#: another effect, the others that were decisive at the first step are tried in its place
#: (:func:`swap_first`).
SWAPPABLE = ("temperature-coefficient", "phase-change")

#: Device effects fitted on the linear ladder one stage longer too when on the baseline's they
#: lead the first step (fitted last, they fit better than every other candidate) and explain
#: only part of the misfit (:func:`longer_ladder`). A latent heat's misses on the
#: random validation draws were ladders a stage short (seed 41's 029, seed 5's 001: 96.6 and
#: 95 % explained, 99.8 and 99 % on a stage more); a temperature coefficient's retry (every
#: form again) cost the project's own pair of a coefficient and a TSP bow 12 s of its 50 and
#: found nothing better.
LONGER_LADDER = ("phase-change",)

#: One effect's fit with its comparison and criterion (:func:`scored_forms`).
Scored = tuple[EffectFit, Comparison, float]


def candidates(data: BundleData, ladder: Foster, effects: Sequence[Effect],
                names: Sequence[str], before: Comparison, noise: Mapping[str, float],
                say: Callable[[str], None], skipped: dict[str, str],
                budget_s: float = 6.0, quiet: bool = True, step: int = 1) -> list[Candidate]:
    """Every effect of ``names`` fitted on top of ``ladder`` and ``effects`` (each form; the
    default form unless another is decisively better, :func:`choose_form`), each within
    ``budget_s`` of work; failures go to ``skipped``."""
    present = {e.name for e in effects}
    linear = None  # the linear alternatives to the device effects, fitted once
    # the model so far refitted jointly (what a rescue must beat), fitted once when asked
    refitted: list[float] = []

    def held_bic() -> float:
        if not refitted:
            joint = joint_refit(data, ladder, effects, RESCUE_BUDGET_S, before, noise, True)
            refitted.append(criterion(joint[2] if joint else before, noise, 0))
        return refitted[0]

    cands: list[Candidate] = []
    bic_before = criterion(before, noise, 0)
    order = sorted(names, key=lambda n: 2 if n in FITTED_LAST else 1 if n in GLANCED
                   else -1 if n in FITTED_FIRST else 0)
    for name in bar(order, desc=f"diagnose step {step}: fitting effects", quiet=quiet):
        try:
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
            missing = needs(name, data)
            if missing:
                skipped[name] = missing
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
                full_s = budget_s * BUDGET_FACTOR.get(name, 1.0)
                scored = scored_forms(data, ladder, name, effects, noise,
                                      full_s if bar_bic is None else GLANCE_S)
                if bar_bic is not None:
                    if min(x[2] for x in scored) > bar_bic:
                        skipped[name] = f"not needed: {why} (its first form is no better)"
                        continue
                    scored = scored_forms(data, ladder, name, effects, noise, full_s)
                best = scored[choose_form([x[2] for x in scored])]
                linear_ladder = ladder
                if name in LONGER_LADDER and not effects \
                        and partial_fit(before, best[1], noise, 1) \
                        and best[2] < min((c.bic for c in cands), default=math.inf):
                    linear_ladder, scored, best = longer_ladder(data, ladder, name, before,
                                                                noise, full_s, scored, best)
            except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS) as exc:
                skipped[name] = f"fit failed: {exc}"
                continue
            fit, cmp, bic = best
            model_effects: tuple[Effect, ...] = ()
            within = DIRECT.get(name, ())
            if effects and not passes(bic_before - bic, improvement_of(before, cmp, noise, within),
                                      explained_fraction(before, cmp, noise, within)):
                fit, cmp, bic, model_effects = rescue(data, fit, effects, before, cmp, bic, noise,
                                                      held_bic)
            contradicted = tied = ""
            if fit.effect.kind == DEVICE and len(data.cooling) > 1:
                # the alternatives on the linear ladder the effect was fitted on
                if linear_ladder is not ladder:
                    alike = alternatives(data, linear_ladder)
                else:
                    alike = linear = alternatives(data, ladder) if linear is None else linear
                # every form as fitted alone, and the candidate's own fit (a joint refit with the
                # effects found before may have fitted the cooling curves where those did not)
                # (with the effect's own parameters: the ladder's are the alternatives' too)
                own = fit.n_params - 2 * (linear_ladder.order - ladder.order)
                contradicted, tied = device_effect_contradicted(
                    data, linear_ladder, fit.effect, own, [*(x[1] for x in scored), cmp], alike)
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
                                   explained_fraction(before, cmp, noise, within),
                                   time.perf_counter() - t0, contradicted, fit.facts,
                                   improvement_of(before, cmp, noise, within), model_effects,
                                   tied))
        except TimeLimitError:
            if budget_left():
                skipped[name] = "fit failed: time budget exhausted"
                continue
            # the diagnosis's budget ran out within this candidate: the step is weighed on the
            # candidates fitted before it, the others were not tried
            for rest_name in order[order.index(name):]:
                if rest_name not in present:
                    skipped[rest_name] = "not tried: the diagnosis's budget ran out"
            break
    cands.sort(key=lambda c: c.bic)
    return cands


def budget_left() -> bool:
    """Whether the innermost budget (:func:`~spicethermal.fit.budget.time_limit`) has work
    left."""
    try:
        check_time(0.0)
    except TimeLimitError:
        return False
    return True


def scored_forms(data: BundleData, ladder: Foster, name: str, effects: Sequence[Effect],
                 noise: Mapping[str, float], budget_s: float) -> list[Scored]:
    """Every form of ``name`` fitted on top of ``ladder`` and ``effects`` within ``budget_s``
    of work, each with its comparison and criterion."""
    with time_limit(budget_s):
        fits = fit_effect_forms(data, ladder, name, effects)
    scored = []
    for fit in fits:
        cmp = comparison_of(data, fit.ladder, [*effects, fit.effect])
        scored.append((fit, cmp, criterion(cmp, noise, fit.n_params)))
    return scored


def longer_ladder(data: BundleData, ladder: Foster, name: str, before: Comparison,
                  noise: Mapping[str, float], budget_s: float, scored: list[Scored],
                  best: Scored) -> tuple[Foster, list[Scored], Scored]:
    """A device effect fitted on the linear ladder one stage longer too, when on ``ladder``
    its best form (``best`` of ``scored``) explains only part of the misfit
    (:func:`~spicethermal.analysis.verdict.partial_fit`): the baseline's order is chosen
    without the effect, and the stage it could not justify on the linear device can be one
    the device with the effect has (seed 41's draw 029 of the random validation set: a latent
    heat of 0.21 J at the junction of a four-layer diode, whose cooling curves a linear ladder
    of two stages fits best; the band on that ladder explained 96.6 % of the misfit and left
    the PWM readings at 4× their noise, on three stages 99.8 %). The longer ladder is kept
    when its best form has the lower criterion, the two extra ladder parameters counted, and
    explains the misfit of ``before`` (:data:`MIN_TOTAL_EXPLAINED` of it, and no longer only
    part of it, :func:`~spicethermal.analysis.verdict.partial_fit`): a stage more can also let
    a band take up physics it does not hold (an ambient drift late in one curve, 73 % of its
    misfit, at a fourth node). Returns the linear ladder the forms kept were fitted on, those
    forms and the best of them."""
    if ladder.order >= MAX_BASELINE_ORDER:
        return ladder, scored, best
    try:
        longer = baseline_ladder(data, ladder.order + 1)
        if longer.order <= ladder.order:
            return ladder, scored, best
        again = []
        for fit, cmp, _ in scored_forms(data, longer, name, [], noise, budget_s):
            fit = replace(fit, n_params=fit.n_params + 2)
            again.append((fit, cmp, criterion(cmp, noise, fit.n_params)))
    except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS):
        return ladder, scored, best
    other = again[choose_form([x[2] for x in again])]
    if other[2] < best[2] and not partial_fit(before, other[1], noise, 1) \
            and explained_fraction(before, other[1], noise) >= MIN_TOTAL_EXPLAINED:
        return longer, again, other
    return ladder, scored, best


def not_needed(name: str, cands: Sequence[Candidate], bic_before: float,
               noise: Mapping[str, float]) -> str:
    """Why the costly fit of ``name`` is not needed ("" when it is): a decisive candidate
    fitted before it (not contradicted) already brings every data set to its noise, or the
    data sets where ``name`` acts (:data:`SIGNATURE`)."""
    held = [c for c in cands if not c.contradicted and decisive(c, bic_before)]
    done = next((c for c in held if at_noise(c.comparison, noise)), None)
    if done is not None:
        return f"{done.effect.name} brings every data set to its noise"
    where = SIGNATURE[name][0] if name in SIGNATURE else ()
    done = next((c for c in held if where and quiet_where(c.comparison, noise, where)), None)
    if done is not None:
        return (f"{done.effect.name} brings the {' and '.join(where)} data sets (where it acts) "
                f"to their noise")
    return ""


def quiet_where(comparison: Comparison, noise: Mapping[str, float],
                prefixes: tuple[str, ...]) -> bool:
    """Whether the data sets of ``comparison`` whose name starts with one of ``prefixes``
    (there is one at least) are at their noise
    (:func:`~spicethermal.analysis.verdict.at_noise`)."""
    sub = Comparison(tuple(p for p in comparison.points if p.dataset.startswith(prefixes)),
                     comparison.engine)
    return bool(sub.points) and at_noise(sub, noise)


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


def swap_first(data: BundleData, steps: Sequence[Step], first: Sequence[Candidate],
               base: Comparison, noise: Mapping[str, float],
               budget_s: float) -> list[Step] | None:
    """The first two steps again with the first effect swapped for another device effect of
    :data:`SWAPPABLE` that was decisive at the first step too, or ``None``.

    A first effect chosen greedily can take up the signature of the second: a phase change
    took the first milliseconds that a transient proportional to the power corrupts, and was
    chosen over the temperature coefficient that fits far closer once the transient is found
    (seed 23's draw 013 of the random validation set). For each alternative, its own
    first-step candidate, the second step is fitted again on top of it, for the second
    effect only (:func:`candidates`, every form, within ``budget_s`` of work): the
    swap is taken when that is decisive on top of the alternative and the model with both has
    a criterion lower by :data:`MIN_BIC_DROP` than the first two steps'."""
    one, two = steps[0].chosen, steps[1].chosen
    bic_now = criterion(two.comparison, noise, one.n_params + two.n_params)
    for alt, on_alt in _alternatives(steps[0], first, base, noise, (two.effect.name,)):
        def closer(new: Candidate, alt: Candidate = alt) -> bool:
            return bic_now - criterion(new.comparison, noise,
                                       alt.n_params + new.n_params) >= MIN_BIC_DROP

        second = _second_step(data, alt, on_alt, [two.effect.name], noise, budget_s, closer)
        if second is None:
            continue
        new, cands, model_effects = second
        return [Step(alt, steps[0].candidates, tuple(on_alt)),
                Step(new, tuple(cands), tuple(model_effects))]
    return None


def _alternatives(step: Step, first: Sequence[Candidate], base: Comparison,
                  noise: Mapping[str, float], also_not: tuple[str, ...] = ()
                  ) -> Iterator[tuple[Candidate, list[Effect]]]:
    """The other device effects of :data:`SWAPPABLE` (not ``also_not``) that were decisive and
    not contradicted at the first step, each with the model's effects with it in place of the
    step's effect."""
    one = step.chosen
    if one.effect.name not in SWAPPABLE:
        return
    before = [e for e in step.effects if e.name != one.effect.name]
    bic0 = criterion(base, noise, 0)
    for alt in first:
        if alt.effect.name in SWAPPABLE and alt.effect.name not in (one.effect.name, *also_not) \
                and not alt.contradicted and decisive(alt, bic0):
            yield alt, list(alt.model_effects) or [*before, alt.effect]


def _second_step(data: BundleData, alt: Candidate, on_alt: list[Effect], names: Sequence[str],
                 noise: Mapping[str, float], budget_s: float,
                 keep: Callable[[Candidate], bool] = lambda _c: True
                 ) -> tuple[Candidate, list[Candidate], list[Effect]] | None:
    """The best decisive candidate of ``names`` on top of ``alt`` (then refitted with the
    effects before it), the candidates weighed and the model's effects; ``None`` when none is
    or ``keep`` rejects it."""
    cands = candidates(data, alt.ladder, on_alt, names, alt.comparison, noise,
                       lambda _text: None, {}, budget_s, step=2)
    new = next((c for c in cands if decisive(c, alt.bic) and not c.contradicted), None)
    if new is None or not keep(new):
        return None
    model_effects = list(new.model_effects) or [*on_alt, new.effect]
    if not new.model_effects:
        new, model_effects = refit_step(data, new, model_effects, alt.comparison, noise)
    return new, cands, model_effects


def swap_dead_end(data: BundleData, step: Step, first: Sequence[Candidate], base: Comparison,
                  names: Sequence[str], noise: Mapping[str, float],
                  budget_s: float) -> list[Step] | None:
    """The first step again with another device effect of :data:`SWAPPABLE` that was decisive
    at the first step too, and a second step on top of it, or ``None``: for a first effect
    that leaves a residual beyond the noise that no second effect lowers decisively.

    Each device effect can mimic the other: a latent-heat band, with its ladder refitted on
    one more stage, explained 97 % of a strong temperature coefficient on the inner layers and
    left the rest to nothing, where the coefficient (94 %) and an electrical transient bring
    every data set to its noise (temperature-coefficient/inner-layers/strong of the validation
    set). The swap is taken only when the alternative and a second effect (any of ``names``
    but the effect it replaces, :func:`candidates` within ``budget_s`` of work) leave every
    data set at its noise. The replaced effect does not come back second: that pair was
    weighed already, in the other order, and its second effect was not decisive (a 0.49 J
    plateau at a diode's node 1, 99 % of the misfit, got a junction coefficient of 56 % put
    before it: seed 53's draw 012 of the random validation set)."""
    for alt, on_alt in _alternatives(step, first, base, noise):
        taken = {e.name for e in on_alt} | {step.chosen.effect.name}
        second = _second_step(data, alt, on_alt, [n for n in names if n not in taken], noise,
                              budget_s)
        if second is not None and at_noise(second[0].comparison, noise):
            new, cands, model_effects = second
            return [Step(alt, step.candidates, tuple(on_alt)),
                    Step(new, tuple(cands), tuple(model_effects))]
    return None
