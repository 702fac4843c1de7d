"""Diagnosis: where a model fails, which physical effect is missing, and by how much the error
falls when it is added. The procedure is stated in full once, in docs/diagnosis.md: the
baseline and the noise (:mod:`.noise`); every candidate effect fitted from its plugin's
``guess()`` (:func:`~spicethermal.fit.search.fit_effect`); forward selection by one criterion
and naming rule (:mod:`.rules`), the noise estimated again after each step; the verdict
(:func:`.verdict.verdict`). The work is counted against :data:`.rules.WORK_BUDGET`, never
timed: the same bundle gives the same verdict on every machine and under any load.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from typing import TYPE_CHECKING

from ..core.errors import DataFormatError, FitError
from ..effects.base import CALIBRATION, EffectPlugin
from ..effects.registry import CATALOGUE, own_kinds, plugin
from ..engines.cauer import as_cauer
from ..engines.meter import Meter, metered
from ..fit.joint import Layout, ModelFit, Start, bic, chi2_by_set, fit_baseline, fit_starts
from ..fit.measurement import BundleData, kind_of
from ..fit.search import FormFit, fit_effect, grow, refit, screen_held, settle, unshown, without
from ..model import ThermalModel
from .compare import Comparison, comparison_of
from .diagnosis import (
    AMBIGUOUS,
    NAMED,
    RIVAL,
    UNSHOWN,
    Candidate,
    Diagnosis,
    Step,
    WorkSpent,
    last_model,
)
from .noise import calibration_degree, noise_estimates
from .rules import (
    CLOSED_FORM_COST,
    DECISIVE_BIC,
    MAX_EFFECTS,
    MIN_EXPLAINED,
    NOISE_FLOOR_K,
    REFINE_ROUNDS,
    SCREEN_ROUNDS,
    WORK_BUDGET,
    decisive,
    explained,
    shows,
)
from .verdict import beyond, short, verdict, weighed_fall
from .where import localise

if TYPE_CHECKING:  # pragma: no cover
    from ..io.bundle import Bundle

__all__ = ["diagnose", "fit_with_effects"]


def _baseline(data: BundleData, model: ThermalModel | None) -> tuple[ModelFit, dict]:
    """The baseline and the noise, each estimated from the other in turn."""
    noise = {n: 1.0 for n in data.datasets}
    if data.calibration is not None:
        noise[CALIBRATION] = max(calibration_degree(data.calibration.temp_c,
                                                    data.calibration.read_c)[1], NOISE_FLOOR_K)
    fit = None
    for _ in range(3):
        if model is None:
            fit = fit_baseline(data, noise, lambda m: not short(data, m))
        else:
            slots = tuple((e.plugin, e.form) for e in model.effects)
            ladder = as_cauer(model.ladder)
            fit = fit_starts(data, noise, Layout(slots, ladder.order, hold_ladder=True,
                                                 move=(False,) * len(slots)),
                             [Start(ladder, tuple(dict(e.params) for e in model.effects))])[0]
            if fit is None:
                raise FitError(f"{data.source}: the model does not simulate these data")
        noise = noise_estimates(data, fit.predictions)
    assert fit is not None  # the criterion's χ² under the final noise
    return _under(data, fit, noise), noise


def _under(data: BundleData, fit: ModelFit, noise: dict) -> ModelFit:
    """``fit`` with its χ² under ``noise``."""
    return replace(fit, chi2=chi2_by_set(data, fit.predictions, noise))


def _renoise(data: BundleData, noise: dict, fit: ModelFit) -> tuple[dict, ModelFit, int]:
    """The noise estimated again from a step's model ``fit`` (each data set's the lower), ``fit``
    refitted under it, and that refit's work (docs/diagnosis.md §6); as they are when none fell."""
    fresh = noise_estimates(data, fit.predictions)
    new = {n: min(v, fresh.get(n, v)) for n, v in noise.items()}
    if new == noise:
        return noise, fit, 0
    under = _under(data, fit, new)
    got = refit(data, new, under, REFINE_ROUNDS)
    return new, got, got.work if got is not under else 0


