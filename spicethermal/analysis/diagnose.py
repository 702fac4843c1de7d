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
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from ..core.errors import DataFormatError, FitError, SimulationError
from ..effects import CATALOGUE
from ..fit.budget import TimeLimitError, mark, reached
from ..fit.effectfit import (
    NUMERICAL_ERRORS,
    BundleData,
    baseline_ladder,
    time_limit,
)
from ..fit.fitters import fit_with_effects
from ..fit.tcforward import own_cache
from ..model import ThermalModel
from ..report.diagnosis import write_report
from .candidates import candidates
from .diagnosis import DIAGNOSIS_FORMAT, Candidate, Diagnosis, Step
from .evidence import evidence
from .refits import refit_step
from .regime import regime_switch
from .residuals import comparison_of, fmt_against, localise, noise_estimates
from .swaps import swap_dead_end, swap_first
from .table2 import TableAnalysis, analyse_table, diagnose_table
from .verdict import (
    MAX_LEFT_CHI2,
    MAX_STEPS,
    MIN_BIC_DROP,
    MIN_EXPLAINED,
    MIN_IMPROVEMENT,
    MIN_TOTAL_EXPLAINED,
    at_noise,
    chi2,
    criterion,
    decisive,
    early_excess,
    explained_fraction,
    far_left,
    partial_fit,
    runs_z,
    structured,
    verdict_reason,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..io.bundle import Bundle

__all__ = ["DIAGNOSIS_FORMAT", "MIN_EXPLAINED", "MIN_IMPROVEMENT", "Candidate", "Diagnosis",
           "Step", "TableAnalysis", "analyse_table", "candidates", "comparison_of", "diagnose",
           "diagnose_table", "evidence", "explained_fraction", "fit_with_effects", "localise",
           "noise_estimates", "runs_z", "structured", "write_report"]

#: Time budget (s of work, see :func:`~spicethermal.fit.effectfit.time_limit`) of one
#: candidate's fit at the first step; a fit past it keeps its
#: best point so far (a fit that cannot start fails).
CANDIDATE_BUDGET_S = 8.0
#: ... and at later steps (their forward models carry the effects added so far; a second
#: effect is often the one that needs an integration).
LATER_BUDGET_S = 8.0
#: Work (s, see :mod:`~spicethermal.fit.budget`) allowed to all the steps of one diagnosis together
#: (the candidates' own budgets stop at it too): no bundle keeps the steps busy for longer,
#: whatever its fits do. The change-of-regime check after them has its own budget (four fits
#: of at most :data:`~spicethermal.analysis.regime.REGIME_BUDGET_S` each).
DIAGNOSIS_BUDGET_S = 50.0


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
    contradicted = ""
    # one budget for every step: a step that finds its time spent stops the diagnosis
    end = mark(DIAGNOSIS_BUDGET_S)
    with time_limit(DIAGNOSIS_BUDGET_S):
        # the first step also when the first readings stand out of a baseline otherwise at
        # its noise (an electrical transient over a few readings)
        while len(steps) < MAX_STEPS and not reached(end) and (
                not at_noise(cur, noise) or
                not steps and early_excess(cur, noise) >= MIN_BIC_DROP):
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
            if not winners and len(steps) == 1:
                # the first effect may have mimicked the other device effect
                swap = _unless_out_of_time(swap_dead_end, data, steps[0], first, base, names,
                                           noise, LATER_BUDGET_S)
                if swap is None:
                    break
                steps = swap
            else:
                if not winners:
                    break
                chosen = winners[0]
                if steps and len(winners) > 1 and winners[1].bic - chosen.bic < MIN_BIC_DROP:
                    break  # two effects gain alike on top of the model: the gain is neither's
                contradicted = chosen.contradicted
                if contradicted:
                    break
                model_effects = list(chosen.model_effects) or [*cur_effects, chosen.effect]
                if steps and not chosen.model_effects:
                    # the effects found before held their one-at-a-time fits: refit all
                    chosen, model_effects = refit_step(data, chosen, model_effects, cur, noise)
                steps.append(Step(chosen, tuple(cands), tuple(model_effects)))
                if len(steps) == 2:
                    steps = _unless_out_of_time(swap_first, data, steps, first, base, noise,
                                                LATER_BUDGET_S) or steps
            # the model so far is the last step's
            last = steps[-1]
            cur_ladder, cur_effects, cur = last.chosen.ladder, list(last.effects), \
                last.chosen.comparison
            cur_bic = criterion(cur, noise, sum(st.chosen.n_params for st in steps))
    # a coefficient named first may be a change of regime (:mod:`.regime`), weighed once the
    # steps end (a missing effect's misfit is a step's to take up too: seed 23's draw 013 of
    # the random validation set, a real coefficient beside a power transient) and on its own
    # budget (REGIME_BUDGET_S per start), which a diagnosis that spent its steps' budget still
    # has (seed 101's draw 015, a convection switch at 33.2 °C)
    if steps and not contradicted:
        contradicted = regime_switch(data, steps, noise)
        if contradicted:
            steps, cur = [], base
    where = tuple(localise(base, noise))

    def partial_after(k: int) -> bool:  # the first k effects leave physics they do not explain
        return partial_fit(base, steps[k - 1].chosen.comparison, noise, k)

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
        why = (f"would explain only {fmt_against(100 * total, 100 * MIN_TOTAL_EXPLAINED, 2)} % "
               f"of it (needs "
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


def _unless_out_of_time(swap: Callable[..., list[Step] | None], *args: Any
                        ) -> list[Step] | None:
    """``swap(*args)``, or ``None`` when the diagnosis's budget runs out within it (the steps
    found so far stand)."""
    try:
        return swap(*args)
    except TimeLimitError:
        return None
