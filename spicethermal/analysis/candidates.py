"""One step of the diagnosis: every candidate effect fitted on top of the model so far, and
what a later step does beyond that (the rescue of a candidate that its held fit hides and the
joint refit of every effect found are :mod:`~spicethermal.analysis.refits`'s; the swap of a
first effect that took up the second one's signature is :mod:`~spicethermal.analysis.swaps`'s).
:func:`~spicethermal.analysis.diagnose.diagnose` runs the steps."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError, FitError, SimulationError
from ..core.progress import bar
from ..effects import DEVICE, Effect
from ..fit.backfit import HELD_LADDER_S
from ..fit.budget import TimeLimitError, check_time, left
from ..fit.effectfit import (
    MAX_BASELINE_ORDER,
    NUMERICAL_ERRORS,
    BundleData,
    baseline_ladder,
    needs,
    time_limit,
    transient_spans,
)
from ..fit.fitters import choose_form, fit_effect_forms
from .compare import Comparison
from .consistency import (
    Alternative,
    alternatives,
    device_effect_contradicted,
    transient_hidden,
)
from .diagnosis import Candidate
from .evidence import evidence
from .refits import REFIT_BUDGET_S, RESCUE_BUDGET_S, Scored, converged, joint_refit, rescue
from .residuals import comparison_of
from .verdict import (
    DIRECT,
    MIN_BIC_DROP,
    MIN_TOTAL_EXPLAINED,
    at_noise,
    can_be_decisive,
    criterion,
    decisive,
    explained_fraction,
    partial_fit,
    passes,
)
from .verdict import improvement as improvement_of

if TYPE_CHECKING:  # pragma: no cover
    from ..core.ladder import Foster

__all__ = ["FITTED_FIRST", "LONGER_LADDER", "RESCUE_COST_S", "as_fitted", "candidates",
           "longer_ladder", "not_needed", "quiet_where", "scored_forms"]

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

#: Work (s) a rescue may cost with the joint refit of the effect a step names after it (two
#: joint refits of :data:`RESCUE_BUDGET_S` and their held first passes, and
#: :data:`REFIT_BUDGET_S`; one joint refit less once the step has refitted the effects found
#: without a candidate): with a decisive candidate in hand, a rescue is tried only when
#: the diagnosis's budget has that much left (seed 5's draw 028 of the random validation set: a
#: fixed transient, decisive on top of a power-law coefficient, was left unrefitted and
#: short of the noise when the rescues of a sample window and a TSP bow spent 17 s of work).
RESCUE_COST_S = 2 * (RESCUE_BUDGET_S + HELD_LADDER_S) + REFIT_BUDGET_S

#: Device effects fitted on the linear ladder one stage longer too when on the baseline's they
#: lead the first step (fitted last, they fit better than every other candidate) and explain
#: only part of the misfit (:func:`longer_ladder`). A latent heat's misses on the
#: random validation draws were ladders a stage short (seed 41's 029, seed 5's 001: 96.6 and
#: 95 % explained, 99.8 and 99 % on a stage more); a temperature coefficient's retry (every
#: form again) cost the project's own pair of a coefficient and a TSP bow 12 s of its 50 and
#: found nothing better.
LONGER_LADDER = ("phase-change",)


def candidates(data: BundleData, ladder: Foster, effects: Sequence[Effect],
               names: Sequence[str], before: Comparison, noise: Mapping[str, float],
               say: Callable[[str], None], skipped: dict[str, str],
               budget_s: float = 6.0, quiet: bool = True, step: int = 1) -> list[Candidate]:
    """Every effect of ``names`` fitted on top of ``ladder`` and ``effects`` (each form; the
    default form unless another is decisively better, :func:`choose_form`), each within
    ``budget_s`` of work; failures go to ``skipped``. A later step's candidate that is not
    decisive on its own fit gets its :func:`rescue` after the cheap candidates' fits and before
    the costly ones (:data:`GLANCED`, :data:`FITTED_LAST`), the best first: on top of an
    integrated effect a rescue (a joint refit of every effect) can cost ten plain fits, and two
    of them spent the diagnosis's budget before a transient beside a power-law coefficient was
    tried (seed 5's draw 028 of the random validation set)."""
    present = {e.name for e in effects}
    linear: list[Alternative] | None = None  # the linear alternatives, fitted once
    # the model so far refitted jointly (what a rescue must beat), fitted once when asked
    refitted: list[float] = []

    def held_bic() -> float:
        if not refitted:
            joint = joint_refit(data, ladder, effects, RESCUE_BUDGET_S, before, noise, True)
            refitted.append(criterion(joint[2] if joint else before, noise, 0))
        return refitted[0]

    cands: list[Candidate] = []
    bic_before = criterion(before, noise, 0)

    def settle(name: str, spent_s: float, scored: list[Scored], best: Scored,
               linear_ladder: Foster, model_effects: tuple[Effect, ...],
               refined: bool = False) -> None:
        """The candidate of ``best`` weighed against the linear alternatives and its own
        signature, into ``cands`` (or ``skipped``); when the alternatives refuse a first
        step's device effect, once more with its general form converged (unless
        ``refined``: that was done, :func:`converged`)."""
        nonlocal linear
        fit, cmp, bic = best
        within = DIRECT.get(name, ())
        contradicted = ""
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
            contradicted = device_effect_contradicted(
                data, linear_ladder, fit.effect, own, [*as_fitted(data, effects, scored), cmp],
                alike)
            if contradicted and not effects and not refined:
                again = converged(data, name, scored, noise)
                if again is not None:  # weighed again with the general form converged
                    settle(name, spent_s, again, again[choose_form([x[2] for x in again])],
                           linear_ladder, model_effects, True)
                    return
        if fit.effect.name == "electrical-transient" and not fit.facts.get("no_gain"):
            # the first readings stand out of the model it extends or of its own ladder (a
            # transient proportional to the power passes for a fast stage of the first)
            why = transient_hidden(before, fit.effect, noise) and transient_hidden(
                comparison_of(data, fit.ladder, effects), fit.effect, noise)
            if why:
                skipped[name] = f"not seen: {why}"
                return
        improvement = before.rms_k / cmp.rms_k if cmp.rms_k > 0 else math.inf
        cands.append(Candidate(fit.effect, fit.ladder, cmp, fit.n_params, bic, improvement,
                               evidence(fit, data, before, cmp, noise),
                               explained_fraction(before, cmp, noise, within), spent_s,
                               contradicted, fit.facts,
                               improvement_of(before, cmp, noise, within), model_effects))

    deferred = []  # later-step fits not decisive on their own, rescued after the cheap fits

    def flush() -> bool:
        """The rescues of the deferred fits, the best first (False when the diagnosis's budget
        ran out within one: the rest are not weighed)."""
        jobs = sorted(deferred, key=lambda job: job[3][2])  # by the best form's criterion
        deferred.clear()
        for k, (name, spent_s, scored, best, linear_ladder) in enumerate(jobs):
            named = min((c for c in cands if decisive(c, bic_before) and not c.contradicted),
                        key=lambda c: c.bic, default=None)
            # what a rescue may still cost: the held model's refit (once), its own, the refit
            cost = RESCUE_COST_S - (RESCUE_BUDGET_S + HELD_LADDER_S) * bool(refitted)
            if named is not None and left() < cost:
                skipped[name] = (f"fitted, not decisive on its own; not refitted with the "
                                 f"effects found: {named.effect.name} is, and the diagnosis's "
                                 f"budget is kept for its refit")
                continue
            t0 = time.perf_counter()
            try:
                fit, cmp, bic, model_effects = rescue(data, best[0], effects, before, best[1],
                                                      best[2], noise, held_bic)
                settle(name, spent_s + time.perf_counter() - t0, scored, (fit, cmp, bic),
                       linear_ladder, model_effects)
            except TimeLimitError:  # the diagnosis's budget ran out: the rest are not weighed
                for rest in jobs[k:]:
                    skipped[rest[0]] = ("fitted, not decisive on its own, and not refitted "
                                        "with the effects found: the diagnosis's budget ran out")
                return False
        return True

    order = sorted(names, key=lambda n: 2 if n in FITTED_LAST else 1 if n in GLANCED
                   else -1 if n in FITTED_FIRST else 0)

    def not_tried(name: str) -> None:  # the diagnosis's budget ran out before ``name``
        for rest_name in order[order.index(name):]:
            if rest_name not in present:
                skipped[rest_name] = "not tried: the diagnosis's budget ran out"

    for name in bar(order, desc=f"diagnose step {step}: fitting effects", quiet=quiet):
        # the costly fits come after the rescues of the cheap ones: a cheap rescue can make
        # them unneeded (seed 303's draw 012: a transient's rescue of 0.14 s of work, on top
        # of a coefficient and a sample window, brings every data set to its noise, where the
        # latent heat's fit spends 11 s and the rescue found the budget spent)
        if (name in FITTED_LAST or name in GLANCED) and deferred and not flush():
            not_tried(name)
            break
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
            within, cmp = DIRECT.get(name, ()), best[1]
            job = (name, time.perf_counter() - t0, scored, best, linear_ladder)
            gain = improvement_of(before, cmp, noise, within)
            if effects and not passes(bic_before - best[2], gain,
                                      explained_fraction(before, cmp, noise, within)):
                deferred.append(job)
                continue
            settle(*job, ())
        except TimeLimitError:
            if budget_left():
                skipped[name] = "fit failed: time budget exhausted"
                continue
            # the diagnosis's budget ran out within this candidate: the step is weighed on the
            # candidates fitted before it, the others were not tried
            not_tried(name)
            break
    flush()  # (when the diagnosis's budget runs out within a rescue, what was weighed stands)
    cands.sort(key=lambda c: c.bic)
    return cands


def as_fitted(data: BundleData, effects: Sequence[Effect], scored: list[Scored]
              ) -> list[Comparison]:
    """Each form of ``scored`` as its own fit left it: a fit that ends worse than the model it
    extends stands switched off (``facts["no_gain"]``), and its comparison is the model's, but
    how its dynamics fit the cooling curves is what the linear alternatives are weighed against
    (on top of a sample window fitted without the coefficient, every form of a coefficient
    misread the PWM grid and was switched off, while its local form fitted two curves of a
    diode at χ² 30, below the 89 of a power per curve: seed 5's draw 000 of the random
    validation set). A fit whose comparison fails keeps the switched-off one."""
    out = []
    for fit, cmp, _ in scored:
        tried = fit.facts.get("tried")
        if tried is None:
            out.append(cmp)
            continue
        try:
            out.append(comparison_of(data, tried.ladder, [*effects, tried.effect]))
        except (FitError, SimulationError, DataFormatError, *NUMERICAL_ERRORS):
            out.append(cmp)
    return out


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