def _candidate(data: BundleData, current: ModelFit, cmp: Comparison, fits: Sequence[ModelFit],
               best: ModelFit, n_points: int, sizes: dict) -> Candidate:
    """The candidate of one effect: its best fit ``best`` weighed against ``current``."""
    b0 = bic(current, n_points)
    after = comparison_of(data, best.predictions)
    name = best.effects[-1].name
    return Candidate(best.effect(name), best, after, b0 - bic(best, n_points),
                     explained(current.chi2, best.chi2, sizes),
                     cmp.rms_k / max(after.rms_k, 1e-300),
                     tuple((m.effect(name).form, b0 - bic(m, n_points)) for m in fits))


def _weigh(data: BundleData, noise: dict, current: ModelFit, cmp: Comparison,
           fitted: dict[str, list[FormFit]], n_points: int, sizes: dict,
           affords: Callable[[int], bool]) -> tuple[list[Candidate], int]:
    """Every effect's candidate, best first: ranked on the model's ladder, the best and every
    one within :data:`.rules.DECISIVE_BIC` of it weighed on ladders grown while the work left
    ``affords(cost)`` one as costly as the last (:func:`~spicethermal.fit.search.grow`, §5)."""
    work = last = 0
    leads = {n: min(forms, key=lambda f: bic(f.fit, n_points)) for n, forms in fitted.items()}
    cands = {n: _candidate(data, current, cmp, [f.fit for f in forms], leads[n].fit,
                           n_points, sizes) for n, forms in fitted.items()}
    if not cands:
        return [], 0
    top = max(c.delta_bic for c in cands.values())
    for name, forms in fitted.items():
        if top - cands[name].delta_bic >= DECISIVE_BIC:
            continue
        lead = leads[name]
        grown, spent, last = grow(data, noise, lead, REFINE_ROUNDS, partial(short, data),
                                  affords, last)
        work += spent
        if grown is not lead.fit:
            fits = [grown if f is lead else f.fit for f in forms]
            cands[name] = _candidate(data, current, cmp, fits, grown, n_points, sizes)
    return sorted(cands.values(), key=lambda c: -c.delta_bic), work


def diagnose(bundle: Bundle, model: ThermalModel | None = None,
             effects: Sequence[str] | None = None,
             progress: Callable[[str], None] | None = None, quiet: bool = True,
             budget: int = WORK_BUDGET) -> Diagnosis:
    """Compare, localise, fit every candidate effect, add the decisive one, and again
    (docs/diagnosis.md states the procedure).

    Parameters
    ----------
    bundle : Bundle
        The measurements.
    model : ThermalModel, optional
        The baseline (default: the linear ladder fitted to every data set). Its effects stay
        in every candidate; the candidates are the registered effects it lacks.
    effects : sequence of str, optional
        Candidate names (default: every registered effect, rivals included).
    progress : callable, optional
        Called with a short text as each candidate is fitted.
    quiet : bool
        No progress bar on stderr.
    budget : int
        The simulator's cost the diagnosis may spend (:data:`.rules.WORK_BUDGET`).

    Returns
    -------
    Diagnosis

    Examples
    --------
    A linear ladder's cooling curves, read with 20 mK of noise: nothing is missing.

    >>> import numpy as np
    >>> from spicethermal.core.ladder import Foster
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> ladder = Foster.from_tau([6.0, 20.0, 50.0, 70.0], [1e-4, 5e-3, 0.4, 30.0])
    >>> t, rng = np.geomspace(1e-4, 100.0, 50), np.random.default_rng(0)
    >>> curves = tuple(CoolingTable(t, p, tj_c=25 + p * ladder.cooling(t)
    ...                             + rng.normal(0, 0.02, t.size), tref_steady_c=25.0)
    ...                for p in (0.1, 0.3))
    >>> d = diagnose(Bundle(ambient_c=25.0, cooling=curves))
    >>> d.verdict.cls, d.effects
    ('none', [])
    """
    t_start = time.perf_counter()
    say = progress or (lambda _text: None)
    data = BundleData.from_bundle(bundle)
    if not data.cooling:
        raise DataFormatError(f"{data.source}: nothing to diagnose without a cooling curve "
                              f"(a ladder is fitted from them)")
    if model is not None and model.reference != bundle.reference:
        raise DataFormatError(f"{data.source}: measured against the {bundle.reference} but the "
                              f"model's reference is {model.reference}")
    with metered() as meter:
        return _search(data, model, bundle.reference, effects, say, budget, meter, t_start)


@dataclass(frozen=True, eq=False)
class _Context:
    """What every step of a diagnosis shares."""

    data: BundleData
    noise: dict
    plugins: list[EffectPlugin]
    skipped: dict[str, str]
    say: Callable[[str], None]
    meter: Meter
    budget: int

    def affords(self, cost: int = 0) -> bool:
        """Whether the budget left exceeds ``cost``."""
        return self.meter.cost + cost < self.budget


@dataclass
class _Path:
    """One forward selection: its steps, the data its last model was settled on, the first
    step's candidates, the work (model evaluations), why the budget stopped it, the further
    candidate it refused (None: none) with its ``weighed_fall``, what a step left unweighed."""

    data: BundleData
    noise: dict
    steps: list[Step] = field(default_factory=list)
    first: tuple[Candidate, ...] = ()
    work: int = 0
    stopped: str = ""
    refused: Candidate | None = None
    weighed: float = 0.0
    unweighed: str = ""


def _search(data: BundleData, model: ThermalModel | None, reference: str,
            effects: Sequence[str] | None, say: Callable[[str], None], budget: int,
            meter: Meter, t_start: float) -> Diagnosis:
    """The procedure of docs/diagnosis.md, the simulator's work counted by ``meter``."""
    say("baseline ladder and noise")
    base, noise = _baseline(data, model)
    if model is None:
        model = ThermalModel(base.foster, (), reference,
                             {"tool": "spicethermal diagnose", "baseline": "linear ladder"})
    n_points = sum(data.sizes().values())
    base_cmp = comparison_of(data, base.predictions)
    names = list(effects) if effects is not None else list(CATALOGUE)
    plugins = [plugin(n) for n in names]
    skipped = {p.name: "already in the model" for p in plugins if base.effect(p.name)}
    skipped |= {p.name: f"no data set that can show it ({' or '.join(sorted(p.traits.shown_by))})"
                for p in plugins if p.name not in skipped and not p.traits.shown_by & data.kinds}
    ctx = _Context(data, noise, plugins, skipped, say, meter, budget)
    path = _forward(ctx, base, base_cmp)
    work, revised, stopped, unweighed = base.work + path.work, "", path.stopped, path.unweighed
    final = last_model(path.steps, base)
    alt = next((i for i, c in enumerate(path.first) if i and c.catalogued
                and decisive(0.0, -c.delta_bic, c.explained)), None)
    if path.steps and path.steps[0].chosen.catalogued and not stopped \
            and short(data, final) and alt is not None and ctx.affords():
        # the best effect alone may be the one that leaves no second effect a way to the
        # noise (its form, or the ladder, took part of the other's misfit): the next best
        # effect first, when its steps end with a lower criterion
        other = _forward(ctx, base, base_cmp, path.first, alt)
        work += other.work
        end = last_model(other.steps, base)
        common = {n: min(v, other.noise[n]) for n, v in path.noise.items()}
        gain = bic(_under(data, final, common), n_points) \
            - bic(_under(data, end, common), n_points)
        lead, name = path.first[0], path.first[alt].name
        if other.stopped:
            stopped = f"{other.stopped} (with {name} added first instead of {lead.name})"
        elif gain >= DECISIVE_BIC:
            revised = (f"{name} is added first although {lead.name} alone lowers the "
                       f"criterion more (by {lead.delta_bic - path.first[alt].delta_bic:.1f}): "
                       f"after {lead.name} no further effect brings every data set to its "
                       f"noise, and the criterion ends {gain:.1f} higher")
            path, unweighed = other, other.unweighed
    further = path.refused
    refused = (f"{further.name} would lower the criterion by a further {further.delta_bic:.1f} "
               f"and remove {100 * max(further.explained, 0):.0f} % of the misfit left, but it "
               "leaves a structured residual too, and weighed under that residual's correlation "
               f"by {path.weighed:.1f} only: not named, since any flexible effect takes part of "
               f"what the approximate form of {path.steps[-1].chosen.name} leaves"
               ) if further else ""
    note = "; ".join(t for t in (refused, revised, stopped, unweighed) if t)
    noise = path.noise  # the last estimate: the verdict and every model's χ² are under it
    if noise != ctx.noise:
        base = _under(data, base, noise)
        path.steps[:] = [replace(s, model=_under(data, s.model, noise)) for s in path.steps]
    result = verdict(path.data, base, path.steps, noise, note, bool(stopped))
    where = tuple(localise(base_cmp, noise, beyond(data, base)))
    return Diagnosis(data.source, noise, base_cmp, base, model, tuple(path.steps), result,
                     path.first, skipped, n_points, work, time.perf_counter() - t_start,
                     where, WorkSpent(meter.solves, budget, stopped or unweighed, meter.steps,
                               meter.cost),
                     further, path.weighed, ctx.noise)


def _forward(ctx: _Context, base: ModelFit, base_cmp: Comparison,
             first: tuple[Candidate, ...] = (), pick: int = 0) -> _Path:
    """Forward selection from ``base`` (docs/diagnosis.md §6); given the first
    step's candidates, weighed already, the first step adds the one of rank ``pick``."""
    data, noise, sizes = ctx.data, ctx.noise, ctx.data.sizes()
    n_points = sum(sizes.values())
    path = _Path(data, dict(noise), first=first)
    steps = path.steps
    current, cmp = base, base_cmp
    while sum(s.status != RIVAL for s in steps) < MAX_EFFECTS and short(data, current):
        k = len(steps) + 1
        spent_before, held = bool(steps) and not ctx.affords(), dict[str, list[FormFit]]()
        cut, i, unfitted = "", pick, list[str]()
        if not steps and path.first:
            cands = list(path.first)
        else:
            fitted = {}
            # closed-form effects first, then the simulated ones, after the first step each in
            # its ranking (each effect's gain alone): a spent budget leaves the least favoured
            rank = {c.name: j for j, c in enumerate(path.first)}
            for p in sorted(ctx.plugins, key=lambda p: (p.traits.cost > CLOSED_FORM_COST,
                                                        rank.get(p.name, len(rank)))):
                if p.name in ctx.skipped or current.effect(p.name):
                    continue
                if not ctx.affords():
                    unfitted.append(p.name)
                    continue
                ctx.say(f"step {k}: {p.name}")
                forms, whole = fit_effect(data, noise, current, p, SCREEN_ROUNDS,
                                          REFINE_ROUNDS, left=ctx.affords)
                path.work += sum(f.fit.work for f in forms)
                if not whole:  # the budget was spent between two of its forms
                    unfitted.append(p.name)
                elif forms:
                    fitted[p.name] = forms
            cut = "" if not unfitted else f"the work budget (a cost of {ctx.budget:,}) was " + (
                f"spent after step {k - 1}" if spent_before else f"spent in step {k} before "
                f"{', '.join(unfitted)} {'was' if len(unfitted) == 1 else 'were'} fitted")
            if steps and unfitted:  # what the step can still weigh: screens, held
                held = screen_held(data, noise, current, map(plugin, unfitted), SCREEN_ROUNDS)
                path.work += sum(f.fit.work for forms in held.values() for f in forms)
                fitted.update(held)
                cut += f" ({', '.join(held)} screened on the model held)" if held else ""
            if not fitted and cut:
                path.stopped = cut
                break
            ctx.say(f"step {k}: the best on longer ladders")
            cands, spent = _weigh(data, noise, current, cmp, fitted, n_points, sizes,
                                  ctx.affords)
            path.work += spent
            if cut and cands and cands[0].name in held and short(data, cands[0].fit):
                # the model held took part of its misfit into the ladder and the effects
                # before it: the best screened one is refitted jointly, once
                lead, fits = cands[0], held[cands[0].name]
                joint = refit(data, noise, lead.fit, REFINE_ROUNDS)
                if joint is not lead.fit:
                    path.work += joint.work
                    cands[0] = _candidate(data, current, cmp, [joint if f.fit is lead.fit
                                                               else f.fit for f in fits],
                                          joint, n_points, sizes)
                    cands.sort(key=lambda c: -c.delta_bic)
            i = 0
            if not steps:
                path.first = tuple(cands)
        # the best, when decisive: after a cut only at the noise (the candidates not weighed
        # could at most tie with it), after a catalogued effect only when its fall stands out
        # of the correlated misfit it leaves; else the best that data only it changes show
        own = next((c for c in cands if _own(c, data, current)), None)
        chosen, weighed = (cands[i] if cands else own), None
        if chosen is not own and (not decisive(0.0, -chosen.delta_bic, chosen.explained)
                                  or cut and short(data, chosen.fit)):
            chosen = own
        elif chosen is not own and chosen.catalogued and short(data, chosen.fit) \
                and any(s.status != RIVAL for s in steps):
            weighed = weighed_fall(data, current, chosen.fit, noise)
            chosen = chosen if weighed >= DECISIVE_BIC else own
        if chosen is None:
            if weighed is not None:
                path.refused, path.weighed = cands[i], weighed
            path.stopped = cut
            break
        loose = short(data, chosen.fit)  # at the noise, it ties only with one at the noise
        if cut:
            path.unweighed = f"{cut}: " + (
                f"{chosen.name} is shown by data none of them changes" if loose else
                f"{'it' if len(unfitted) == 1 else 'they'} could at most tie with "
                f"{chosen.name}, which brings every data set to its noise")
        why = _unshown(chosen, data, current, noise) if chosen.catalogued else ""
        if why and any(s.status != RIVAL for s in steps):
            break  # a further effect the data do not show is no evidence of its physics
        # within the margin either side (from the next best first effect, the best is above)
        tied = tuple(c for c in cands if c is not chosen
                     and abs(chosen.delta_bic - c.delta_bic) < DECISIVE_BIC
                     and decisive(0.0, -c.delta_bic, c.explained)
                     and not _refuted(c, data, current) and (loose or not short(data, c.fit))
                     and not unshown(data, c.fit, c.name, noise))
        status = _status(chosen, tied, why)
        if chosen.name in held:  # screened or refitted once, at the noise: not settled again
            current, cmp = chosen.fit, comparison_of(data, chosen.fit.predictions)
            steps.append(Step(chosen, tuple(cands), status, current, cmp, tied, (), why, noise))
            continue
        # the model the next step starts from is converged: what a further refit would still
        # gain is then no candidate's
        current = refit(data, noise, chosen.fit, REFINE_ROUNDS)
        path.work += current.work if current is not chosen.fit else 0
        dropped = []
        for e in [e for e in current.effects if e.name != chosen.name]:
            try:
                lighter = without(data, noise, current, e.name, REFINE_ROUNDS)
            except (ValueError, FitError):
                continue
            path.work += lighter.work
            if bic(lighter, n_points) - bic(current, n_points) < DECISIVE_BIC:
                current, _ = lighter, dropped.append(e.name)
        # with its PWM readings exact, and the next step's fits from there
        data, settled = settle(data, noise, current, REFINE_ROUNDS)
        path.work += settled.work if settled is not current else 0
        current, path.data = settled, data
        noise, current, spent = _renoise(data, noise, current)
        path.work, path.noise = path.work + spent, noise
        cmp = comparison_of(data, current.predictions)
        steps.append(Step(chosen, tuple(cands), status, current, cmp, tied, tuple(dropped),
                          why, noise))
    return path


def _status(chosen: Candidate, tied: Sequence[Candidate], why: str) -> str:
    """A step's status (:class:`~.diagnosis.Step`); ``why``: :func:`_unshown`'s reason or ""."""
    if not chosen.catalogued:
        return RIVAL
    named_too = any(t.catalogued for t in tied)
    return AMBIGUOUS if named_too else UNSHOWN if why else NAMED


def _unshown(chosen: Candidate, data: BundleData, before: ModelFit, noise: dict) -> str:
    """Why the data do not show the chosen effect (docs/diagnosis.md §7), or "": the data sets
    it needs are missing or do not show it themselves, or its plugin's ``unshown`` says so."""
    needs = chosen.effect.plugin.traits.needs
    what = " and ".join(sorted(needs))
    if not needs <= data.kinds:
        return f"without {what} data the bundle cannot tell it from a device effect"
    if _refuted(chosen, data, before):
        return (f"the {what} data do not show it themselves: the bundle cannot tell it from "
                f"a device effect")
    return unshown(data, chosen.fit, chosen.name, noise)


def _refuted(cand: Candidate, data: BundleData, before: ModelFit) -> bool:
    """Whether the data ``cand``'s effect needs (``traits.needs``) are in the bundle and do not
    show it, on their own (a calibration's decisive bow) and in the model (§7, ``shows``)."""
    needs, cal = cand.effect.plugin.traits.needs, data.calibration
    sets = [n for n in data.datasets if kind_of(n) in needs]
    bow = CALIBRATION not in sets or calibration_degree(cal.temp_c, cal.read_c)[2] >= DECISIVE_BIC
    return bool(needs) and needs <= data.kinds and not (bow and shows(before.chi2,
                                                                      cand.fit.chi2, sets))


def _own(cand: Candidate, data: BundleData, before: ModelFit) -> bool:
    """Whether the data ``cand``'s effect needs are data only it changes (``own_kinds``) and
    show it (not :func:`_refuted`) as decisively as §4 asks (docs/diagnosis.md §6)."""
    needs = cand.effect.plugin.traits.needs
    mine = [{n: chi2[n] for n in data.datasets if kind_of(n) in needs}
            for chi2 in (before.chi2, cand.fit.chi2)]
    return bool(mine[0]) and own_kinds(cand.name) == needs and cand.delta_bic >= DECISIVE_BIC \
        and not _refuted(cand, data, before) and explained(*mine, data.sizes()) >= MIN_EXPLAINED


def fit_with_effects(bundle: Bundle, names: Sequence[str],
                     provenance: dict | None = None) -> ThermalModel:
    """The linear ladder and the named effects fitted jointly to every data set of
    ``bundle``, as the diagnosis fits them: the baseline and its noise, then each effect in
    turn (every form; the one with the lowest criterion kept, its ladder grown as the
    diagnosis grows it, and settles it: its PWM readings exact) with the ladder and the
    effects before it refitted.

    Parameters
    ----------
    bundle : Bundle
    names : sequence of str
        Registered effects, in the order they are added.
    provenance : dict, optional
        Written into the model.

    Returns
    -------
    ThermalModel
    """
    data = BundleData.from_bundle(bundle)
    if not data.cooling:
        raise DataFormatError(f"{data.source}: effects are fitted with a ladder, which needs a "
                              f"cooling curve")
    current, noise = _baseline(data, None)
    n_points = sum(data.sizes().values())
    for name in dict.fromkeys(names):
        fits, _ = fit_effect(data, noise, current, plugin(name), SCREEN_ROUNDS, REFINE_ROUNDS)
        if not fits:
            raise FitError(f"{data.source}: {name} cannot be fitted to these data (none of its "
                           f"data sets, {', '.join(sorted(plugin(name).traits.shown_by))}, "
                           f"shows it)")
        best = min(fits, key=lambda f: bic(f.fit, n_points))
        current = grow(data, noise, best, REFINE_ROUNDS, partial(short, data))[0]
        data, current = settle(data, noise, current, REFINE_ROUNDS)
        noise, current, _ = _renoise(data, noise, current)
    return ThermalModel(current.foster, current.effects, bundle.reference,
                        {**(provenance or {}), "fit": {
                            "effects": list(dict.fromkeys(names)),
                            "chi2": {k: round(v, 3) for k, v in current.chi2.items()},
                            "noise_k": {k: round(v, 6) for k, v in noise.items()}}})
